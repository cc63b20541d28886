// Going to a goal (P1 beside an object, or a survey point): A* path planning
// around the mapped lines, remembered bump points and what the beams see now,
// pure pursuit along the path with periodic replanning, escape from contacts
// (turn away from what was hit, drive off), and giving the goal up (timeout,
// stuck, a second contact). For a goal with a heading the robot turns to it on
// arrival. Pure: time, map and readings are arguments.
#ifndef IRSLAM_CONTROL_GO_TO_H_
#define IRSLAM_CONTROL_GO_TO_H_

#include <Eigen/Core>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "control/bump_memory.h"
#include "control/path_planner.h"
#include "control/wall_follower.h"
#include "slam/slam.h"
#include "types/options.h"

namespace irslam::control {

struct GoToOptions {
  // [exploration] keys since the first exploration release.
  double clearance_m = 0.08;       // planned paths keep robot radius + this from mapped lines
  double goal_tolerance_m = 0.08;  // the goal is reached within this
  double heading_tolerance_rad = 0.12;
  double cruise_speed_mps = 0.18;
  double lookahead_m = 0.25;
  double k_heading = 2.5;  // rad/s per radian of heading error
  double replan_period_s = 2.0;
  // Blocked ahead and no path, replan_backoff_after times in a row: retry after
  // replan_backoff_s, doubling up to replan_period_s (before that, every period).
  // Off by default (0: every period): 0.1 s changed the outcome of some generated
  // worlds and cost one `done` of 30 realistic ones (docs/benchmarks.md).
  double replan_backoff_s = 0;
  int replan_backoff_after = 10;
  // Planning in one control period runs at most this many A* queue pops (~0.1
  // us each here: ~0.7 ms); a search that needs more goes on in the next
  // periods, the robot holding still (or, replanning, following the path it
  // has) meanwhile. 0: no bound (every search ends in the period it starts).
  // Paths in rooms up to 8 x 6 m take under 2,000 pops; only searches that
  // flood a large grid (a goal that cannot be reached) are spread
  // (docs/benchmarks.md: 66 paper-world runs unchanged, the campaign no worse
  // in any row; 5,000 changed the free_start runs).
  int plan_pops_per_period = 7000;
  // A plan's clearance grid counts against that budget: this many cells
  // computed cost one pop (a pop ~0.1 us, a cell ~1.5 ns here), so a period
  // that computes a large room's grid (181,000 cells in a 16 x 12 m hall) runs
  // fewer pops. 0: not counted.
  int plan_cells_per_pop = 64;
  double front_stop_m = 0.32;   // unmapped obstacle ahead: stop, replan
  double go_to_timeout_s = 90;  // give the goal up if not reached by then
  double go_to_stuck_s = 25;    // ... or if the robot got no go_to_progress_m further for this long
  // Tuning numbers that used to be literals.
  double go_to_progress_m = 0.3;  // what counts as getting further (stuck detection)
  double same_contact_m = 0.15;   // a contact this close to the last one is the same contact
  int same_contact_escapes = 5;   // ... for at most this many escapes
  double near_obstacle_m = 0.12;  // a reading ahead within robot radius + this stops the robot
  double near_obstacle_offset_m = 0.1;  // ... and counts as this much farther than it is
  double look_around_factor = 0.3;      // blocked: turn at k_heading times this (rad/s)
  double align_max_rate_rad_s = 0.8;    // turning to the goal's heading
  double pursuit_stop_angle_rad = 0.8;  // aim this far off the heading: turn on the spot
  double pursuit_max_rate_rad_s = 1.0;
  double approach_gain =
      0.6;  // speed limit near the goal: gain * distance + approach_min_speed_mps
  double approach_min_speed_mps = 0.03;
  double line_extension_m = 0.15;  // mapped sides are planned around extended this much at each end
  // No way found: plan again (for the rest of this goal) with the ends of
  // sides that meet another side at a corner extended only to that corner
  // (ExtendedSides). Not always: the extension past convex corners also keeps
  // the robot off corners it passes (extended only to the corners in every
  // plan, the cleaning campaign touched 27 % more). Off while exploring (no
  // key; cleaning sets it, CleaningOptions::boxed_in_corners).
  bool boxed_in_corners = false;
  // ... and still no way: plan again (for the rest of this goal) letting the
  // path follow the robot's own path of the last boxed_in_trail_m metres,
  // whatever the map says is beside it (PathPlanner::SetFreeTrail): the robot
  // came in that way. A side seen short and planned round extended past its
  // end can close the gap the robot drove through into a pocket (the edge pass
  // of a cleaning goes round pieces of furniture by the room model, not by
  // plans); every plan out then failed at once. 0: never (exploring: no key;
  // cleaning sets it, CleaningOptions::boxed_in_trail_m).
  double boxed_in_trail_m = 0;
  double hard_clearance_m = 0.02;  // never plan closer than robot radius + this
  double tight_clearance_m = 0.03;  // a tight goal's plans (TryGoal) keep radius + this, and
                                    // extend the sides only to their corners
  double keep_path_ratio = 1.25;   // keep the current path while shorter than ratio * new + slack
  double keep_path_slack_m = 0.2;
  double keep_path_skip_m = 0.3;  // ... and clear beyond this from the robot
  double escape_side_m = 0.08;    // a mapped side within robot radius + this is what was hit
  double escape_max_s = 6.0;      // an escape lasts at most this
  double escape_heading_tolerance_rad = 0.25;
  double escape_k_heading = 2.0;  // rad/s per radian while turning away
  double escape_max_rate_rad_s = 0.9;
  double escape_drive_s = 1.0;  // drive off for this long once turned away
  double escape_speed_mps = 0.08;
  // Blocked ahead this long with a path found (the path leads past what is in
  // front closer than front_stop_m lets the robot go, so it would hold still
  // until go_to_stuck_s gives the goal up): back off from it as from a contact,
  // without counting one, and plan again from there. 0: never.
  double blocked_escape_s = 3.0;
  // No way found from where the robot stands while remembered contacts lie this
  // close: plan once more without them (and leave them out of this goal's
  // replans). Turning on the spot against something records a contact at every
  // heading, a ring around the robot; a pose corrected after a contact can put
  // the robot over it. Either boxes the start in the planner's grid, and a
  // cleaning gave up every cell at once. The front stop and the bumpers still
  // guard the way. 0: never (the default: over the campaigns, 0.3 m cleaned
  // more but touched more; docs/cleaning.md).
  double boxed_in_contacts_m = 0;
  // Plans leave out remembered contacts closer than this to the robot: under
  // its body, where it is now, they are stale (recorded at the body's edge, they
  // come there when the pose is corrected). 0: never.
  double under_body_contacts_m = 0;
  PlannerOptions planner;  // grid; inflation and hard distance come from the above
};
options::Table<GoToOptions> GoToKeys();

// The mapped sides as the planner's obstacles, each extended by extension_m
// at both ends: sides are seen shorter than they are (their ends are passed on
// corner arcs). to_corners: an end that meets another side at a corner - the
// two lines cross at more than 30 deg, within extension_m of this end and of
// the other side (its end, or on it) - is extended only as far as that corner
// (not at all if it already reaches it). Past a convex corner lies free floor:
// extended there, the sides of two pieces of furniture closed the way between
// them, and a robot that had driven in found no way out.
// Appended to *sides (its buffer reused from one plan to the next).
void ExtendedSides(const std::vector<slam::LineFeature>& lines, double extension_m, bool to_corners,
                   std::vector<Obstacle>* sides);

// Rotation of a vector by angle a (frames differ by the map rotation).
inline Eigen::Vector2d RotateVector(const Eigen::Vector2d& v, double a) {
  return {std::cos(a) * v.x() - std::sin(a) * v.y(), std::sin(a) * v.x() + std::cos(a) * v.y()};
}

// A monotonic clock in ns, injected by the shell to measure planning (the core
// never reads a clock itself); empty: not measured.
using WorkClock = std::function<int64_t()>;

class GoTo {
 public:
  enum class Status { kDriving, kArrived, kGiveUp };
  struct Result {
    Status status = Status::kDriving;
    Twist twist;      // kDriving
    std::string why;  // kGiveUp
  };

  GoTo(GoToOptions options, const RobotGeometry& geometry,
       const std::array<SensorMount, kNumIrSensors>& mounts)
      : options_(options), radius_m_(geometry.radius_m), mounts_(mounts) {}

  // Sets the goal (internal frame) and plans a path to it from the robot's pose
  // (t: the control period's time, whose planning budget it spends); false if
  // none was found. A search that needs more than the period's budget is
  // accepted and goes on in Step, the robot holding still; if it then finds no
  // path, Step gives the goal up ("no way found"). align: on arrival turn to
  // `heading` first; without, once reached the goal stays reached (the caller
  // acts there). tight: plan with tight_clearance_m instead of clearance_m
  // and the sides extended only to their corners (the way out of a pen: its
  // gaps are what the usual clearance closes).
  bool TryGoal(double t, const Eigen::Vector2d& goal, double heading, bool align,
               const slam::Slam& slam, const BumpMemory& bumps, bool tight = false);
  // Starts driving to the goal set by the last successful TryGoal.
  void Begin(double t);
  // One control step; bumpers: the bumper bits now.
  Result Step(double t, const slam::Slam& slam, const RangeScan& raw_scan, uint8_t bumpers,
              const BumpMemory& bumps, const WallFollower& follower);

  const Eigen::Vector2d& goal() const { return p1_; }
  const std::vector<Eigen::Vector2d>& path() const { return path_; }

  void SetWorkClock(WorkClock clock) { clock_ = std::move(clock); }
  // Time spent planning, summed (ns; 0 without a work clock), and the planner's counters.
  int64_t planning_ns() const { return planning_ns_; }
  const PathPlanner::Stats& planner_stats() const { return planner_.stats(); }

 private:
  Result GiveUp(std::string why) { return {Status::kGiveUp, {}, std::move(why)}; }
  Result Drive(Twist tw) { return {Status::kDriving, tw, {}}; }
  // Starts a plan from the robot's pose round the mapped lines, the bumps and
  // what the scan sees, and runs it within the period's budget.
  PathPlanner::Progress Replan(double t, const slam::Slam& slam, const RangeScan& scan,
                               const BumpMemory& bumps);
  // Runs the plan in progress within the period's budget.
  PathPlanner::Progress ContinuePlan(double t);
  // The period's budget of pops left (a new period: the whole budget).
  int64_t* Budget(double t);
  // A plan ended: found (the path taken, or the one followed kept) or not.
  PathPlanner::Progress Ended(PathPlanner::Progress p);
  // After a replan ended in Step: the failure count and the back-off.
  void Planned(double t, bool ok);
  // The nearest thing ahead (mapped or not, or a bump point) from the scan.
  std::optional<double> Front(const RangeScan& scan, const WallFollower& follower) const;
  void BeginEscape(double t, const slam::Slam& slam, double contact_bearing);
  Twist Escape(double t, const Pose2& me);
  Twist Pursue(const Pose2& me, std::optional<double> front);
  // Stuck: go_to_stuck_s without getting go_to_progress_m further (and not escaping).
  bool NoProgress(double t, const Pose2& p);
  // Blocked ahead with a path for longer than blocked_escape_s (then starts over).
  bool BlockedTooLong(double t, bool blocked);
  struct Hit {
    double distance;  // as Front counts it
    double bearing;   // robot frame
  };
  std::optional<Hit> NearestAhead(const RangeScan& scan) const;
  // Bearing (robot frame) of what Front found closest; 0 when that was the
  // front sensors' distance.
  double FrontBearing(const RangeScan& scan, const WallFollower& follower) const;
  // A contact (at bearing, robot frame): begins the escape from it, or false
  // when it is this go-to's second one (not the same one again).
  bool OnContact(double t, const slam::Slam& slam, double bearing);
  // Boxed in: this goal's plans leave out the contacts within boxed_in_contacts_m
  // of the robot from now on. False (nothing changed) when already done for this
  // goal or no contact is that close.
  bool DropNearContacts(const slam::Slam& slam, const BumpMemory& bumps);
  // A remembered contact within boxed_in_contacts_m of at (never when it is 0).
  bool WithinDropped(const Eigen::Vector2d& contact, const Eigen::Vector2d& at) const;
  // No way found: the next plan of this goal may leave more out - first the
  // contacts close by (DropNearContacts), then the extensions past corners
  // (boxed_in_corners), then the robot's own path is free (boxed_in_trail_m).
  // False when nothing is left to leave out.
  bool Loosen(const slam::Slam& slam, const BumpMemory& bumps);

  GoToOptions options_;
  double radius_m_;
  std::array<SensorMount, kNumIrSensors> mounts_;
  Eigen::Vector2d p1_ = Eigen::Vector2d::Zero();  // internal frame
  double p1_heading_ = 0;
  bool align_ = true;
  bool arrived_ = false;
  std::vector<Eigen::Vector2d> path_;
  double since_ = 0;
  double last_plan_ = -1e9;
  // Blocked ahead and the last replan_backoff_after plans failed: not replanned
  // before retry_at_ (the delay doubles with each failure, up to
  // replan_period_s); meanwhile the robot looks around on the spot.
  bool last_plan_ok_ = true;
  int plan_failures_ = 0;
  double retry_at_ = -1e9;
  PathPlanner planner_;  // its grids are kept between plans
  std::vector<Obstacle> plan_obstacles_;                 // what the plan in progress avoids
  Eigen::Vector2d plan_from_ = Eigen::Vector2d::Zero();  // ... and where the robot was
  double budget_t_ = -1e18;                              // the period budget_left_ is for
  int64_t budget_left_ = 0;
  WorkClock clock_;
  int64_t planning_ns_ = 0;
  double backoff_until_ = -1e9;
  double escape_heading_ = 0;
  bool escape_turned_ = false;
  int bumps_ = 0;  // contacts since the go-to began
  int same_contact_escapes_ = 0;
  Eigen::Vector2d last_contact_ = Eigen::Vector2d::Zero();
  double blocked_since_ = -1;  // blocked ahead with a path since then (-1: not)
  // This goal's plans leave out the contacts within boxed_in_contacts_m of
  // drop_at_ (set by DropNearContacts when boxed in there).
  bool drop_contacts_ = false;
  Eigen::Vector2d drop_at_ = Eigen::Vector2d::Zero();
  // This goal's plans extend sides only to their corners (Loosen).
  bool to_corners_ = false;
  // This goal's plans may follow the robot's own recent path (Loosen).
  bool along_trail_ = false;
  bool tight_ = false;  // this goal's plans keep tight_clearance_m, sides extended only to corners
  std::vector<Eigen::Vector2d> trail_;  // its points (internal frame), buffer reused
  double progress_t_ = -1;  // got go_to_progress_m further at this time ...
  Eigen::Vector2d progress_at_ = Eigen::Vector2d::Zero();  // ... from here
};

}  // namespace irslam::control

#endif  // IRSLAM_CONTROL_GO_TO_H_
