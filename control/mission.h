// The mission state machine: idle -> wall_follow -> model -> ... -> done, with
// fault on controller loss and stop/start at any time. Owns the behaviours
// (wall following now; go-to and contour following come with exploration) and
// turns their twist into wheel velocities. Pure: time is an argument.
#ifndef IRSLAM_CONTROL_MISSION_H_
#define IRSLAM_CONTROL_MISSION_H_

#include <array>
#include <string>
#include <vector>

#include "control/path_planner.h"
#include "control/room_model.h"
#include "control/wall_follower.h"
#include "slam/slam.h"
#include "types/geometry.h"
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
};
const char* ToString(MissionState s);

struct MissionOptions {
  double max_time_s = 900;           // whole mission, robot time
  double progress_timeout_s = 120;   // no new distance covered for this long: give up
  double loop_min_distance_m = 3.0;  // wall following must cover this before a loop can close
  double loop_close_radius_m = 0.25;  // back within this of where wall following started
  double loop_close_angle_rad = 0.7;
  double max_accel_mps2 = 0.8;       // wheel acceleration limit of the command
  int wall_follow_loops = 1;         // loops of the room before modelling (Fig. 18: 5)
  bool explore = true;               // false: model after wall following and stop (map only)
};

struct ExploreOptions {
  double clearance_m = 0.08;          // planned paths keep robot radius + this from mapped lines
  double goal_tolerance_m = 0.08;     // P1 reached
  double heading_tolerance_rad = 0.12;
  double cruise_speed_mps = 0.18;
  double lookahead_m = 0.25;
  double k_heading = 2.5;
  double replan_period_s = 2.0;
  double front_stop_m = 0.32;         // unmapped obstacle ahead while going to P1: stop, replan
  double go_to_timeout_s = 90;        // give the object up if P1 is not reached by then
  double go_to_stuck_s = 25;          // ... or if the robot got no 0.3 m further for this long
  double contour_timeout_s = 150;     // give up completing an object after this
  int contour_loops = 2;              // times round an object before giving it up
  double contour_leave_m = 0.6;       // a wall-contact object's free sides have been followed
                                      // once the robot is this much farther than the follow
                                      // distance from it (it follows the wall away)
  bool survey_centre = true;          // look round from inside the room (first its middle) to find
                                      // free objects too far from the walls to be seen
  int max_surveys = 3;                // ... from at most this many points
  double survey_range_m = 0.7;        // a part of the room within this of the trajectory was seen
  double survey_min_unseen_m2 = 0.4;  // a survey point must see at least this much unseen room
};

class Mission {
 public:
  Mission(MissionOptions options, WallFollowerOptions wall, ExploreOptions explore,
          ModelOptions model, const slam::SlamOptions& slam);

  bool Start(double t, std::string* why);
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
  // The go-to path (internal frame) and P1, for status and drawings.
  const std::vector<Eigen::Vector2d>& path() const { return path_; }
  double started_at() const { return started_at_; }
  // Robot times at which wall-following loops of the room closed.
  const std::vector<double>& loop_times() const { return loop_times_; }

 private:
  void Enter(MissionState s, double t, std::string reason);
  WheelCommand ToWheels(const Twist& tw, double dt);
  // The scan with remembered bump points added as virtual readings (see .cc).
  RangeScan WithBumpMemory(const RangeScan& scan, const Pose2& me) const;
  WheelCommand StepWallFollow(double t, double dt, const slam::Slam& slam, const RangeScan& scan, bool bumped);
  WheelCommand StepModel(double t, const slam::Slam& slam);
  WheelCommand StepGoTo(double t, double dt, const slam::Slam& slam, const RangeScan& scan, bool bumped);
  WheelCommand StepContour(double t, double dt, const slam::Slam& slam, const RangeScan& scan, bool bumped);
  bool Replan(const slam::Slam& slam, const RangeScan& scan);
  // Gives the go-to's goal up (the object, noted in the model; or the survey point).
  WheelCommand AbandonGoTo(double t, const std::string& why);
  // Picks the next survey point and starts going there; false if none is left.
  bool StartSurvey(double t, const slam::Slam& slam, const EnvironmentModel& m);
  // Getting clear of a contact during a go-to: turn away from it, drive off.
  void BeginEscape(double t, const slam::Slam& slam);
  WheelCommand Escape(double t, double dt, const Pose2& me);
  WheelCommand Halt() {
    last_cmd_ = {};
    return {};
  }

  MissionOptions options_;
  ExploreOptions explore_;
  RobotGeometry geometry_;
  std::array<SensorMount, kNumIrSensors> mounts_;
  double follow_distance_m_;
  WallFollower follower_;
  Modeler modeler_;
  int target_ = 0;                     // object being completed (0: the survey)
  int surveys_done_ = 0;
  std::vector<Eigen::Vector2d> survey_points_;  // map frame
  double survey_turned_ = -1;          // >= 0 while turning round at the survey point
  Eigen::Vector2d p1_ = Eigen::Vector2d::Zero();  // internal frame
  double p1_heading_ = 0;
  std::vector<Eigen::Vector2d> path_;
  std::vector<Eigen::Vector2d> bump_points_;  // where bumpers hit something (internal frame)
  double state_since_ = 0;
  double last_plan_ = -1e9;
  double backoff_until_ = -1e9;
  double escape_heading_ = 0;
  bool escape_turned_ = false;
  uint8_t bumpers_now_ = 0;
  int windows_seen_ = 0;
  int go_to_bumps_ = 0;  // contacts since the go-to began
  int contour_loops_done_ = 0;
  int same_contact_escapes_ = 0;
  Eigen::Vector2d last_contact_ = Eigen::Vector2d::Zero();
  double go_progress_t_ = -1;  // the go-to last got 0.3 m further at this time ...
  Eigen::Vector2d go_progress_at_ = Eigen::Vector2d::Zero();  // ... from here
  std::vector<Eigen::Vector2d> contour_loop_;  // map frame: where contour following went
  bool target_at_wall_ = false;                // the target is a wall-contact object
  double contour_turned_ = 0;
  double last_theta_ = 0;
  MissionState state_ = MissionState::kIdle;
  MissionState resume_state_ = MissionState::kIdle;
  std::string reason_;
  double started_at_ = 0;
  double last_t_ = 0;
  bool have_anchor_ = false;
  double follow_since_ = -1;
  Pose2 anchor_;
  Pose2 last_pose_;
  double turned_since_anchor_ = 0;  // net heading change while following (+: ccw)
  int objects_left_ = 0;  // free objects circled by mistake and left
  int loops_done_ = 0;
  std::vector<double> loop_times_;
  double anchor_distance_ = 0;
  double progress_distance_ = 0;
  double progress_t_ = 0;
  WheelCommand last_cmd_;
};

}  // namespace irslam::control

#endif  // IRSLAM_CONTROL_MISSION_H_
