// Cleaning the modelled room: plans the coverage once on entering (coverage.h,
// bounded by the room's size; a bounded piece per control period while the
// robot holds still), then drives each cell's route with a
// cross-track controller (the heading is corrected towards the lane in
// proportion to the distance off it; the error is reported), while SLAM goes on
// correcting the pose. Between cells, and round anything the lanes run into that
// the map does not have (a contact, an unmapped obstacle ahead), the go-to
// behaviour plans a way with the A* planner; a route point it cannot reach is
// skipped, and after max_goal_failures in one cell the rest of the cell is
// reported unreachable (unreachable_m2), never retried. Pure: time, map and
// readings are arguments.
#ifndef IRSLAM_CONTROL_CLEAN_H_
#define IRSLAM_CONTROL_CLEAN_H_

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "control/bump_memory.h"
#include "control/coverage.h"
#include "control/go_to.h"
#include "control/room_model.h"
#include "control/wall_follower.h"
#include "slam/slam.h"

namespace irslam::control {

// The go-to options for cleaning: route points lie at the cleaning clearance
// from walls and furniture, so the planner allows a little less, and the stop
// for things ahead must not fire at every lane end.
GoToOptions CleaningGoTo(GoToOptions g, const CleaningOptions& c);

enum class CleanState { kNone, kCleaning, kReturning, kDone, kStopped };
const char* ToString(CleanState s);

// Progress of the cleaning (status.cleaning and the map's "cleaning").
struct CleaningProgress {
  CleanState state = CleanState::kNone;
  double started_t = 0;
  double finished_t = 0;  // 0 while not finished (home reached, or stopped)
  double swept_t = 0;     // the last cell finished (going home from then); 0 before
  int cells_done = 0;
  int cells_total = 0;
  double covered_m2 = 0;  // estimated from the SLAM pose
  double total_m2 = 0;    // floor the body can reach from the plan's free space
  double fraction = 0;
  double path_m = 0;      // driven since cleaning began
  double eta_s = 0;
  double unreachable_m2 = 0;
  double cross_track_rms_m = 0;  // on the lanes
  double cross_track_max_m = 0;
  double cleaning_width_m = 0;
  // Per cell in tour order (map frame): outline of the floor it cleans, route,
  // done (swept to the end) or unreachable (given up).
  struct Cell {
    int id = 0;
    std::vector<Eigen::Vector2d> polygon;
    std::vector<Eigen::Vector2d> route;
    bool done = false;
    bool unreachable = false;
  };
  std::vector<Cell> cells;
  // What the plan was made from (map frame): the room, the objects' boxes and
  // the remembered contacts it went round (the latest max_bump_obstacles). A
  // resume plans from these again while the model has not moved
  // (CleaningOptions::resume_same_model_m), so it cuts the same cells. None:
  // not planned yet, or a map saved without them.
  struct PlanInputs {
    Box room;
    std::vector<Box> objects;
    std::vector<Eigen::Vector2d> contacts;
  };
  std::optional<PlanInputs> planned;
};

// The model now (`now`) is where the plan's (`planned`) was: the same number of
// objects, and the room and each object (paired one to one) with every edge
// within tolerance_m of the planned one's. tolerance_m 0: never.
bool SameModel(const CleaningProgress::PlanInputs& planned, const CleaningProgress::PlanInputs& now,
               double tolerance_m);

class Clean {
 public:
  enum class Status { kCleaning, kDone };
  struct Result {
    Status status = Status::kCleaning;
    Twist twist;
  };

  Clean(CleaningOptions options, GoToOptions go_to, const RobotGeometry& geometry,
        const std::array<SensorMount, kNumIrSensors>& mounts);

  // Starts planning the coverage of the modelled room (once), from where the
  // robot is now and the contacts remembered now. The planning is done by Plan,
  // a bounded piece per control period (issue 15); then the cleaning starts at
  // the first cell not done. `resume`: a cleaning stopped before (issue 13; the
  // saved map's or the live map's progress) goes on: each planned cell lying
  // mostly inside the cells done then (resume_overlap of its outline) is done
  // now and the tour skips it (resumed_cells counts them); the routes of the
  // cells done then count as swept. While the model is where the stopped plan
  // had it (SameModel), the plan is made from that plan's inputs (its cells
  // again); otherwise from the current model and contacts, and may be cut
  // differently.
  void Begin(double t, const slam::Slam& slam, const EnvironmentModel& m, const BumpMemory& bumps,
             std::optional<CleaningProgress> resume = std::nullopt);
  // Planning (Begin was called, the plan is not complete): the robot holds still.
  bool planning() const { return stage_ != PlanStage::kNone; }
  // This period's share of the planning (plan_work_per_period; at least one
  // piece); true when it is complete (Step drives from then).
  bool Plan(double t);
  // Cells of the plan taken as done from the cleaning resumed (known once planned).
  int resumed_cells() const { return resumed_cells_; }
  // The cleaning resumed was planned again from the stopped plan's inputs.
  bool replanned_same() const { return replanned_same_; }
  Result Step(double t, const slam::Slam& slam, const RangeScan& raw_scan, uint8_t bumpers,
              const BumpMemory& bumps, const WallFollower& follower);
  // The mission's state changed: returning home, finished or stopped.
  void SetState(CleanState s, double t, double distance_m);

  const CleaningProgress& progress() const { return progress_; }
  CleaningProgress Progress(double t, double distance_m) const;
  const CoveragePlan& plan() const { return plan_; }
  void Reset();
  // Driving was interrupted (issue 14: relocalising after the map disagreed):
  // the next Step plans its way to the current route point again.
  void Interrupted(double t);
  bool active() const { return progress_.state != CleanState::kNone; }
  // The go-to's path (internal frame) while it drives.
  const std::vector<Eigen::Vector2d>& path() const { return go_to_.path(); }

 private:
  enum class Phase { kPlanGoal, kTransit, kSweep, kDone };
  // Planning, in this order: the coverage plan (CoveragePlanner), the
  // covered-floor grid (a few free rectangles per step), the progress's cells,
  // the cells done before (ResumeStep, then MarkSwept).
  enum class PlanStage { kNone, kCoverage, kGrid, kCells, kResume };
  // Resuming: a piece of matching planned cell stage_next_ against the cells
  // done before (it is done if at least CleaningOptions::resume_overlap of it
  // lies inside them): one lattice column; the work it took.
  double ResumeStep(const CleaningProgress& before);
  // Resuming: what a cell done before swept counts as covered; the work.
  double MarkSwept(const CleaningProgress::Cell& before);
  // One piece of the planning; returns its work (CleaningOptions::plan_work_per_period).
  double PlanStep(double t);
  // The plan is complete: the cleaning starts (at t).
  void Started(double t);
  // The current cell is finished (swept, or its rest given up).
  void NextCell(bool unreachable);
  // Moves cell_ past cells already done (resumed).
  void SkipDone();
  // The nearest point of the current cell's free space, 5 cm inside its
  // boundary where it is that wide (the route points of a pushed-out edge pass
  // lie outside it).
  Eigen::Vector2d IntoCell(const Eigen::Vector2d& p) const;
  // Gives the current route point up; counted: towards max_goal_failures.
  void SkipPoint(bool counted = true);
  double RemainingRoute() const;
  // The share of the current cell's area that a length of its route sweeps.
  double AreaShare(double length_m) const;
  Twist Follow(const Pose2& me, const RangeScan& scan, bool* blocked, bool* passed);
  // Step's phases: planning to the next route point, and sweeping a lane.
  Result StepPlanGoal(double t, const Pose2& me, double rot, const slam::Slam& slam, const BumpMemory& bumps);
  std::vector<Eigen::Vector2d> GoalTries(const Eigen::Vector2d& goal) const;  // at most four points
  Result StepSweep(const Pose2& me, const slam::Slam& slam, const RangeScan& raw_scan, uint8_t bumpers,
                   const BumpMemory& bumps);

  CleaningOptions options_;
  double radius_m_;
  std::array<SensorMount, kNumIrSensors> mounts_;
  GoTo go_to_;
  CoveragePlan plan_;
  CoveragePlanner planner_;
  PlanStage stage_ = PlanStage::kNone;
  Box room_;                      // the room planned for
  std::vector<Box> free_rects_;   // the plan's free space (grid targets)
  size_t stage_next_ = 0;         // the next rectangle or cell of the stage
  std::optional<CleaningProgress> resume_;
  int resumed_cells_ = 0;
  bool replanned_same_ = false;
  std::optional<CleaningProgress::PlanInputs> inputs_;  // what the plan being made is made from
  // The planned cell being matched (ResumeStep): its bounds, the outlines of
  // the cells done before that may overlap it (in resume_), the lattice column
  // next, and the lattice points inside it and inside those so far.
  struct Match {
    Box box;
    std::vector<const std::vector<Eigen::Vector2d>*> done;
    double vertices = 0;
    int column = 0;
    long inside = 0, inside_done = 0;
  };
  Match match_;
  CoverageGrid grid_;
  CleaningProgress progress_;
  Phase phase_ = Phase::kDone;
  size_t cell_ = 0;   // position in the tour
  size_t point_ = 0;  // the route point driven to
  int failures_ = 0;  // in this cell
  // Where the last route point that could not be planned to was given up
  // (none: no such point since Begin).
  std::optional<Eigen::Vector2d> no_plan_at_;
  double start_distance_ = 0;
  double progress_t_ = 0;  // got 0.1 m further at this time ...
  Eigen::Vector2d progress_at_ = Eigen::Vector2d::Zero();  // ... from here
  double cross_sq_ = 0;
  long cross_n_ = 0;
};

}  // namespace irslam::control

#endif  // IRSLAM_CONTROL_CLEAN_H_
