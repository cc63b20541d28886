#include "daemon/irslamd.h"

#include <systemd/sd-daemon.h>

#include <unistd.h>

#include <sys/socket.h>
#include <sys/un.h>

#include <cstddef>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <thread>

#include "daemon/config.h"
#include "daemon/core_json.h"
#include "proto/codec.h"

namespace irslam {

namespace {
int64_t Ns(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch()).count();
}
}  // namespace

Daemon::Daemon(boost::asio::io_context& io, DaemonOptions options, robot::CoreOptions core)
    : io_(io),
      options_(std::move(options)),
      core_options_(core),
      core_(std::make_unique<robot::RobotCore>(core)),
      timer_(io),
      signals_(io, SIGINT, SIGTERM, SIGHUP),
      start_(Clock::now()),
      scheduler_(static_cast<int64_t>(core.period_s / options_.time_scale * 1e9), Ns(start_)),
      store_(core.state_dir) {}

Daemon::~Daemon() {
  if (notify_fd_ >= 0) ::close(notify_fd_);
}

double Daemon::WallNow() const {
  return std::chrono::duration<double>(Clock::now() - start_).count();
}

double Daemon::RobotNow() const { return WallNow() * options_.time_scale; }

bool Daemon::Open(std::string* error) {
  drivers::CanBusOptions bus_options;
  bus_options.iface = options_.can_iface;
  bus_options.rx_ids = {proto::kControllerStatusId, proto::kEncoderId, proto::kIrAId,
                        proto::kIrBId};
  bus_ = drivers::OpenCanBus(io_, bus_options, error);
  if (!bus_) return false;
  // The map saved by the previous run (a bad file is moved aside, never loaded).
  stored_ = store_.Load(&store_error_);
  if (!store_error_.empty()) std::fprintf(stderr, "<3>irslamd: %s\n", store_error_.c_str());
  if (stored_) {
    std::fprintf(stderr, "<6>irslamd: map loaded from %s (save %llu, %s, %zu lines)\n", store_.path().c_str(),
                 static_cast<unsigned long long>(stored_->seq), stored_->reason.c_str(),
                 stored_->map.value("lines", nlohmann::json::array()).size());
  }
  // A configured safety line that cannot be had is an error, never ignored.
  gpio_ = drivers::Gpio::Open(io_, core_options_.gpio, error);
  if (!gpio_) return false;
  const auto& a = core_options_.api;
  access_.daemon_uid = ::getuid();
  std::optional<gid_t> socket_gid;
  for (const auto& [name, out] : {std::pair<const std::string*, std::optional<gid_t>*>{&a.socket_group, &socket_gid},
                                  {&a.read_group, &access_.read_gid},
                                  {&a.control_group, &access_.control_gid}}) {
    if (name->empty()) continue;
    *out = GroupId(*name, error);
    if (!*out) return false;
  }
  api_ = std::make_unique<ApiServer>(io_, options_.socket_path, options_.limits, this);
  if (!api_->Listen(error)) return false;
  if (socket_gid && ::chown(options_.socket_path.c_str(), static_cast<uid_t>(-1), *socket_gid) != 0) {
    *error = "api: cannot give " + options_.socket_path + " to group " + a.socket_group;
    return false;
  }
  bus_->Start([this](const can_frame& f, double) { core_->OnFrame(f, RobotNow()); });
  gpio_->Start([this](drivers::Gpio::Input in, bool active) { OnGpioInput(in, active); });
  return true;
}

void Daemon::OnGpioInput(drivers::Gpio::Input input, bool active) {
  using In = drivers::Gpio::Input;
  using Safety = robot::RobotCore::SafetyInput;
  const double now = RobotNow();
  const bool was_latched = core_->estop_latched();
  core_->OnSafetyInput(input == In::kEstop        ? Safety::kEstop
                       : input == In::kBumperLeft ? Safety::kBumperLeft
                                                  : Safety::kBumperRight,
                       active, now);
  if (core_->estop_latched() && !was_latched) {
    // At once, not at the next period: wheels zero and the driver disabled.
    if (bus_) bus_->Send(core_->StopFrame());
    ApplyOutputs(now);
    std::fprintf(stderr, "<2>irslamd: emergency stop pressed: wheels stopped, motor driver disabled\n");
  }
}

void Daemon::SaveMap(const char* reason) {
  if (!mission_ran_) return;  // nothing new: never overwrite the saved map with an empty one
  StoredMap m;
  m.seq = (stored_ ? stored_->seq : 0) + 1;
  m.reason = reason;
  m.map = ToJson(core_->Map());
  const auto t0 = Clock::now();
  std::string error;
  if (store_.Save(m, &error)) {
    ++saves_;
    stored_ = std::move(m);
    store_error_.clear();
  } else {
    ++save_errors_;
    store_error_ = error;
    std::fprintf(stderr, "<3>irslamd: %s\n", error.c_str());
  }
  last_save_ms_ = std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

void Daemon::ApplyOutputs(double now) {
  if (!gpio_) return;
  gpio_->SetMotorEnable(running_ && core_->MotorEnable());
  gpio_->SetLed(core_->StatusLed(now));
}

void Daemon::Notify(const std::string& text) {
  // Not sd_notify(): it sends on a blocking socket, and a notify socket whose
  // queue is full (net.unix.max_dgram_qlen) would stall the control loop. A
  // message that does not fit now is dropped and counted; the next WATCHDOG=1
  // comes half a watchdog interval later.
  const char* path = std::getenv("NOTIFY_SOCKET");
  if (path == nullptr || (path[0] != '/' && path[0] != '@')) return;
  if (notify_fd_ < 0) notify_fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  if (notify_fd_ < 0) return;
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  const size_t n = std::min(std::strlen(path), sizeof addr.sun_path - 1);
  std::memcpy(addr.sun_path, path, n);
  if (addr.sun_path[0] == '@') addr.sun_path[0] = '\0';  // abstract namespace
  const auto len = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + n);
  if (::sendto(notify_fd_, text.data(), text.size(), MSG_DONTWAIT | MSG_NOSIGNAL,
               reinterpret_cast<sockaddr*>(&addr), len) < 0) {
    ++notify_dropped_;
  }
}

int Daemon::Run() {
  running_ = true;
  signals_.async_wait([this](const boost::system::error_code& ec, int signo) {
    if (!ec) OnSignal(signo);
  });
  if (sd_watchdog_enabled(0, &watchdog_usec_) <= 0) watchdog_usec_ = 0;
  start_ = Clock::now();
  scheduler_ = PeriodScheduler(scheduler_.period_ns(), Ns(start_));
  ArmTimer();
  std::fprintf(stderr, "<6>irslamd: ready can=%s socket=%s period=%.3fs time_scale=%g\n",
               bus_->name().c_str(), options_.socket_path.c_str(), core_options_.period_s,
               options_.time_scale);
  Notify("READY=1\nSTATUS=state=idle");
  io_.run();
  return 0;
}

void Daemon::ArmTimer() {
  timer_.expires_at(Clock::time_point(std::chrono::nanoseconds(scheduler_.deadline_ns())));
  timer_.async_wait([this](const boost::system::error_code& ec) {
    if (ec || !running_) return;
    OnTick();
    ArmTimer();
  });
}

void Daemon::OnTick() {
  const auto woke = Clock::now();
  scheduler_.OnWake(Ns(woke));
  const double now = RobotNow();
  if (options_.test_hang_at_s >= 0 && now >= options_.test_hang_at_s) {
    std::fprintf(stderr, "<3>irslamd: --test-hang-at: the control loop hangs now (a test of the watchdog)\n");
    for (;;) std::this_thread::sleep_for(std::chrono::seconds(1));
  }
  for (const can_frame& f : core_->Tick(now)) bus_->Send(f);
  ApplyOutputs(now);
  if (core_->state() != last_state_) {
    // Each model completion is saved (the model step just ended).
    if (last_state_ == control::MissionState::kModel) SaveMap("model");
    last_state_ = core_->state();
    std::fprintf(stderr, "<6>irslamd: state=%s reason=\"%s\"\n", control::ToString(last_state_),
                 core_->Status(now).mission.reason.c_str());
    Notify(std::string("STATUS=state=") + control::ToString(last_state_));
  }
  // The watchdog is fed from the loop itself, so a stalled loop is noticed.
  const double wall = WallNow();
  if (watchdog_usec_ > 0 && wall - last_watchdog_ >= static_cast<double>(watchdog_usec_) * 0.5e-6) {
    last_watchdog_ = wall;
    Notify("WATCHDOG=1");
  }
  max_work_s_ = std::max(max_work_s_, std::chrono::duration<double>(Clock::now() - woke).count());
}

void Daemon::OnSignal(int signo) {
  if (signo == SIGHUP) {
    Reload();
    signals_.async_wait([this](const boost::system::error_code& ec, int s) {
      if (!ec) OnSignal(s);
    });
    return;
  }
  std::fprintf(stderr, "<6>irslamd: signal %d: stopping the wheels and exiting\n", signo);
  Shutdown();
}

void Daemon::Shutdown() {
  Notify("STOPPING=1");
  running_ = false;
  core_->Stop(RobotNow());
  if (bus_) bus_->Send(core_->StopFrame());
  if (gpio_) gpio_->Close();  // motor driver disabled, LED off
  SaveMap("shutdown");
  timer_.cancel();
  signals_.cancel();
  if (api_) api_->Close();
  if (bus_) bus_->Close();
  io_.stop();
}

void Daemon::Reload() {
  if (options_.config_path.empty()) {
    std::fprintf(stderr, "<5>irslamd: SIGHUP: no --config file, nothing to reload\n");
    return;
  }
  robot::CoreOptions fresh = robot::DefaultCoreOptions();
  std::string error;
  if (!LoadConfigFile(options_.config_path, &fresh, &error)) {
    std::fprintf(stderr, "<3>irslamd: reload failed, keeping the running config: %s\n",
                 error.c_str());
    return;
  }
  const auto s = core_->state();
  if (s == control::MissionState::kIdle || s == control::MissionState::kDone) {
    pending_options_.reset();
    if (!fresh.gpio.SameLines(core_options_.gpio)) {
      std::fprintf(stderr, "<4>irslamd: [gpio] lines are opened at start: the change applies after a restart\n");
      const double debounce_s = fresh.gpio.debounce_s;  // this applies at once
      fresh.gpio = core_options_.gpio;
      fresh.gpio.debounce_s = debounce_s;
    }
    core_options_ = fresh;
    auto next = std::make_unique<robot::RobotCore>(fresh);
    core_ = std::move(next);
    if (gpio_) gpio_->Replay();  // the new core learns the inputs' present levels
    scheduler_ = PeriodScheduler(static_cast<int64_t>(fresh.period_s / options_.time_scale * 1e9),
                                 Ns(Clock::now()));
    std::fprintf(stderr, "<5>irslamd: config reloaded from %s\n", options_.config_path.c_str());
  } else {
    pending_options_ = fresh;
    std::fprintf(stderr, "<5>irslamd: config from %s validated; applied when the mission ends\n",
                 options_.config_path.c_str());
  }
}

nlohmann::json Daemon::StatusJson() {
  const double now = RobotNow();
  nlohmann::json s = ToJson(core_->Status(now));
  s["uptime"] = WallNow();
  s["time_scale"] = options_.time_scale;
  s["period"] = {{"target", core_options_.period_s},
                 {"ticks", scheduler_.ticks()},
                 {"overruns", scheduler_.overruns()},
                 {"jitter_mean", scheduler_.mean_late_ns() * 1e-9},
                 {"jitter_max", static_cast<double>(scheduler_.max_late_ns()) * 1e-9},
                 {"jitter_last", static_cast<double>(scheduler_.last_late_ns()) * 1e-9},
                 {"work_max", max_work_s_}};
  const auto& c = bus_->stats();
  s["can"] = {{"iface", bus_->name()},     {"rx", c.rx_frames},
              {"tx", c.tx_frames},         {"rx_dropped", c.rx_dropped},
              {"tx_dropped", c.tx_dropped}, {"filtered", c.filtered},
              {"error_frames", c.error_frames}, {"bus_off", c.bus_off},
              {"link_up", c.link_up},      {"link_down_events", c.link_down_events},
              {"last_error", c.last_error},
              {"last_rx_time", c.last_rx_time},   {"kernel_timestamps", c.kernel_timestamps}};
  const auto& a = api_->stats();
  s["api"] = {{"clients", api_->client_count()}, {"requests", a.requests}, {"errors", a.errors},
              {"dropped_slow", a.dropped_slow}, {"dropped_long_line", a.dropped_long_line},
              {"rejected_full", a.rejected_full}};
  s["config_pending"] = pending_options_.has_value();
  s["notify_dropped"] = notify_dropped_;
  nlohmann::json lines = nlohmann::json::object();
  for (const auto& l : gpio_->lines()) {
    lines[l.role] = {{"chip", l.chip}, {"label", l.label}, {"offset", l.offset}, {"name", l.name},
                     {"output", l.output}, {"active", l.active}};
  }
  s["gpio"] = {{"lines", lines}, {"events", gpio_->events()}};
  s["map_store"] = {{"path", store_.path()},
                    {"seq", stored_ ? stored_->seq : 0},
                    {"saved_map", stored_.has_value()},
                    {"saves", saves_},
                    {"save_errors", save_errors_},
                    {"last_save_ms", last_save_ms_},
                    {"error", store_error_}};
  return s;
}

nlohmann::json Daemon::StatusNotification() { return StatusJson(); }

bool Daemon::MaySubscribe(const PeerCred& peer) {
  return Allowed(access_, peer.uid, PeerGroups(peer.uid, peer.gid), Access::kRead);
}

nlohmann::json Daemon::Handle(const rpc::Request& req, const PeerCred& peer) {
  const double now = RobotNow();
  const bool control = req.method == "start" || req.method == "stop";
  if (!Allowed(access_, peer.uid, PeerGroups(peer.uid, peer.gid), control ? Access::kControl : Access::kRead)) {
    std::fprintf(stderr, "<4>api: denied method=%s uid=%u pid=%d\n", req.method.c_str(),
                 static_cast<unsigned>(peer.uid), static_cast<int>(peer.pid));
    return rpc::MakeError(req.id, rpc::kAccessDenied,
                          "access denied: " + req.method + " needs the " +
                              (control ? "control" : "read") + " group");
  }
  if (req.method == "status") return rpc::MakeResult(req.id, StatusJson());
  if (req.method == "map") {
    // Before any mission of this run: the map saved by the previous one.
    if (!mission_ran_ && stored_) {
      nlohmann::json m = stored_->map;
      m["saved"] = {{"seq", stored_->seq}, {"reason", stored_->reason}, {"path", store_.path()}};
      return rpc::MakeResult(req.id, m);
    }
    return rpc::MakeResult(req.id, ToJson(core_->Map()));
  }
  if (req.method == "start") {
    const auto s = core_->state();
    if (pending_options_ &&
        (s == control::MissionState::kIdle || s == control::MissionState::kDone)) {
      Reload();
    }
    std::string why;
    if (!core_->Start(now, &why)) return rpc::MakeError(req.id, rpc::kRejected, "start rejected: " + why);
    mission_ran_ = true;
    std::fprintf(stderr, "<6>irslamd: mission started\n");
    return rpc::MakeResult(req.id, {{"state", control::ToString(core_->state())}});
  }
  if (req.method == "stop") {
    core_->Stop(now);
    bus_->Send(core_->StopFrame());  // at once, not at the next period
    ApplyOutputs(now);
    SaveMap("stop");
    std::fprintf(stderr, "<6>irslamd: stopped by request\n");
    return rpc::MakeResult(req.id, {{"state", control::ToString(core_->state())}});
  }
  return rpc::MakeError(req.id, rpc::kMethodNotFound, "method not found: " + req.method);
}

}  // namespace irslam
