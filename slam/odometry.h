// Wheel odometry for a differential-drive robot: cumulative encoder counts in,
// wheel travel and pose increments out. Also the motion noise model used to grow
// the pose covariance (noise growing with distance travelled and angle turned),
// and the odometry's systematic parameters (OdometryCalibration): the scale
// factors of the two wheel radii and of the track width, estimated in the EKF
// state as the robot drives (simultaneous localisation and odometry
// self-calibration: A. Martinelli, N. Tomatis, R. Siegwart, "Simultaneous
// localization and odometry self calibration for mobile robot", Autonomous Robots
// 22(1), 2007 and IEEE T-RO 2007; R. Kuemmerle, G. Grisetti, W. Burgard,
// "Simultaneous calibration, localization, and mapping", IROS 2011).
#ifndef IRSLAM_SLAM_ODOMETRY_H_
#define IRSLAM_SLAM_ODOMETRY_H_

#include <Eigen/Core>
#include <optional>

#include "types/geometry.h"
#include "types/options.h"
#include "types/robot.h"
#include "types/signals.h"

namespace irslam::slam {

// The random part of the odometry's error; its systematic part (wheel radii,
// track width) is estimated in the EKF (CalibrationOptions). A quarter of the
// values used before 2026-12-07 (4e-4, 1e-3, 2e-4): with those, a wall line's
// noisy angle turned the heading by 1-2 degrees at a time and the map as a whole
// with it (docs/error-budget.md, "Trusting the odometry more").
struct MotionNoise {
  double var_per_m = 1e-4;            // m^2 of position variance per metre travelled
  double var_theta_per_rad = 2.5e-4;  // rad^2 of heading variance per radian turned
  double var_theta_per_m = 5e-5;      // rad^2 of heading variance per metre travelled
  // > 0: the three variances are multiplied by the running mean, over this many
  // matches, of the matches' normalised innovation squared over its 2 degrees
  // of freedom, clamped to 1 .. adapt_max_scale (covariance matching: A. H.
  // Mohamed, K. P. Schwarz, "Adaptive Kalman filtering for INS/GPS", Journal of
  // Geodesy 73, 1999): a robot that slips more than the noise above says gets
  // the noise it shows, a nominal one keeps it. 0 (default): fixed.
  int adapt_window = 0;
  double adapt_max_scale = 16;
};

// A pose increment in the robot frame at the start of the increment.
struct Motion {
  double ds = 0;      // distance travelled by the centre
  double dtheta = 0;  // rotation
};

// The wheels' travel over one encoder interval, by the nominal geometry.
struct WheelMotion {
  double dl = 0, dr = 0;
};

// The odometry's systematic parameters, as scale factors of the nominal geometry:
// true left/right wheel radius = nominal * left/right, true track width = nominal
// * base. Three, because that is what differs on a real robot (UMBmark's E_d and
// E_b: the two tyres wear and compress differently, the contact patches set the
// effective track) and all three are observable from line features: the mean of
// left and right scales the distance (ranges to walls met at an angle), their
// difference bends straight runs, and (left + right) / base scales turns
// (the angles of walls seen before and after a corner).
struct OdometryCalibration {
  double left = 1, right = 1, base = 1;
  double ratio() const { return right / left; }  // right / left wheel radius
};

// Config section [slam.calibration].
struct CalibrationOptions {
  bool enabled = true;            // false: the nominal geometry, fixed (the parameters are not estimated)
  double prior_sigma_wheel = 0.01;  // 1-sigma of each wheel radius scale at the start (no saved value)
  double prior_sigma_base = 0.03;   // 1-sigma of the track width scale at the start
  double resume_sigma = 0.002;    // added (in quadrature) to a saved value's sigma when a mission starts from it
  double random_walk_per_m = 1e-7;  // variance of each scale added per metre travelled (floor changes, wear)
  double min_sigma = 2e-4;        // the parameters' sigma never falls below this (the filter stays open)
};
options::Table<CalibrationOptions> CalibrationKeys();

// Config section [slam] (odometry noise keys).
options::Table<MotionNoise> MotionNoiseKeys();

class Odometry {
 public:
  explicit Odometry(RobotGeometry geometry) : geometry_(geometry) {}

  // Returns the wheels' nominal travel since the previous ticks (nullopt for the
  // first sample); the dead-reckoned pose advances by the motion calibrated with c.
  std::optional<WheelMotion> Add(const WheelTicks& ticks, const OdometryCalibration& c = {});
  // The pose increment of wheel travel w under calibration c.
  Motion ToMotion(const WheelMotion& w, const OdometryCalibration& c = {}) const {
    return Calibrated(w, geometry_.wheel_base_m, c);
  }
  // Dead-reckoned pose in the odometry frame (starts at the origin).
  const Pose2& pose() const { return pose_; }
  double distance_m() const { return distance_m_; }
  double last_t() const { return last_ ? last_->t : 0.0; }

  // Applies a motion to a pose (midpoint integration).
  static Pose2 Apply(const Pose2& p, const Motion& m);
  // Jacobians of Apply with respect to the pose (3x3) and process noise Q for m.
  static Eigen::Matrix3d JacobianPose(const Pose2& p, const Motion& m);
  static Eigen::Matrix3d ProcessNoise(const Pose2& p, const Motion& m, const MotionNoise& n);
  // Jacobian of Apply with respect to the motion (ds, dtheta) (3x2).
  static Eigen::Matrix<double, 3, 2> JacobianMotion(const Pose2& p, const Motion& m);
  // The motion of wheel travel w with track width wheel_base_m under calibration c:
  // ds = (kl dl + kr dr) / 2, dtheta = (kr dr - kl dl) / (kb b); and its Jacobian
  // with respect to (kl, kr, kb) (2x3).
  static Motion Calibrated(const WheelMotion& w, double wheel_base_m, const OdometryCalibration& c);
  static Eigen::Matrix<double, 2, 3> JacobianCalibration(const WheelMotion& w, double wheel_base_m,
                                                         const OdometryCalibration& c);

 private:
  RobotGeometry geometry_;
  std::optional<WheelTicks> last_;
  Pose2 pose_;
  double distance_m_ = 0;
};

}  // namespace irslam::slam

#endif  // IRSLAM_SLAM_ODOMETRY_H_
