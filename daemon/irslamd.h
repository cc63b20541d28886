// The daemon's thin shell: one io_context, the CAN bus, the fixed-period control
// loop, the JSON-RPC API, signals and systemd notification around a RobotCore.
#ifndef IRSLAM_DAEMON_IRSLAMD_H_
#define IRSLAM_DAEMON_IRSLAMD_H_

#include <boost/asio/io_context.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/asio/steady_timer.hpp>
#include <chrono>
#include <memory>
#include <optional>
#include <string>

#include "robot/robot_core.h"
#include "daemon/access.h"
#include "daemon/api_server.h"
#include "daemon/map_store.h"
#include "daemon/period_scheduler.h"
#include "drivers/can_bus.h"
#include "drivers/gpio.h"

namespace irslam {

struct DaemonOptions {
  std::string can_iface;
  std::string socket_path = "/run/irslam/irslamd.sock";
  std::string config_path;  // empty: built-in defaults
  double time_scale = 1.0;
  ApiLimits limits;
  // Test aid (--test-hang-at): the control loop hangs for good at this robot time,
  // so the watchdog's stall detection can be tested. Negative: never.
  double test_hang_at_s = -1;
};

class Daemon : public ApiServer::Dispatcher {
 public:
  Daemon(boost::asio::io_context& io, DaemonOptions options, robot::CoreOptions core);
  ~Daemon() override;

  // Opens the bus and the socket; false with a one-line *error.
  bool Open(std::string* error);
  // Runs until SIGTERM/SIGINT. Returns the process exit status.
  int Run();

  // ApiServer::Dispatcher
  void Handle(const rpc::Request& request, const PeerCred& peer, Reply reply) override;
  bool MaySubscribe(const PeerCred& peer) override;
  nlohmann::json StatusNotification() override;

 private:
  using Clock = std::chrono::steady_clock;
  double RobotNow() const;
  double WallNow() const;
  void ArmTimer();
  void OnTick();
  void OnSignal(int signo);
  void Reload();
  void Shutdown();
  nlohmann::json StatusJson();
  // The synchronous body of Handle.
  nlohmann::json HandleNow(const rpc::Request& request, const PeerCred& peer);
  void Notify(const std::string& text);
  void OnGpioInput(drivers::Gpio::Input input, bool active);
  // Saves the map (if a mission ran since start) atomically in the state directory.
  void SaveMap(const char* reason);
  // Drives the GPIO outputs (motor enable, LED) from the core's state.
  void ApplyOutputs(double now);

  boost::asio::io_context& io_;
  DaemonOptions options_;
  robot::CoreOptions core_options_;
  std::optional<robot::CoreOptions> pending_options_;
  std::unique_ptr<robot::RobotCore> core_;
  std::unique_ptr<drivers::CanBus> bus_;
  std::unique_ptr<ApiServer> api_;
  std::unique_ptr<drivers::Gpio> gpio_;
  boost::asio::steady_timer timer_;
  boost::asio::signal_set signals_;
  Clock::time_point start_;
  PeriodScheduler scheduler_;
  double max_work_s_ = 0;
  uint64_t watchdog_usec_ = 0;
  double last_watchdog_ = -1e9;
  control::MissionState last_state_ = control::MissionState::kIdle;
  bool running_ = false;
  AccessPolicy access_;
  int notify_fd_ = -1;           // our own non-blocking NOTIFY_SOCKET sender
  uint64_t notify_dropped_ = 0;  // notifications that did not fit
  MapStore store_;
  std::optional<StoredMap> stored_;  // the last map saved or loaded
  bool mission_ran_ = false;         // a mission ran since start: its map is the one to serve/save
  uint64_t saves_ = 0, save_errors_ = 0;
  double last_save_ms_ = 0;
  std::string store_error_;
};

}  // namespace irslam

#endif  // IRSLAM_DAEMON_IRSLAMD_H_
