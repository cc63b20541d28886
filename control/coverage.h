// Coverage planning for cleaning the modelled room: the free floor (the room
// minus its furniture and remembered contacts, inflated by the robot radius plus
// a clearance: the places the robot's centre may be) is split into cells by the
// boustrophedon cellular decomposition (H. Choset, "Coverage of known spaces:
// the boustrophedon cellular decomposition", Autonomous Robots 9, 2000). The map
// frame's obstacles are axis-aligned boxes, so the decomposition is a sweep over
// the boxes' x-edges: between two consecutive edges (a slab) the free floor is a
// set of y-intervals, and a cell goes on from one slab to the next while the
// connectivity does not change (one interval overlapping exactly one). Each cell
// is swept by lanes parallel to the y walls, lane spacing = cleaning width -
// overlap, after an edge pass round the cell (its lower and upper boundaries are
// walls or furniture, so are its first and last lanes where a box ends it). The
// cells are ordered into a short tour (greedy nearest neighbour, then 2-opt) and
// each is entered from the corner nearest where the last one ended. Pure: boxes
// in, cells and routes out (map frame).
#ifndef IRSLAM_CONTROL_COVERAGE_H_
#define IRSLAM_CONTROL_COVERAGE_H_

#include <Eigen/Core>
#include <algorithm>
#include <optional>
#include <vector>

#include "control/room_model.h"
#include "types/options.h"

namespace irslam::control {

// Config section [cleaning]: planning and driving the lanes.
struct CleaningOptions {
  double cleaning_width_m = 0.34;  // floor width cleaned in one pass (the body's diameter)
  double overlap_m = 0.04;         // neighbouring lanes overlap by this
  double clearance_m = 0.05;       // lanes keep the robot radius plus this from walls and furniture
  // The edge pass keeps the robot radius plus this (< clearance_m: closer than the lanes;
  // docs/cleaning.md, "The edge pass 2 cm from the walls").
  double edge_clearance_m = 0.02;
  double bump_block_m = 0.05;      // a remembered contact blocks the robot radius plus this round it
  int max_bump_obstacles = 40;     // at most this many contacts (the latest) go into the plan
  double min_interval_m = 0.005;   // free intervals and overlaps narrower than this do not count
  bool both_directions = true;      // plan lanes along y and along x, keep the shorter
  bool edge_pass = true;           // round each cell along its walls and furniture before its lanes
  int max_cells = 300;             // decomposition bound (more: the smallest are dropped)
  int two_opt_rounds = 30;         // improvement passes over the tour
  int plan_work_per_period = 100000;  // planning done per control period at most (at least one
                                      // step), in work units: a grid cell examined each, 3-5 ns here
  double sweep_speed_mps = 0.15;   // speed along a lane
  double k_cross = 4.0;            // lane following: desired heading correction, rad per metre off
  double k_heading = 2.5;          // rad/s per radian of heading error
  double max_rate_rad_s = 1.0;     // turn rate limit on the lanes
  double turn_in_place_rad = 0.5;  // heading error beyond this: turn on the spot
  double waypoint_tolerance_m = 0.04;  // a route point is passed within this (along the route)
  double approach_gain = 1.0;      // slow down before a route point: speed <= gain * distance + 0.03
  double front_stop_m = 0.08;      // an unmapped obstacle ahead within the robot radius + this
                                   // (and short of where the lane ends): plan round it
  double coverage_cell_m = 0.05;   // grid of the covered-floor estimate
  double resume_overlap = 0.9;     // resuming: a planned cell at least this share inside the
                                   // cells done before is done
  double resume_same_model_m = 0.05;  // resuming: the room and every object within this of where
                                      // the stopped plan had them: plan from its inputs again (its cells)
  double stuck_s = 20;             // no 0.1 m of progress for this long: the route point is given up
  // The cleaning's go-tos (to route points and home) are given these (GoToOptions'
  // of the same names; exploring keeps its own, 0: the exploring campaigns lost
  // runs with them on): no way found with remembered contacts within
  // boxed_in_contacts_m, plan once more without them; plans leave out contacts
  // closer than under_body_contacts_m to the robot (stale: it is there).
  double boxed_in_contacts_m = 0.3;
  double under_body_contacts_m = 0.14;
  // ... and no way found: plan again with sides extended only to their corners
  // (GoToOptions::boxed_in_corners).
  bool boxed_in_corners = true;
  // ... and still none: plan once more letting the way out follow the robot's
  // own path of the last this many metres (GoToOptions::boxed_in_trail_m; 0: never).
  double boxed_in_trail_m = 10;
  int max_goal_failures = 4;       // route points given up in a row: the rest of the cell is given up
  // A route point that cannot be planned to, given up within this of where the
  // last such point was, does not count towards max_goal_failures (the robot
  // has not moved: where it stands is what fails, not the points; the next is
  // tried). 0: every one counts.
  double no_plan_spot_m = 0.1;
  double max_time_s = 3600;        // cleaning plus going home, robot time
  double home_tolerance_m = 0.05;  // home is reached within this
  int home_attempts = 3;           // plans home before giving up
};
options::Table<CleaningOptions> CleaningKeys();

// A rectangle of the robot centre's free space: x in [x0, x1], y in [ylo, yhi].
struct Slab {
  double x0 = 0, x1 = 0, ylo = 0, yhi = 0;
};

struct CoverageCell {
  int id = 0;
  std::vector<Slab> slabs;  // left to right, each starting where the last ends
  std::vector<int> neighbours;
  double area_m2() const;  // of the centre's free space
  // The outline (counter-clockwise), grown by `grow_m` (the body radius: the floor it cleans).
  std::vector<Eigen::Vector2d> Outline(double grow_m) const;
};

struct CoveragePlan {
  bool swapped = false;        // cells and slabs have x and y swapped (lanes along the map's x)
  double inflation_m = 0;      // robot radius + clearance
  double edge_out_m = 0;       // the edge pass runs this much closer to walls and furniture
  double lane_spacing_m = 0;
  Box free;                    // the centre's free space bounds (room shrunk)
  std::vector<CoverageCell> cells;
  std::vector<int> order;      // the tour: indices into cells
  // routes[i]: the polyline cell order[i] is swept along (map frame).
  std::vector<std::vector<Eigen::Vector2d>> routes;
  double route_length_m = 0;   // sum of the routes
  double transit_length_m = 0; // straight-line gaps between routes (from the start)
  // The free rectangles of the robot's centre, in the map frame.
  std::vector<Box> FreeRects() const;
};

// The free space of the robot's centre, decomposed into cells. Obstacles are
// boxes already grown by the inflation; `free` is the room shrunk by it.
std::vector<CoverageCell> Decompose(const Box& free, const std::vector<Box>& obstacles,
                                    const CleaningOptions& options);

// The sweep of one cell: edge pass round it (if asked for), then the lanes in
// between, starting in the corner given (mirror_x: from the right; mirror_y:
// from the top). edge_out_m: the edge pass runs this much outside the cell's
// boundary (closer to the walls and furniture that make it; the route starts
// and its lanes run inside the cell).
std::vector<Eigen::Vector2d> SweepRoute(const CoverageCell& cell, double spacing_m, bool mirror_x,
                                        bool mirror_y, bool edge_pass = true, double edge_out_m = 0);

// The contacts a plan goes round are the latest max_bump_obstacles of those
// remembered (oldest first): the index of the first of them among n.
inline size_t FirstPlannedContact(size_t n, const CleaningOptions& o) {
  return n - std::min(n, static_cast<size_t>(std::max(0, o.max_bump_obstacles)));
}

// The whole plan from the room model (map frame), contacts (map frame) and where
// the robot stands (map frame).
CoveragePlan PlanCoverage(const Box& room, const std::vector<Box>& objects,
                          const std::vector<Eigen::Vector2d>& bumps, const Eigen::Vector2d& start,
                          double robot_radius_m, const CleaningOptions& options);

// PlanCoverage in bounded steps (issue 15: nothing in the control tick does
// unbounded work). Start takes the inputs; each Step does one piece: one
// orientation's decomposition, its greedy tour, one 2-opt round, one cell's
// sweep routes; then the other orientation; then the choice. Done, the plan
// is exactly the one PlanCoverage makes from the same inputs (same cells,
// tour and routes; PlanCoverage runs the same pieces in one go). A step costs
// at most one of: a decomposition (bounded by the boxes: furniture plus
// max_bump_obstacles), O(cells^2) for the tour (cells <= max_cells), one cell's
// four candidate routes.
class CoveragePlanner {
 public:
  // lanes_along_x: plan that orientation only (a resumed cleaning keeps the
  // one it was planned in); none: both_directions decides.
  void Start(const Box& room, const std::vector<Box>& objects, const std::vector<Eigen::Vector2d>& bumps,
             const Eigen::Vector2d& start, double robot_radius_m, const CleaningOptions& options,
             std::optional<bool> lanes_along_x = std::nullopt);
  // One piece of the work; true when the plan is complete (and from then on).
  bool Step();
  bool done() const { return stage_ == Stage::kDone; }
  int steps() const { return steps_; }
  // The work of the steps so far, in work units (CleaningOptions::plan_work_per_period):
  // an estimate of the distances and interval look-ups done, three units each.
  double work() const { return work_; }
  // The plan, once done (moved out: the planner is idle again).
  CoveragePlan Take();

 private:
  enum class Stage { kIdle, kDecompose, kGreedy, kTwoOpt, kRoutes, kDone };
  void EndOrientation();

  Box room_;
  std::vector<Box> objects_;
  std::vector<Eigen::Vector2d> bumps_;
  Eigen::Vector2d start_ = Eigen::Vector2d::Zero();
  double radius_m_ = 0;
  CleaningOptions options_;
  Stage stage_ = Stage::kIdle;
  bool swap_ = false;               // the orientation being planned (false: lanes along y)
  bool one_orientation_ = false;    // Start's lanes_along_x: swap_ only
  CoveragePlan plan_;               // of this orientation
  std::optional<CoveragePlan> along_y_;  // the first orientation's, when both are planned
  Eigen::Vector2d oriented_start_ = Eigen::Vector2d::Zero();
  std::vector<Eigen::Vector2d> mid_;  // the cells' middles (tour)
  int round_ = 0;                   // 2-opt rounds done
  size_t next_ = 0;                 // the next cell of the tour to route
  Eigen::Vector2d at_ = Eigen::Vector2d::Zero();  // where the last route ended
  int steps_ = 0;
  double work_ = 0;
};

// Floor covered so far: a grid over the room; the target is the floor the body
// disc can reach from the plan's free space, marks come from the body's poses.
class CoverageGrid {
 public:
  CoverageGrid() = default;
  // Cells of the floor within body_radius_m of the plan's free space are the target.
  void Init(const Box& room, const std::vector<Box>& free_rects, double body_radius_m, double cell_m);
  // Init in pieces (the same grid): Reset, then AddTarget for each free rectangle.
  void Reset(const Box& room, double body_radius_m, double cell_m);
  void AddTarget(const Box& free_rect);
  // The body disc at p (radius body_radius_m) cleans the floor under it.
  void Mark(const Eigen::Vector2d& p);
  // Every target cell whose centre lies inside `polygon` is covered.
  void MarkInside(const std::vector<Eigen::Vector2d>& polygon);
  double total_m2() const { return target_ * cell_m_ * cell_m_; }
  double covered_m2() const { return covered_ * cell_m_ * cell_m_; }

 private:
  Box room_;
  double cell_m_ = 0.05;
  double radius_m_ = 0;
  int nx_ = 0, ny_ = 0;
  std::vector<uint8_t> state_;  // 0 not target, 1 target, 2 covered
  long target_ = 0, covered_ = 0;
};

}  // namespace irslam::control

#endif  // IRSLAM_CONTROL_COVERAGE_H_
