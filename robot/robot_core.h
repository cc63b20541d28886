// RobotCore: everything irslamd does between the CAN socket and the API, as pure
// code. Frames in (with the host's robot time), frames out once per control
// period, status and map as JSON values. The daemon drives it from its event
// loop; `irslam-sim run` drives the very same object in process.
#ifndef IRSLAM_ROBOT_ROBOT_CORE_H_
#define IRSLAM_ROBOT_ROBOT_CORE_H_

#include <linux/can.h>

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "control/mission.h"
#include "control/safety.h"
#include "drivers/ir_calibration.h"
#include "drivers/motor_client.h"
#include "slam/slam.h"

namespace irslam::robot {

using control::Debouncer;
using control::ExploreOptions;
using control::GpioSettings;
using control::Mission;
using control::MissionOptions;
using control::MissionState;
using control::ModelOptions;
using control::WallFollowerOptions;

// The control socket's settings (config section [api]; used by irslamd only).
struct ApiSettings {
  std::string socket_group;    // chgrp the socket to this group ("": the daemon's)
  std::string read_group;      // may call status/map/subscribe ("": anyone who can connect)
  std::string control_group;   // may call start/stop too ("": anyone who can connect)
  int max_clients = 16;
  int max_line_bytes = 64 * 1024;
  double idle_timeout_s = 300;
  int max_pending_bytes = 1 << 20;
};

// Every parameter of the robot software (config file sections in brackets).
struct CoreOptions {
  slam::SlamOptions slam;                 // [robot], [sensors].mounts, [slam]
  drivers::IrCalibrationOptions ir;       // [sensors]
  drivers::MotorClientOptions motor;      // [controller]
  WallFollowerOptions wall;               // [wall_follow]
  MissionOptions mission;                 // [mission]
  ExploreOptions explore;                 // [exploration]
  ModelOptions model;                     // [model]
  double period_s = 0.02;                 // [control].period_s
  double heartbeat_period_s = 0.1;        // [controller].heartbeat_period_s
  ApiSettings api;                        // [api]
  GpioSettings gpio;                      // [gpio]
  std::string state_dir = "/var/lib/irslam";  // [state].dir: the saved map (irslamd only)
};

CoreOptions DefaultCoreOptions();

class RobotCore {
 public:
  explicit RobotCore(CoreOptions options);

  // A frame received from the bus at host robot time now_s.
  void OnFrame(const can_frame& frame, double now_s);
  // One control period at host robot time now_s: returns the frames to send.
  std::vector<can_frame> Tick(double now_s);

  bool Start(double now_s, std::string* why);
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

  nlohmann::json Status(double now_s) const;
  nlohmann::json Map() const;

  MissionState state() const { return mission_.state(); }
  const slam::Slam& slam() const { return slam_; }
  const drivers::MotorClient& motor() const { return motor_; }
  const WheelCommand& last_command() const { return last_cmd_; }
  const std::vector<double>& loop_times() const { return mission_.loop_times(); }
  const CoreOptions& options() const { return options_; }

 private:
  CoreOptions options_;
  drivers::MotorClient motor_;
  drivers::IrCalibration calibration_;
  slam::Slam slam_;
  Mission mission_;
  RangeScan scan_;
  std::array<uint16_t, kNumIrSensors> last_adc_{};
  std::array<int, kNumIrSensors> same_adc_{};  // samples in a row with the same raw value
  uint64_t ir_out_of_range_ = 0, ir_stuck_ = 0;
  uint8_t bumpers_ = 0;       // from CTRL_STATUS, confirmed by two frames in a row
  uint8_t last_status_bumpers_ = 0, bumpers_before_ = 0;
  uint64_t bumper_unconfirmed_ = 0;
  Debouncer estop_, bump_left_, bump_right_;
  bool estop_latched_ = false;
  bool fault_latched_ = false;  // LatchFault
  double last_heartbeat_ = -1e9;
  WheelCommand last_cmd_;
};

}  // namespace irslam::robot

#endif  // IRSLAM_ROBOT_ROBOT_CORE_H_
