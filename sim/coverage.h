// Cleaning coverage against the simulator's truth (issue 13): how much of the
// floor the robot could reach its body swept. Used by the accuracy tools
// (tests/tools/clean_eval.cc) and by irslam-sim run --baseline bounce.
#ifndef IRSLAM_SIM_COVERAGE_H_
#define IRSLAM_SIM_COVERAGE_H_

#include <utility>
#include <vector>

#include "sim/world.h"
#include "types/geometry.h"

namespace irslam::sim {

// The reachable floor: the free
// floor (room minus furniture) the robot's body disc can reach from the start,
// rasterised at cell_m (world frame); covered: swept by the true body disc
// (radius_m) at the truth's poses with t0 <= t <= t1. curve (optional): the
// covered fraction every sample_s from t0.
struct CoverageScore {
  double reachable_m2 = 0;
  double covered_m2 = 0;
  double fraction = 0;
  double path_m = 0;  // true distance driven between t0 and t1
};
CoverageScore ScoreCoverage(const World& world, double radius_m, const std::vector<TimedPose>& truth,
                            double t0, double t1, double cell_m = 0.02,
                            std::vector<std::pair<double, double>>* curve = nullptr, double sample_s = 10);

}  // namespace irslam::sim

#endif  // IRSLAM_SIM_COVERAGE_H_
