// Grid path planning for the go-to behaviour: A* (8-connected) on an occupancy
// grid made from the mapped lines and any extra obstacle points (IR readings),
// inflated by the robot radius plus a clearance. Pure.
#ifndef IRSLAM_CONTROL_PATH_PLANNER_H_
#define IRSLAM_CONTROL_PATH_PLANNER_H_

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "types/options.h"

namespace irslam::control {

struct PlannerOptions {
  double resolution_m = 0.05;
  double inflation_m = 0.25;  // robot radius + clearance
  double hard_m = 0.19;       // never closer than this (robot radius + a little): near the
                              // start, cells between hard_m and inflation_m may be crossed
                              // to get out of a tight spot, and cells within hard_m only
                              // moving away from the obstacle
  double margin_m = 1.0;      // grid extends this far beyond the obstacles
};
// The planner's configurable keys (resolution and margin; the go-to sets the
// inflation and hard distance from the robot radius and its clearances, so they
// are no keys). Section [exploration], as planner_*.
options::Table<PlannerOptions> PlannerKeys();

struct Obstacle {
  Eigen::Vector2d a, b;  // a segment (a == b: a point)
};

// The point of the obstacle nearest p.
Eigen::Vector2d ClosestPoint(const Obstacle& o, const Eigen::Vector2d& p);

// A path from start to goal (both included), simplified to its corners; nullopt if
// the goal cannot be reached. A start inside the inflation, even within hard_m,
// is allowed (the robot may stand closer to a wall than the clearance, or where
// a mapped side, extended past its seen ends, is assumed to go on).
std::optional<std::vector<Eigen::Vector2d>> PlanPath(const std::vector<Obstacle>& obstacles,
                                                     const Eigen::Vector2d& start,
                                                     const Eigen::Vector2d& goal,
                                                     const PlannerOptions& options);

// Whether a path (from the robot's position) still keeps at least `clearance_m`
// from every obstacle, beyond its first `skip_m` (where the robot stands now).
bool PathClear(const std::vector<Obstacle>& obstacles, const std::vector<Eigen::Vector2d>& path,
               double clearance_m, double skip_m);

// The length of a polyline.
double PathLength(const std::vector<Eigen::Vector2d>& path);

}  // namespace irslam::control

#endif  // IRSLAM_CONTROL_PATH_PLANNER_H_
