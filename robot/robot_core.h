// RobotCore: everything irslamd does between the CAN socket and the API, as pure
// code (no fd, clock or file), and nothing but the orchestration of it: frames
// in -> the motor-controller client (drivers/motor_client.h) -> IR conditioning
// (drivers/ir_conditioner.h) -> SLAM -> the mission -> the safety latches ->
// frames out once per control period. Status and map come out as typed values
// (robot/status.h); their JSON views are the daemon's (daemon/core_json.h). The
// daemon drives it from its event loop; `irslam-sim run` drives the very same
// object in process.
#ifndef IRSLAM_ROBOT_ROBOT_CORE_H_
#define IRSLAM_ROBOT_ROBOT_CORE_H_

#include <linux/can.h>

#include <optional>
#include <string>
#include <vector>

#include "control/mission.h"
#include "control/safety.h"
#include "drivers/ir_calibration.h"
#include "drivers/ir_conditioner.h"
#include "drivers/motor_client.h"
#include "robot/status.h"
#include "slam/slam.h"

namespace irslam::robot {

using control::Debouncer;
using control::ExploreOptions;
using control::Mission;
using control::MissionOptions;
using control::MissionState;
using control::ModelOptions;
using control::WallFollowerOptions;

// Every parameter of the pure core (config file sections in brackets). What only
// the daemon uses (the API socket, the GPIO lines, the bus recording, the state
// directory) is the daemon's own (irslam::DaemonSettings, daemon/daemon_settings.h,
// which holds a CoreOptions beside it).
struct CoreOptions {
  slam::SlamOptions slam;                 // [robot], [sensors].mounts, [slam]
  drivers::IrCalibrationOptions ir;       // [sensors]
  drivers::MotorClientOptions motor;      // [controller]
  WallFollowerOptions wall;               // [wall_follow]
  MissionOptions mission;                 // [mission]
  ExploreOptions explore;                 // [exploration]
  ModelOptions model;                     // [model]
  control::SafetyOptions safety;          // [gpio].debounce_s (the lines are the daemon's)
  // The control period stays the core's: the controllers' gains and limits are
  // tuned to it, and the core (Tick, the loop-stall grace) reasons in periods;
  // the daemon and irslam-sim only schedule Tick at it.
  double period_s = 0.02;                 // [control].period_s
  double heartbeat_period_s = 0.1;        // [controller].heartbeat_period_s
};

CoreOptions DefaultCoreOptions();

class RobotCore {
 public:
  // A tick later than this many periods after the previous one: the loop was stalled.
  static constexpr double kStallPeriods = 2.5;
  explicit RobotCore(CoreOptions options);

  // A frame received from the bus at host robot time now_s.
  void OnFrame(const can_frame& frame, double now_s);
  // One control period at host robot time now_s: returns the frames to send.
  std::vector<can_frame> Tick(double now_s);

  bool Start(double now_s, std::string* why);
  // The mode of the next start: clean (explore, clean, go home) or explore only.
  void SetCleanMode(bool clean) { mission_.SetCleanMode(clean); }
  bool clean_mode() const { return mission_.clean_mode(); }
  void Stop(double now_s);
  // Frames that stop the wheels at once (used on stop and shutdown).
  can_frame StopFrame();

  // The GPIO safety inputs (already corrected for their active level), as edges
  // arrive. An emergency stop acts at once: fault, wheels zero, motor enable
  // dropped; it stays latched until released and start is called again.
  enum class SafetyInput { kEstop, kBumperLeft, kBumperRight };
  void OnSafetyInput(SafetyInput input, bool active, double now_s);
  // A fault found outside the core (the daemon saw a second controller client on
  // the bus): wheels zero, state fault with this reason, latched like the
  // emergency stop until start is called again.
  void LatchFault(double now_s, const std::string& reason);
  // The outputs: motor-driver enable (only while driving is allowed) and the LED.
  bool MotorEnable() const;
  bool StatusLed(double now_s) const;
  bool estop_latched() const { return estop_latched_; }

  CoreStatus Status(double now_s) const;
  MapSnapshot Map() const;

  // The map the next start works in (issue 14): the daemon's saved file or
  // `irslam-sim run --map-in`. What a start (from idle or done) does:
  //  - the core's own live map has a modelled room (a mission ran in this
  //    process since the last fresh start): it continues in it (state model,
  //    then the configured work), the map's agreement checked as below;
  //  - else, with a saved map that has a room: it relocalises in it first
  //    (state relocalize, a fresh local SLAM), then continues in its frame with
  //    its ids: a modelling pass that completes what is incomplete, then the
  //    configured work (cleaning in mode clean). If the map later disagrees
  //    with what the robot sees (it was carried elsewhere), it relocalises again;
  //  - else it explores from nothing (a fresh SLAM).
  // nullopt (the API's start {"fresh": true}) also forgets the live map.
  void SetSavedMap(std::optional<MapSnapshot> map) {
    if (!map) forget_live_ = true;
    saved_map_ = std::move(map);
  }
  const std::optional<MapSnapshot>& saved_map() const { return saved_map_; }
  // What the last accepted Start did, as the list above says (the daemon's log
  // line tells it): nothing yet, a new map, on in the live map, relocalising in
  // the saved map, or on after an emergency stop or a fault was released.
  enum class StartKind { kNone, kNewMap, kLiveMap, kSavedMap, kResumed };
  StartKind last_start() const { return last_start_; }

  MissionState state() const { return mission_.state(); }
  // Cleaning cells finished since the mission started (0 when not cleaning).
  int cleaning_cells_done() const { return mission_.clean().progress().cells_done; }
  const slam::Slam& slam() const { return slam_; }
  // The relocalisation search while the mission relocalises (its hypotheses;
  // slam() is then the local map they place), else nullptr.
  const slam::Relocalizer* relocalizer() const { return mission_.reloc().search(); }
  const drivers::MotorClient& motor() const { return motor_; }
  const drivers::IrConditioner& ir() const { return ir_; }
  const WheelCommand& last_command() const { return last_cmd_; }
  const std::vector<double>& loop_times() const { return mission_.loop_times(); }
  const CoreOptions& options() const { return options_; }

  // A monotonic clock (ns) the shell lends the core to time its planning
  // (tick_profile.h); the core itself never reads a clock.
  void SetWorkClock(control::WorkClock clock) {
    work_clock_ = clock;
    mission_.SetWorkClock(std::move(clock));
  }
  int64_t planning_ns() const { return mission_.go_to().planning_ns(); }
  const control::PathPlanner::Stats& planner_stats() const { return mission_.go_to().planner_stats(); }
  // Ticks at which controller loss was not judged because the loop itself had
  // been stalled (see Tick).
  uint64_t loop_stalls() const { return loop_stalls_; }

 private:
  // The controller is lost or back, the e-stop released: the mission's fault follows.
  void UpdateFault(double now_s);

  CoreOptions options_;
  drivers::MotorClient motor_;
  drivers::IrConditioner ir_;
  slam::Slam slam_;
  Mission mission_;
  Debouncer estop_, bump_left_, bump_right_;
  bool estop_latched_ = false;
  bool fault_latched_ = false;  // LatchFault
  double last_heartbeat_ = -1e9;
  double last_tick_s_ = -1;
  bool graced_last_tick_ = false;  // the last tick did not judge the controller (stalled)
  uint64_t loop_stalls_ = 0;
  WheelCommand last_cmd_;
  std::optional<MapSnapshot> saved_map_;
  bool forget_live_ = false;
  StartKind last_start_ = StartKind::kNone;
  control::WorkClock work_clock_;
  // A fresh SLAM and mission (a start from nothing or in a saved map), the
  // calibration carried over (the saved map's, else the live one's).
  void Renew(const std::optional<slam::CalibrationEstimate>& calibration);
  // Start's bookkeeping: remembers `kind` when the start was accepted.
  bool Started(bool accepted, StartKind kind);
  // The mission committed (or restores the map on an end): the SLAM adopts it.
  void AdoptIfAsked(double now_s);
};

}  // namespace irslam::robot

#endif  // IRSLAM_ROBOT_ROBOT_CORE_H_
