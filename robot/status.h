// What RobotCore reports, as plain values copied out at the time of the call:
// CoreStatus (the API's `status`, without the daemon's own parts) and
// MapSnapshot (the API's `map` and the map files, contracts §4). Their JSON views
// live on the daemon side (daemon/core_json.h); nothing here knows JSON.
#ifndef IRSLAM_ROBOT_STATUS_H_
#define IRSLAM_ROBOT_STATUS_H_

#include <Eigen/Core>
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "control/mission.h"
#include "drivers/ir_conditioner.h"
#include "drivers/motor_client.h"
#include "proto/codec.h"
#include "slam/slam.h"
#include "types/geometry.h"
#include "types/signals.h"

namespace irslam::robot {

struct MissionStatus {
  control::MissionState state = control::MissionState::kIdle;
  std::string reason;
  control::FollowMode behaviour = control::FollowMode::kFind;  // the wall follower's mode
  int target_object = 0;
};

// The estimate, in the map frame.
struct SlamStatus {
  Pose2 pose;
  std::array<double, 3> pose_std{};  // standard deviations of x, y, theta
  double distance_m = 0;             // travelled (odometry)
  size_t lines = 0;
  slam::SlamStats stats;
  // The odometry's calibration (wheel radius and track width scale factors) and
  // whether it is being estimated ([slam.calibration].enabled).
  slam::CalibrationEstimate calibration;
  bool calibration_enabled = false;
};

struct ModelStatus {
  size_t objects = 0;
  int pending = 0;  // incomplete objects exploration still has to visit
};

struct IrStatus {
  RangeScan scan;  // the last conditioned scan
  drivers::IrConditioner::Counts adc{};
};

// The GPIO safety inputs (debounced) and outputs.
struct SafetyStatus {
  bool estop = false;
  bool estop_latched = false;
  bool bumper_left = false;
  bool bumper_right = false;
  bool motor_enable = false;
};

struct ControllerLink {
  bool alive = false;
  std::optional<proto::ControllerStatus> last;  // the last CTRL_STATUS taken
};

// The frames from the controller and what was made of them.
struct FrameCounters {
  drivers::MotorClientCounters motor;
  drivers::IrConditionerCounters ir;
};

// Relocalisation in a saved map (issue 14): while in state relocalize, and
// after the commit (the mission's own record, control/mission.h).
using RelocalizeStatus = control::RelocalizeProgress;

struct CoreStatus {
  double robot_time = 0;
  MissionStatus mission;
  SlamStatus slam;
  ModelStatus model;
  IrStatus ir;
  WheelCommand command;  // the last one sent
  SafetyStatus safety;
  ControllerLink controller;
  FrameCounters frames;
  // Present when cleaning ran since the last start (contracts §7).
  std::optional<control::CleaningProgress> cleaning;
  // Present while relocalising in a saved map and after (contracts §7, issue 14).
  std::optional<RelocalizeStatus> relocalize;
};

// The map as the API serves it (map frame: the first wall along x).
struct MapSnapshot {
  control::MissionState state = control::MissionState::kIdle;
  Pose2 pose;
  Eigen::Matrix3d pose_cov = Eigen::Matrix3d::Zero();
  std::vector<slam::LineFeature> lines;
  control::RoomModel room;
  std::vector<control::ObjectModel> objects;
  std::vector<TimedPose> trajectory;  // the corrected estimate
  std::optional<control::CleaningProgress> cleaning;  // when cleaning ran since the last start
  // The odometry's calibration learnt (kept in the saved map: the next mission
  // starts from it); none when it is not estimated.
  std::optional<slam::CalibrationEstimate> calibration;
  // When this mission started in a saved map and relocalised in it (contracts
  // §7: "relocalized": {"t": T, "hypotheses": N}); the map is then in the saved
  // map's frame with its ids.
  struct Relocalized {
    double t = 0;
    int hypotheses = 0;
  };
  std::optional<Relocalized> relocalized;
};

}  // namespace irslam::robot

#endif  // IRSLAM_ROBOT_STATUS_H_
