// The daemon's loop and lifecycle around a RobotCore: one io_context, the CAN
// bus, GPIO, the fixed-period control loop, the JSON-RPC API, signals (SIGHUP
// reload, SIGTERM/SIGINT shutdown) and systemd notification. Its parts live
// beside it: the RPC method table (daemon/rpc_methods.h, the methods themselves
// in daemon_rpc.cc), the map service (daemon/map_service.h), the notifier
// (daemon/sd_notifier.h), status assembly (daemon_status.cc). Time comes from an
// injected clock, so tests drive Tick() with fake time on a loopback bus.
#ifndef IRSLAM_DAEMON_IRSLAMD_H_
#define IRSLAM_DAEMON_IRSLAMD_H_

#include <algorithm>
#include <boost/asio/io_context.hpp>
#include <boost/asio/signal_set.hpp>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "robot/robot_core.h"
#include "robot/tick_profile.h"
#include "daemon/access.h"
#include "daemon/api_server.h"
#include "daemon/bus_recorder.h"
#include "daemon/core_json.h"
#include "daemon/daemon_settings.h"
#include "daemon/foreign_commander.h"
#include "daemon/map_service.h"
#include "daemon/period_scheduler.h"
#include "daemon/period_timer.h"
#include "daemon/realtime.h"
#include "daemon/rpc_methods.h"
#include "daemon/sd_notifier.h"
#include "daemon/wall_clock.h"
#include "drivers/can_bus.h"
#include "drivers/gpio.h"

namespace irslam {

// The command line's and systemd's part (the config file's is DaemonSettings).
struct DaemonOptions {
  std::string can_iface;
  std::string socket_path = "/run/irslam/irslamd.sock";
  std::string config_path;  // empty: built-in defaults
  double time_scale = 1.0;
  ApiLimits limits;
  std::string notify_socket;   // $NOTIFY_SOCKET ("": no systemd notification)
  uint64_t watchdog_usec = 0;  // systemd's WatchdogSec (0: no watchdog pings)
  // Test aid (--test-hang-at): the control loop hangs for good at this robot time,
  // so the watchdog's stall detection can be tested. Negative: never.
  double test_hang_at_s = -1;
};

class Daemon : public ApiServer::Dispatcher {
 public:
  Daemon(boost::asio::io_context& io, DaemonOptions options, DaemonSettings settings,
         WallClock clock = SystemWallClock());
  ~Daemon() override;
  Daemon(const Daemon&) = delete;
  Daemon& operator=(const Daemon&) = delete;

  // Opens the bus, GPIO and the socket, loads the saved map; false with a one-line *error.
  bool Open(std::string* error);
  // Runs until SIGTERM/SIGINT. Returns the process exit status (non-zero when the
  // final map save failed).
  int Run();

  // One control period at the clock's present time (Run's timer calls it).
  void Tick();
  // SIGHUP: re-reads the config file; a bad one changes nothing (one log line).
  void Reload();
  // The loop thread's scheduling from settings_.realtime_priority (logged on a change).
  void ApplyScheduling(bool log_change);
  // SIGTERM: wheels stopped, outputs off, the final save, everything closed.
  // Returns the exit status.
  int Shutdown();

  // ApiServer::Dispatcher
  void Handle(const rpc::Request& request, const PeerCred& peer, Reply reply) override;
  bool MaySubscribe(const PeerCred& peer) override;
  nlohmann::json StatusNotification() override { return StatusJson(); }

  nlohmann::json StatusJson();
  const robot::TickProfile& tick_profile() const { return profile_; }
  const RpcMethodTable& methods() const { return methods_; }
  const DaemonSettings& settings() const { return settings_; }
  const robot::CoreOptions& core_options() const { return settings_.core; }
  const MapService& maps() const { return maps_; }
  const robot::RobotCore& core() const { return *core_; }
  // The map the next start relocalises in (issue 14): the saved file's at Open,
  // then each finished or stopped mission's; none after start {"fresh": true}
  // or when the map has no room model yet (see UseAsSavedMap).
  const std::optional<robot::MapSnapshot>& saved_map() const { return saved_map_; }

 private:
  double WallNow() const { return SecondsBetween(start_, clock_()); }
  // Whole microseconds of wall time: the bus recorder writes them exactly
  // (daemon/candump_log.h), so irslam-replay gives its core the same times.
  // Wall time since the start in whole microseconds, and robot time from it.
  int64_t NowUs() const {
    return static_cast<int64_t>(std::chrono::duration_cast<std::chrono::microseconds>(clock_() - start_).count());
  }
  // Every robot time the daemon hands out (to the core, the recording) comes from
  // here or FrameRobotTime, which never goes below it: the core and the log see
  // time only go forward.
  double RobotNow() const {
    last_handed_us_ = std::max(last_handed_us_, NowUs());
    return RobotTimeFromLogNs(last_handed_us_ * 1000, options_.time_scale);
  }
  static int64_t Ns(WallTime t);
  // The live core's map: a typed snapshot now, its JSON built when called (on
  // the map writer's thread for a save: issue 15).
  MapEncoder LiveMap() const {
    return [m = std::make_shared<const robot::MapSnapshot>(core_->Map())] { return ToJson(*m); };
  }
  RpcMethodTable MakeMethods();  // daemon_rpc.cc
  nlohmann::json Start(const rpc::Request& req);
  // stop: the wheels at once; the reply when the map's save has an outcome.
  void Stop(const rpc::Request& req, Reply reply);
  nlohmann::json StopReply(const nlohmann::json& id, SaveResult saved);
  void OnMapWritten(SaveResult result);  // the map writer's outcome, on the loop
  bool ArmTimer();  // false (logged) if the kernel refused the timer
  void OnSignal(int signo);
  void WaitSignal();
  // A frame drained from the bus at the start of a period (rx_realtime_s: its
  // kernel receive time, CLOCK_REALTIME seconds; 0 when unknown).
  void OnFrame(const can_frame& f, double rx_realtime_s);
  // The robot time of a frame received rx_realtime_s (see OnFrame): now, less
  // its age in the socket (at most kMaxFrameAgeS), never before a robot time
  // already handed out, in whole microseconds like RobotNow().
  double FrameRobotTime(double rx_realtime_s);
  static constexpr double kMaxFrameAgeS = 0.25;
  // Sends a frame (and records it when [record] is on).
  void SendFrame(const can_frame& f, double now);
  void SendFrames(const std::vector<can_frame>& frames, double now);  // together, now (end of a period)
  void OpenRecorder();
  void OnStateChange(double now);
  // A new core with these settings; the map service keeps the old core's map.
  void ApplyOptions(DaemonSettings fresh);
  void ApplyPendingOptions();
  void OnGpioInput(drivers::Gpio::Input input, bool active);
  // Drives the GPIO outputs (motor enable, LED) from the core's state.
  void ApplyOutputs(double now);
  bool OpenAccess(std::string* error);
  // Keeps map as the one the next start relocalises in, and hands it to the
  // core, when it has a room model (a mission stopped before its first loop
  // leaves a map too partial to relocalise in: the previous one stays).
  // `source` names it in the log.
  void UseAsSavedMap(robot::MapSnapshot map, const char* source);
  // Hands saved_map_ to a new core.
  void GiveSavedMap() { core_->SetSavedMap(saved_map_); }

  boost::asio::io_context& io_;
  DaemonOptions options_;
  DaemonSettings settings_;  // the config file's (the core runs on settings_.core)
  std::optional<DaemonSettings> pending_options_;
  WallClock clock_;
  WallTime start_;
  std::unique_ptr<robot::RobotCore> core_;
  std::optional<robot::MapSnapshot> saved_map_;
  std::unique_ptr<drivers::CanBus> bus_;
  std::unique_ptr<ApiServer> api_;
  std::unique_ptr<drivers::Gpio> gpio_;
  PeriodTimer timer_;
  boost::asio::signal_set signals_;
  PeriodScheduler scheduler_;
  double max_work_s_ = 0;
  ThreadScheduling scheduling_;      // the loop thread's, after ApplyScheduling
  ThreadScheduling api_scheduling_;  // the API thread's (one priority below)
  // Each period's work by phase (issue 15): the frames handled since the last
  // tick (SLAM) plus the tick itself, measured here around the core's calls.
  robot::TickProfile profile_;
  int64_t frames_ns_ = 0;  // OnFrame since the last tick
  double poll_realtime_s_ = 0;  // CLOCK_REALTIME when this period's frames were drained
  int64_t poll_us_ = 0;         // RobotNow()'s microseconds then
  mutable int64_t last_handed_us_ = 0;  // the latest robot time handed out (RobotNow, frames)
  control::MissionState last_state_ = control::MissionState::kIdle;
  int last_cells_done_ = 0;  // cleaning cells finished at the last tick
  bool running_ = false;
  int exit_status_ = 0;
  AccessPolicy access_;
  std::optional<gid_t> socket_gid_;
  SdNotifier notifier_;
  WatchdogPacer watchdog_;
  MapService maps_;
  struct StopWaiter {
    nlohmann::json id;
    Reply reply;
  };
  std::vector<StopWaiter> stop_waiters_;  // stop requests waiting for the map writer
  ForeignCommanderWatch foreign_;
  RpcMethodTable methods_;
  std::unique_ptr<BusRecorder> recorder_;  // [record] enabled
};

}  // namespace irslam

#endif  // IRSLAM_DAEMON_IRSLAMD_H_
