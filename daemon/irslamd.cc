// irslamd's Daemon (daemon/irslamd.h): opening the bus and the API, the fixed-
// period loop, signals and shutdown. The API's methods are in daemon_rpc.cc, the
// status in daemon_status.cc, the SIGHUP reload in daemon_reload.cc.
#include "daemon/irslamd.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ctime>
#include <thread>
#include <utility>

#include "daemon/config.h"
#include "daemon/core_json.h"
#include "proto/codec.h"

namespace irslam {

namespace {
int64_t PeriodNs(const robot::CoreOptions& core, double time_scale) {
  return static_cast<int64_t>(core.period_s / time_scale * 1e9);
}
}  // namespace

int64_t Daemon::Ns(WallTime t) {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch()).count();
}

Daemon::Daemon(boost::asio::io_context& io, DaemonOptions options, DaemonSettings settings, WallClock clock)
    : io_(io),
      options_(std::move(options)),
      settings_(std::move(settings)),
      clock_(std::move(clock)),
      start_(clock_()),
      core_(std::make_unique<robot::RobotCore>(settings_.core)),
      timer_(io),
      signals_(io, SIGINT, SIGTERM, SIGHUP),
      scheduler_(PeriodNs(settings_.core, options_.time_scale), Ns(start_)),
      notifier_(options_.notify_socket),
      watchdog_(options_.watchdog_usec),
      maps_(settings_.state_dir, clock_, MapService::kDefaultMinIntervalS, &io),
      methods_(MakeMethods()) {
  maps_.set_written([this](SaveResult r) { OnMapWritten(r); });
  core_->SetWorkClock([this] { return Ns(clock_()); });
}

Daemon::~Daemon() = default;

bool Daemon::Open(std::string* error) {
  drivers::CanBusOptions bus_options;
  bus_options.iface = options_.can_iface;
  // The wheel-command and heartbeat ids too: only another commander sends them.
  bus_options.rx_ids = {proto::kControllerStatusId, proto::kEncoderId, proto::kIrAId, proto::kIrBId,
                        proto::kWheelCmdId, proto::kDaemonHeartbeatId};
  bus_ = drivers::OpenCanBus(io_, bus_options, error);
  if (!bus_) return false;
  maps_.Load();  // the map saved by the previous run (a bad file is moved aside, never loaded)
  // The next start relocalises in it (issue 14). A file that checks out but
  // does not make a map is moved aside too; the daemon starts without it.
  if (maps_.stored()) {
    robot::MapSnapshot saved;
    std::string why;
    if (MapFromJson(maps_.stored()->map, &saved, &why)) {
      UseAsSavedMap(std::move(saved), "the saved map");
    } else {
      std::fprintf(stderr, "<3>irslamd: %s\n", maps_.SetAside(why).c_str());
    }
  }
  // Its odometry calibration, if it kept one: the core starts from it (nothing
  // has reached the core yet, so it is simply made again with it).
  if (maps_.stored()) {
    if (const auto c = CalibrationFromMap(maps_.stored()->map)) {
      settings_.core.slam.initial_calibration = c;
      core_ = std::make_unique<robot::RobotCore>(settings_.core);
      GiveSavedMap();
      std::fprintf(stderr, "<6>irslamd: odometry calibration from the saved map: wheel radius scale %.5f/%.5f, "
                   "track width scale %.5f\n", c->value.left, c->value.right, c->value.base);
    }
  }
  // A configured safety line that cannot be had is an error, never ignored.
  gpio_ = drivers::Gpio::Open(io_, settings_.gpio, error);
  if (!gpio_) return false;
  if (!OpenAccess(error)) return false;
  api_ = std::make_unique<ApiServer>(io_, options_.socket_path, options_.limits, this);
  if (!api_->Listen(error, socket_gid_)) return false;
  // Drained once per period, at the start of Tick (one wakeup per period, not
  // one per frame: issue 15's CPU budget); each frame keeps its receive time.
  bus_->StartPolled([this](const can_frame& f, double rx) { OnFrame(f, rx); });
  gpio_->Start([this](drivers::Gpio::Input in, bool active) { OnGpioInput(in, active); });
  return true;
}

void Daemon::UseAsSavedMap(robot::MapSnapshot map, const char* source) {
  if (!map.room.box) {
    std::fprintf(stderr, "<5>irslamd: %s has no room model yet (%zu lines): the next start does not relocalise in it%s\n",
                 source, map.lines.size(), saved_map_ ? " but in the previous one" : "");
    return;
  }
  std::fprintf(stderr, "<6>irslamd: the next start relocalises in %s (%zu lines, %zu objects)\n", source,
               map.lines.size(), map.objects.size());
  saved_map_ = std::move(map);
  GiveSavedMap();
}

bool Daemon::OpenAccess(std::string* error) {
  const auto& a = settings_.api;
  access_.daemon_uid = ::getuid();
  const std::pair<const std::string*, std::optional<gid_t>*> groups[] = {
      {&a.socket_group, &socket_gid_}, {&a.read_group, &access_.read_gid}, {&a.control_group, &access_.control_gid}};
  for (const auto& g : groups) {
    if (g.first->empty()) continue;
    *g.second = GroupId(*g.first, error);
    if (!*g.second) return false;
  }
  return true;
}

void Daemon::SendFrame(const can_frame& f, double now) {
  if (!bus_) return;
  bus_->Send(f);
  if (recorder_) recorder_->Record(f, now);
}

void Daemon::SendFrames(const std::vector<can_frame>& frames, double now) {
  if (!bus_) return;
  bus_->SendNow(frames);
  if (recorder_) {
    for (const can_frame& f : frames) recorder_->Record(f, now);
  }
}

void Daemon::OpenRecorder() {
  if (!settings_.record.enabled || !bus_) return;
  timespec ts{};
  ::clock_gettime(CLOCK_REALTIME, &ts);
  // The origin on a whole microsecond: every stamp is then origin + whole microseconds.
  const RecordHeader header{static_cast<int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec / 1000 * 1000,
                            options_.time_scale, settings_.core.period_s};
  const std::string iface = options_.can_iface.rfind("unix:", 0) == 0 ? "loopback" : options_.can_iface;
  recorder_ = std::make_unique<BusRecorder>(settings_.state_dir, settings_.record, header, iface);
  std::string error;
  if (!recorder_->Open(&error)) {
    std::fprintf(stderr, "<3>irslamd: record: %s: not recording\n", error.c_str());
    recorder_.reset();
    return;
  }
  std::fprintf(stderr, "<6>irslamd: recording the bus to %s\n", recorder_->stats().path.c_str());
}

double Daemon::FrameRobotTime(double rx_realtime_s) {
  int64_t us = poll_us_;
  if (rx_realtime_s > 0) {
    const double age = std::clamp(poll_realtime_s_ - rx_realtime_s, 0.0, kMaxFrameAgeS);
    us -= std::llround(age * 1e6);
  }
  us = std::max(us, last_handed_us_);
  last_handed_us_ = us;
  return RobotTimeFromLogNs(us * 1000, options_.time_scale);
}

void Daemon::OnFrame(const can_frame& f, double rx_realtime_s) {
  const double now = FrameRobotTime(rx_realtime_s);  // one time for the core and the recording
  if (recorder_) recorder_->Record(f, now);
  if (!ForeignCommanderWatch::IsCommanderFrame(f)) {
    const int64_t t0 = Ns(clock_());
    core_->OnFrame(f, now);
    frames_ns_ += Ns(clock_()) - t0;
    return;
  }
  if (foreign_.OnFrame(WallNow())) {
    // Never fight over the wheels: stop and fault until it is gone and start is called.
    core_->LatchFault(RobotNow(), kForeignCommanderReason);
    SendFrame(core_->StopFrame(), RobotNow());
    ApplyOutputs(RobotNow());
    std::fprintf(stderr, "<2>irslamd: %s (CAN id 0x%03x): wheels stopped, mission in fault\n",
                 kForeignCommanderReason, f.can_id & CAN_SFF_MASK);
  }
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
    SendFrame(core_->StopFrame(), now);
    ApplyOutputs(now);
    std::fprintf(stderr, "<2>irslamd: emergency stop pressed: wheels stopped, motor driver disabled\n");
  }
}

void Daemon::ApplyOutputs(double now) {
  if (!gpio_) return;
  gpio_->SetMotorEnable(running_ && core_->MotorEnable());
  gpio_->SetLed(core_->StatusLed(now));
}

int Daemon::Run() {
  running_ = true;
  WaitSignal();
  start_ = clock_();
  scheduler_ = PeriodScheduler(scheduler_.period_ns(), Ns(start_));
  OpenRecorder();
  ApplyScheduling(/*log_change=*/false);  // after the threads it starts: they keep normal scheduling
  if (!ArmTimer()) {
    Shutdown();
    return 1;
  }
  std::fprintf(stderr, "<6>irslamd: ready can=%s socket=%s period=%.3fs time_scale=%g scheduling=%s\n",
               bus_->name().c_str(), options_.socket_path.c_str(), settings_.core.period_s, options_.time_scale,
               scheduling_.Describe(settings_.realtime_priority).c_str());
  notifier_.Send("READY=1\nSTATUS=state=idle");
  io_.run();
  return exit_status_;
}

void Daemon::ApplyScheduling(bool log_change) {
  const int loop = settings_.realtime_priority;
  const int api = ApiThreadPriority(loop);
  const std::string before = scheduling_.Describe(loop) + api_scheduling_.Describe(api);
  scheduling_ = SetLoopScheduling(loop);
  pthread_t api_thread;
  if (api_ && api_->ApiThread(&api_thread)) api_scheduling_ = SetThreadScheduling(api_thread, api);
  if (!scheduling_.error.empty() || !api_scheduling_.error.empty()) {
    std::fprintf(stderr,
                 "<4>irslamd: the control loop keeps normal scheduling: SCHED_FIFO %d refused (%s); "
                 "set LimitRTPRIO= in the unit or control.realtime_priority = 0\n",
                 loop, (scheduling_.error.empty() ? api_scheduling_.error : scheduling_.error).c_str());
  } else if (log_change && scheduling_.Describe(loop) + api_scheduling_.Describe(api) != before) {
    std::fprintf(stderr, "<5>irslamd: scheduling: control loop %s, API thread %s\n",
                 scheduling_.Describe(loop).c_str(), api_scheduling_.Describe(api).c_str());
  }
}

bool Daemon::ArmTimer() {
  std::string error;
  if (timer_.Start(scheduler_.deadline_ns(), scheduler_.period_ns(), [this] { if (running_) Tick(); }, &error)) {
    return true;
  }
  std::fprintf(stderr, "<3>irslamd: cannot start the control period's timer: %s\n", error.c_str());
  return false;
}

void Daemon::Tick() {
  using robot::TickPhase;
  const WallTime woke = clock_();
  scheduler_.OnWake(Ns(woke));
  if (api_) api_->NewPeriod();
  // This period's frames, each at its receive time, before the tick.
  timespec rt{};
  ::clock_gettime(CLOCK_REALTIME, &rt);
  poll_realtime_s_ = static_cast<double>(rt.tv_sec) + 1e-9 * static_cast<double>(rt.tv_nsec);
  poll_us_ = NowUs();
  if (bus_) bus_->Poll();
  const double now = RobotNow();
  if (options_.test_hang_at_s >= 0 && now >= options_.test_hang_at_s) {
    std::fprintf(stderr, "<3>irslamd: --test-hang-at: the control loop hangs now (a test of the watchdog)\n");
    for (;;) std::this_thread::sleep_for(std::chrono::seconds(1));
  }
  robot::TickWork work;
  work[TickPhase::kSlam] = std::exchange(frames_ns_, 0);
  const int64_t planned0 = core_->planning_ns();
  const int64_t t_core = Ns(clock_());
  std::vector<can_frame> out = core_->Tick(now);
  const int64_t t_core_end = Ns(clock_());
  work[TickPhase::kPlanning] = core_->planning_ns() - planned0;
  work[TickPhase::kMission] = t_core_end - t_core - work[TickPhase::kPlanning];
  SendFrames(out, now);
  ApplyOutputs(now);
  const int64_t t_map = Ns(clock_());
  OnStateChange(now);  // the model's save: built and handed to the writer
  maps_.Poll([this] { return LiveMap(); });
  const int64_t t_map_end = Ns(clock_());
  work[TickPhase::kMapSave] = t_map_end - t_map;
  // The watchdog is fed from the loop itself, so a stalled loop is noticed.
  if (watchdog_.Due(WallNow())) notifier_.Send("WATCHDOG=1");
  const WallTime done = clock_();
  work[TickPhase::kOther] = (Ns(done) - Ns(woke)) - (t_core_end - t_core) - (t_map_end - t_map);
  profile_.Add(work, now);
  max_work_s_ = std::max(max_work_s_, SecondsBetween(woke, done));
}

void Daemon::OnStateChange(double now) {
  // Each finished cleaning cell is saved (rate-limited like every save), so the
  // progress survives a crash of the daemon (issue 13).
  const int cells_done = core_->cleaning_cells_done();
  if (cells_done > last_cells_done_) maps_.Save("cell", [this] { return LiveMap(); });
  last_cells_done_ = cells_done;
  if (core_->state() == last_state_) return;
  // Each model completion is saved (the model step just ended).
  if (last_state_ == control::MissionState::kModel) maps_.Save("model", [this] { return LiveMap(); });
  const auto ended = [](control::MissionState s) {
    return s == control::MissionState::kIdle || s == control::MissionState::kDone;
  };
  // A mission finished or stopped (its map saved): the next start relocalises in it.
  if (ended(core_->state()) && !ended(last_state_) && maps_.has_live_map()) {
    UseAsSavedMap(core_->Map(), "this mission's map");
  }
  last_state_ = core_->state();
  std::fprintf(stderr, "<6>irslamd: state=%s reason=\"%s\"\n", control::ToString(last_state_),
               core_->Status(now).mission.reason.c_str());
  notifier_.Send(std::string("STATUS=state=") + control::ToString(last_state_));
  // A config that came during the mission: the new core hears the controller
  // before the next start.
  ApplyPendingOptions();
}

void Daemon::WaitSignal() {
  signals_.async_wait([this](const boost::system::error_code& ec, int signo) {
    if (!ec) OnSignal(signo);
  });
}

void Daemon::OnSignal(int signo) {
  if (signo == SIGHUP) {
    Reload();
    WaitSignal();
    return;
  }
  std::fprintf(stderr, "<6>irslamd: signal %d: stopping the wheels and exiting\n", signo);
  Shutdown();
}

int Daemon::Shutdown() {
  notifier_.Send("STOPPING=1");
  running_ = false;
  const double now = RobotNow();
  core_->Stop(now);  // not noted for the replay: it ends in the mission's state
  SendFrame(core_->StopFrame(), now);
  if (gpio_) gpio_->Close();  // motor driver disabled, LED off
  // Not in a tick: waits for the write in flight (a stop waiting for it is
  // answered), then writes the final map synchronously.
  if (maps_.Flush("shutdown", [this] { return LiveMap(); }) == SaveResult::kFailed) {
    std::fprintf(stderr, "<3>irslamd: the final map save failed: exit status 1\n");
    exit_status_ = 1;
  }
  timer_.Cancel();
  signals_.cancel();
  if (api_) api_->Close();
  if (bus_) bus_->Close();
  io_.stop();
  return exit_status_;
}

void Daemon::ApplyOptions(DaemonSettings fresh) {
  // (The debounce time, fresh.core.safety, applies at once with the new core.)
  if (!fresh.gpio.SameLines(settings_.gpio)) {
    std::fprintf(stderr, "<4>irslamd: [gpio] lines are opened at start: the change applies after a restart\n");
    fresh.gpio = settings_.gpio;
  }
  // The odometry calibration carries over: what the old core learnt if a mission
  // ran on it, else what it started from.
  fresh.core.slam.initial_calibration = maps_.has_live_map() && settings_.core.slam.calibration.enabled
                                            ? std::optional(core_->slam().calibration())
                                            : settings_.core.slam.initial_calibration;
  maps_.OnCoreReplaced(LiveMap());  // the old core's map is kept (and saved if it was not)
  settings_ = fresh;
  core_ = std::make_unique<robot::RobotCore>(fresh.core);
  core_->SetWorkClock([this] { return Ns(clock_()); });
  GiveSavedMap();
  if (foreign_.Present(WallNow())) core_->LatchFault(RobotNow(), kForeignCommanderReason);
  if (gpio_) gpio_->Replay();  // the new core learns the inputs' present levels
  scheduler_ = PeriodScheduler(PeriodNs(fresh.core, options_.time_scale), Ns(clock_()));
  ApplyScheduling(/*log_change=*/true);
}

bool Daemon::MaySubscribe(const PeerCred& peer) {
  return methods_.Allowed(access_, peer, methods_.Needs("subscribe"));
}

void Daemon::Handle(const rpc::Request& req, const PeerCred& peer, Reply reply) {
  if (req.method == "stop" && methods_.Allowed(access_, peer, methods_.Needs("stop"))) {
    Stop(req, std::move(reply));
    return;
  }
  reply(methods_.Handle(req, peer, access_));
}

}  // namespace irslam
