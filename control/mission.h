// The mission: a state machine over behaviours. Each behaviour is its own class
// with its own state and options (wall_follower.h, loop_detector.h, go_to.h,
// contour_follow.h, survey.h, bump_memory.h); the Mission keeps only the state,
// the transitions between behaviours and the reason for each, and turns the
// active behaviour's twist into wheel velocities. Pure: time is an argument.
//
// Transitions (every running state also: time limit or no progress -> idle;
// stop -> idle; controller lost -> fault, back -> the state it left):
//
//   from            on                                   to              reason
//   idle, done      start                                wall_follow     ""
//   wall_follow     loop round a free object             wall_follow     "circled a free object;
//   ..." wall_follow     room loop, more loops asked for      wall_follow     (unchanged)
//   wall_follow     room loop, the last one              model           "wall-following loop
//   closed" model           exploration off                      done            "room modelled
//   (exploration off)" model           nothing pending, a survey planned    go_to_p1 "surveying the
//   room (n)" model           nothing pending                      done            "room modelled:
//   n objects, k complete" model           P1 of the nearest pending object     go_to_p1 "going to
//   object n" model           no P1 reachable (object given up)    model           "object n: P1
//   unreachable" go_to_p1        timeout, stuck, blocked (given up)   model           "object n,
//   P1: why" / "survey point: why" go_to_p1        survey point: turned round           model
//   "survey done" go_to_p1        at P1, heading along the side        contour_follow  "contour
//   following object n" contour_follow  complete / closed by the contour     model "object n
//   complete ..." contour_follow  all round, free sides, timeout       model           "object n
//   incomplete ..." (given up)
//
//   model           done as above, mode clean                clean           "cleaning n cells"
//   clean           every cell swept or given up             return_home     "cleaned: ..."
//   return_home     at the start pose                        done            "cleaned ..., back home"
//   return_home     no way home after home_attempts plans    done            "cleaned ...; home: why"
//   model, go_to_p1, contour_follow  mission time limit, mode clean, room modelled
//                                    (clean_at_time_limit) -> model -> clean
//                   "mission time limit reached: cleaning the room as modelled" (pending objects given up)
// (clean and return_home: time limit [cleaning].max_time_s from entering clean.)
//
// A pen (free_space.h; [mission].pen_*; not after a relocalisation: its evidence is of another frame):
//   wall_follow     room loop, the last one, floor seen free go_to_p1        "the loop went round a pen (a m2 of
//                   outside its room box, a way out planned                   floor seen outside it): leaving it"
//   go_to_p1        at the way out                           wall_follow     "out of the pen: following walls again"
//   go_to_p1        timeout, stuck, blocked                  model           "leaving the pen: why"
//
// A free object circled again ([mission].repeat_free_loop_m):
//   wall_follow     loop round a free object closing where   model           "circled the same free object
//                   one closed before, the room's four walls                 again, the room's walls mapped"
//                   mapped (as the last room loop: the pen check first)
//
// In a saved map (issue 14; relocalize.h):
//   idle, done      start in a saved map (StartInMap)        relocalize      "relocalising in the saved map"
//   idle, done      start, the live map modelled (StartKnown) model          "continuing in the map ..."
//   relocalize      the search commits                       model           "relocalised in the saved map ..."
//                   (the core then has the SLAM adopt the saved map: TakeAdoption, Adopted)
//   relocalize      no commit within [relocalize].max_time_s wall_follow     "could not relocalise ...: exploring
//                                                                              afresh" (the local map goes on)
//   any running     the map disagrees (MapAgreement)         relocalize      "the map disagrees ...: relocalising"
//                   (the core restarts the local SLAM: TakeSlamReset; after the commit the
//                    mission resumes cleaning where it was, anything else via model)
//   any running     the map disagreed max_attempts times     idle            "the map disagrees ...: giving up"
#ifndef IRSLAM_CONTROL_MISSION_H_
#define IRSLAM_CONTROL_MISSION_H_

#include <array>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "control/bump_memory.h"
#include "control/clean.h"
#include "control/contour_follow.h"
#include "control/free_space.h"
#include "control/go_to.h"
#include "control/loop_detector.h"
#include "control/path_planner.h"
#include "control/relocalize.h"
#include "control/room_model.h"
#include "control/survey.h"
#include "control/wall_follower.h"
#include "slam/slam.h"
#include "types/geometry.h"
#include "types/options.h"
#include "types/signals.h"

namespace irslam::control {

enum class MissionState : uint8_t {
  kIdle = 0,
  kWallFollow = 1,
  kModel = 2,
  kGoToP1 = 3,
  kContourFollow = 4,
  kDone = 5,
  kFault = 6,
  kClean = 7,
  kReturnHome = 8,
  kRelocalize = 9,
};
const char* ToString(MissionState s);

struct MissionOptions {
  double max_time_s = 900;          // whole mission, robot time
  double progress_timeout_s = 120;  // no new distance covered for this long: give up
  double max_accel_mps2 = 0.8;      // wheel acceleration limit of the command
  int wall_follow_loops = 1;        // loops of the room before modelling (Fig. 18: 5)
  bool explore = true;              // false: model after wall following and stop (map only)
  double progress_step_m = 0.05;    // distance that counts as progress
  double max_step_s = 0.1;          // longest control step used for the acceleration limit
  LoopOptions loop;                 // [mission] too
  BumpMemoryOptions bump;           // [mission] too
  PenOptions pen;                   // [mission] too
  std::string mode = "explore";     // explore: map the room; clean: map, clean, go home
  // Mode clean: the exploration reaching max_time_s with the room modelled (the
  // loop closed) cleans the room as it is modelled - the objects still pending
  // given up - instead of ending without cleaning. false: it ends (as in mode explore).
  bool clean_at_time_limit = true;
  // A free-object loop closing within this of an earlier one's closing point,
  // with the room's four walls mapped, ends wall following: the room is
  // modelled from the map. (The follower, turned at a gap onto the same object
  // each time, left it and came back along the same walls until the time limit:
  // generated room 1028.) 0: always leave.
  double repeat_free_loop_m = 0.5;
  CleaningOptions cleaning;         // [cleaning]
  RelocalizeOptions relocalize;     // [relocalize]
};
options::Table<MissionOptions> MissionKeys();

// What a mission continuing in a saved map starts from (map frame).
struct SavedMission {
  SavedLines map;
  EnvironmentModel model;
  std::optional<CleaningProgress> cleaning;  // a cleaning stopped before: resumed
};

// The SLAM is to adopt the saved map: Slam::AdoptMap(local_to_map, lines).
struct Adoption {
  Pose2 local_to_map;
  std::vector<slam::LineFeature> lines;
  // Relocalising failed and the map is restored as it was before it
  // disagreed: the local SLAM's lines, in no known relation to the map's
  // frame, are forgotten first (AdoptMap would keep them as new lines).
  bool restore = false;
};

// Relocalisation's progress (status.relocalize): searching, or committed.
struct RelocalizeProgress {
  bool committed = false;
  double started_t = 0;
  double committed_t = 0;
  int hypotheses = 0;
  double best_score = 0;
  double evidence_m = 0;
  int attempts = 0;
};

// The exploration behaviours' options (config section [exploration]).
struct ExploreOptions {
  GoToOptions go_to;
  ContourOptions contour;
  SurveyOptions survey;
};

class Mission {
 public:
  Mission(MissionOptions options, WallFollowerOptions wall, ExploreOptions explore,
          ModelOptions model, const slam::SlamOptions& slam);

  bool Start(double t, std::string* why);
  // Starts in a saved map (the core has given it a fresh local SLAM): relocalise first.
  bool StartInMap(double t, SavedMission saved, std::string* why);
  // Starts again in the live map (modelled: the room is known): model, then the
  // configured work, with the map's agreement checked as after a relocalisation.
  bool StartKnown(double t, const slam::Slam& slam, std::string* why);
  // Once per period after Step, for the core: the SLAM must adopt the saved map
  // (then call Adopted with it), or restart from nothing for a new search.
  std::optional<Adoption> TakeAdoption();
  bool TakeSlamReset();
  // Lines to take out of the map (furniture that moved): the core removes them
  // from the SLAM and then calls LinesRemoved.
  std::vector<int> TakeLineRemovals() { return std::exchange(line_removals_, {}); }
  void LinesRemoved(const slam::Slam& slam);
  void Adopted(double t, const slam::Slam& slam);
  // Relocalisation since the last start (none when the mission did not start in a map).
  std::optional<RelocalizeProgress> relocalize() const;
  // The mode of the next start (the configured one until set): cleaning or not.
  void SetCleanMode(bool clean) { clean_mode_ = clean; }
  bool clean_mode() const { return clean_mode_; }
  void Stop(double t);
  // Controller lost / back: fault keeps the state to resume.
  void SetFault(double t, const std::string& reason);
  void ClearFault(double t);

  // One control period: returns the wheel command. bumpers: CTRL_STATUS.Bumpers bits
  // (bit0 left, bit1 right).
  WheelCommand Step(double t, const slam::Slam& slam, const RangeScan& scan, uint8_t bumpers);

  MissionState state() const { return state_; }
  const std::string& reason() const { return reason_; }
  const WallFollower& wall_follower() const { return follower_; }
  const EnvironmentModel& model() const { return modeler_.model(); }
  int target_object() const { return target_; }
  // The go-to path (internal frame), for status and drawings.
  const std::vector<Eigen::Vector2d>& path() const { return go_to_.path(); }
  // Planning's share of the work (issue 15): the shell injects the clock.
  void SetWorkClock(WorkClock clock) { go_to_.SetWorkClock(std::move(clock)); }
  const GoTo& go_to() const { return go_to_; }
  double started_at() const { return started_at_; }
  // Cleaning progress (state none when cleaning never ran since the last start).
  CleaningProgress cleaning(double t, double distance_m) const {
    return clean_.Progress(t, distance_m);
  }
  const Clean& clean() const { return clean_; }
  const Relocalize& reloc() const { return reloc_; }
  // Robot times at which wall-following loops of the room closed.
  const std::vector<double>& loop_times() const { return loop_times_; }

 private:
  void Enter(MissionState s, double t, std::string reason);
  // Enter and stop the wheels for this period.
  WheelCommand To(MissionState s, double t, std::string reason) {
    Enter(s, t, std::move(reason));
    return Halt();
  }
  WheelCommand ToWheels(const Twist& tw, double dt);
  WheelCommand Halt() {
    last_cmd_ = {};
    return {};
  }
  // Time limit and progress watchdog; false if the mission was ended.
  bool Watchdogs(double t, const slam::Slam& slam);
  // The exploration's time limit in mode clean with the room modelled: the model
  // is to be cleaned as it is (clean_at_time_limit; once). False: the limit ends
  // the mission as ever.
  bool CleanAtTimeLimit(double t);
  WheelCommand StepWallFollow(double t, double dt, const slam::Slam& slam, const RangeScan& scan,
                              bool bumped);
  WheelCommand StepModel(double t, const slam::Slam& slam);
  WheelCommand StepGoTo(double t, double dt, const slam::Slam& slam, const RangeScan& scan,
                        uint8_t bumpers);
  WheelCommand StepContour(double t, double dt, const slam::Slam& slam, const RangeScan& scan,
                           bool bumped);
  // Plans to the nearest pending object's P1 and starts going there.
  WheelCommand GoToObject(double t, const slam::Slam& slam, const EnvironmentModel& m);
  // Gives the go-to's goal up (the object, noted in the model, unless a free
  // object's side facing a near wall is inferred; or the survey point).
  WheelCommand AbandonGoTo(double t, const slam::Slam& slam, const std::string& why);
  // The target is free and the model infers its side facing a wall too near to
  // go between (Modeler::CloseNearWall): it is complete.
  bool InferNearWall(const slam::Slam& slam);
  // Picks the next survey point and starts going there; false if none is left.
  bool StartSurvey(double t, const slam::Slam& slam, const EnvironmentModel& m);
  // At the last room loop: if the beams saw floor outside the room it encloses,
  // plans the way out of the pen and returns true (go_to_p1).
  bool LeavePen(double t, const slam::Slam& slam);
  // At a free-object loop: it closed where one closed before (repeat_free_loop_m)
  // and the room's four walls are mapped (remembers where it closed).
  bool RepeatedFreeLoop(const slam::Slam& slam);
  // Out of the pen: its mouth, where the way out left its box, is remembered as
  // contacts (bumps_) along the box's side up to what the beams hit there, so
  // that the followers and plans do not go back in.
  void ClosePenMouth();
  void TracePenExit(const Pose2& map_pose);
  // Modelled and explored: done, or in mode clean, plan the cleaning and start it.
  WheelCommand Finish(double t, const slam::Slam& slam, const EnvironmentModel& m,
                      std::string reason);
  // The reason while cleaning: the cells planned (and resumed).
  std::string CleaningReason() const;
  WheelCommand StepClean(double t, double dt, const slam::Slam& slam, const RangeScan& scan,
                         uint8_t bumpers);
  WheelCommand StepReturnHome(double t, double dt, const slam::Slam& slam, const RangeScan& scan,
                              uint8_t bumpers);
  WheelCommand StepRelocalize(double t, double dt, const slam::Slam& slam, const RangeScan& scan,
                              bool bumped);
  // After a commit or a known start: the map's agreement is checked every
  // period; false when the mission turned to relocalising (or gave up).
  bool CheckAgreement(double t, const slam::Slam& slam, const RangeScan& scan);
  // Ending while relocalising again: the map before it disagreed is restored.
  void RestoreMapOnEnd();
  // The common reset of every start.
  void Reset(double t);

  MissionOptions options_;
  RobotGeometry geometry_;
  double follow_distance_m_;
  // The behaviours.
  WallFollower follower_;
  Modeler modeler_;
  BumpMemory bumps_;
  FreeSpace free_;  // the floor the beams saw while following walls (SLAM frame)
  double radius_m_;  // the robot's
  LoopDetector loop_;
  GoTo go_to_;
  ContourFollow contour_;
  Survey survey_;
  Clean clean_;
  GoTo home_go_to_;
  // The mission's own state.
  MissionState state_ = MissionState::kIdle;
  MissionState resume_state_ = MissionState::kIdle;
  std::string reason_;
  int target_ = 0;  // object being completed (0: a survey point or a pen's way out)
  bool leaving_pen_ = false;  // go_to_p1 drives out of a pen
  Box pen_box_;               // ... the room its loop modelled (map frame, turned by pen_rotation_)
  double pen_rotation_ = 0;
  bool pen_was_inside_ = false;               // on the way out: the robot was inside the box
  std::optional<Eigen::Vector2d> pen_mouth_;  // ... and here first outside it after (map frame)
  int pens_left_ = 0;         // pens left this mission
  std::vector<Eigen::Vector2d> free_loops_;  // where free-object loops closed (at most kMaxFreeLoops)
  static constexpr size_t kMaxFreeLoops = 16;
  double started_at_ = 0;
  double last_t_ = 0;
  int loops_done_ = 0;
  std::vector<double> loop_times_;
  double progress_distance_ = 0;
  double progress_t_ = 0;
  WheelCommand last_cmd_;
  // Cleaning.
  bool clean_mode_ = false;
  bool home_set_ = false;
  Pose2 home_;  // internal frame: where the mission started
  bool home_planned_ = false;
  int home_attempts_ = 0;
  double home_retry_t_ = 0;  // the next plan home not before this
  double clean_started_ = 0;
  // Working in a saved map (issue 14).
  ModelOptions model_options_;
  Relocalize reloc_;
  MapAgreement agreement_;
  bool checking_ = false;  // the map's agreement is checked (committed or known start)
  std::optional<Adoption> adoption_;
  bool slam_reset_ = false;
  bool reloc_ran_ = false;  // relocalisation ran since the last start
  RelocalizeProgress reloc_progress_;
  MissionState after_reloc_ = MissionState::kModel;
  size_t reloc_bumps_from_ = 0;  // bumps recorded while relocalising (local frame) from here
  MapChanges changes_;
  std::vector<int> line_removals_;
  // The objects the IR check (agreement_) attributes rays to: the saved
  // map's (or, continuing in the live map, the model's at the start), less
  // those found moved. Kept across relocalisations: by then the modeller may
  // have grouped a side the SLAM stretched over a moved piece's new place
  // with the new piece.
  EnvironmentModel checked_model_;
  // The ids of the lines the map had when the mission began working in it
  // (the rest are this mission's own: agreement_ may find them contradicted).
  std::vector<int> checked_lines_;
  // Watches the saved furniture for moves (after a commit or a known start).
  void WatchChanges(const slam::Slam& slam, const std::vector<TimedPose>& trajectory);
  void StepChanges(const slam::Slam& slam);
  // Object `o` of the map (id, sides, box) is not where it was: its sides
  // leave the map and the modeller is told (map_changes.h, or the IR check in
  // relocalize.h, which gives the object as it was set aside).
  void ObjectMoved(const ObjectModel& o);
  // Cleaning is over (or the modelling after it): home.
  WheelCommand ReturnHome(double t, std::string reason);
  std::optional<CleaningProgress> resume_cleaning_;  // the next cleaning resumes this
  Pose2 local_to_map_;          // of the last commit
  bool home_in_local_ = false;  // home_ was taken in a relocalisation's local frame
  bool give_up_after_adoption_ = false;  // the adoption restores the map; then idle
  std::string clean_summary_;
  bool remodel_after_clean_ = false;  // cleaned; modelling a moved piece before going home
  bool explore_timed_out_ = false;    // clean_at_time_limit: the model is cleaned as it is
  double last_distance_ = 0;  // travelled, at the last step
};

}  // namespace irslam::control

#endif  // IRSLAM_CONTROL_MISSION_H_
