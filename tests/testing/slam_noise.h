// The SLAM's noise options before 2026-12-07 (test helper): the odometry
// self-calibration off, the eq. (7) covariance as it is, and the motion noise
// then (docs/error-budget.md, "Trusting the odometry more"). Mechanism tests
// whose scenarios were found with them set them, as they set the eq. (8)
// threshold they were found with: with today's the defects they show do not
// form where they look for them. The values are those of that day, not a
// multiple of today's defaults, so that a later change of the defaults does
// not move these scenarios too.
#ifndef IRSLAM_TESTS_TESTING_SLAM_NOISE_H_
#define IRSLAM_TESTS_TESTING_SLAM_NOISE_H_

#include "slam/slam.h"

namespace irslam::testing {

inline void UseSlamNoiseBefore20261207(slam::SlamOptions* o) {
  o->calibration.enabled = false;
  o->association.measurement_cov_scale = 1;
  o->motion_noise.var_per_m = 4e-4;
  o->motion_noise.var_theta_per_rad = 1e-3;
  o->motion_noise.var_theta_per_m = 2e-4;
}

}  // namespace irslam::testing

#endif  // IRSLAM_TESTS_TESTING_SLAM_NOISE_H_
