// irslam-sim: the simulated motor controller and world (contracts.md §2).
//   irslam-sim run   --world W.json [--seed S] [--max-time SECONDS] --map-out map.json --truth-out truth.json
//                    [--map-in MAP.json] [--start X,Y,THETA]
//   irslam-sim run   --world W.json --baseline bounce [--max-time SECONDS] [--map-out R.json] [--svg R.svg]
//   irslam-sim serve --can IFACE --world W.json [--seed S] [--time-scale K] [--truth-out truth.json]
//                    [--realtime-priority N]
#include <pthread.h>

#include <CLI/CLI.hpp>
#include <boost/asio/io_context.hpp>
#include <boost/asio/signal_set.hpp>
#include <boost/asio/steady_timer.hpp>
#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <fstream>
#include <memory>
#include <sstream>

#include "io/file_io.h"
#include "robot/robot_core.h"
#include "daemon/config.h"
#include "daemon/core_json.h"
#include "daemon/map_pgm.h"
#include "daemon/map_svg.h"
#include "daemon/realtime.h"
#include "drivers/can_bus.h"
#include "proto/codec.h"
#include "io/json_text.h"
#include "sim/bounce.h"
#include "sim/coverage.h"
#include "sim/faults.h"
#include "sim/generator.h"
#include "sim/sim_controller.h"
#include "sim/sim_run.h"

namespace irslam::sim {
namespace {

constexpr int kExitUsage = 2;

bool WriteJson(const std::string& path, const nlohmann::json& j) {
  return path.empty() || WriteFileReplacing(path, j.dump(1) + "\n");
}

std::string ReadText(const std::string& path) {
  std::ifstream in(path);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

struct Common {
  std::string world_path;
  std::string config_path;
  std::optional<uint64_t> seed;
  std::string truth_out;
  std::string faults;  // --faults SPEC (sim/faults.h, docs/reliability.md)
  std::string mode;     // run --mode explore|clean ("": the config's mission.mode)
  std::string pgm_out;  // run --pgm FILE.pgm (daemon/map_pgm.h)
  double pgm_res = kDefaultPgmResolutionM;
  std::string map_in;  // run --map-in MAP.json: start from this saved map (issue 14)
  std::string start;   // run --start X,Y,THETA: replaces the world's start pose
};

bool Load(const Common& c, World* world, robot::CoreOptions* core, uint64_t* seed) {
  std::string error;
  auto w = LoadWorldFile(c.world_path, &error);
  if (!w) {
    std::fprintf(stderr, "irslam-sim: %s\n", error.c_str());
    return false;
  }
  *core = robot::DefaultCoreOptions();
  if (!c.config_path.empty() && !LoadCoreConfigFile(c.config_path, core, &error)) {
    std::fprintf(stderr, "irslam-sim: %s\n", error.c_str());
    return false;
  }
  if (!c.mode.empty()) core->mission.mode = c.mode;
  *world = *w;
  *seed = c.seed.value_or(w->seed.value_or(1));
  return true;
}

bool LoadFaults(const Common& c, FaultSpec* spec) {
  std::string error;
  auto f = ParseFaultSpec(c.faults, &error);
  if (!f) {
    std::fprintf(stderr, "irslam-sim: %s\n", error.c_str());
    return false;
  }
  *spec = *f;
  return true;
}

nlohmann::json FaultsJson(const FaultCounters& f) {
  nlohmann::json j = {{"lost", f.lost},         {"corrupted", f.corrupted}, {"duplicated", f.duplicated},
                      {"reordered", f.reordered}, {"delayed", f.delayed},   {"silenced", f.silenced},
                      {"flooded", f.flooded},   {"stuck", f.stuck},         {"glitched", f.glitched}};
  if (f.kidnapped > 0) j["kidnapped"] = f.kidnapped;
  return j;
}

// A saved map: a map file (contracts §4, irslam-sim run --map-out, irslamctl
// map --out) or the daemon's saved file (daemon/map_store.h: the map inside).
std::optional<robot::MapSnapshot> LoadSavedMap(const std::string& path, std::string* why) {
  std::string text;
  if (!ReadRegularFile(path, 64u << 20, &text, why)) return std::nullopt;
  auto j = ParseJsonText(text, why);
  if (!j) return std::nullopt;
  if (j->is_object() && j->contains("format") && (*j)["format"] == "irslam-map") {
    if (!j->contains("map")) {
      *why = "an irslam map file without a map";
      return std::nullopt;
    }
    j = (*j)["map"];
  }
  robot::MapSnapshot map;
  if (!MapFromJson(*j, &map, why)) return std::nullopt;
  return map;
}

// run --start, --map-in and the kidnap targets (sim/sim_run.h RunSetup); false
// after a one-line message.
bool LoadRunSetup(const Common& c, const FaultSpec& faults, World* world, robot::CoreOptions* core,
                  RunSetup* setup) {
  std::string why;
  const double clearance = core->slam.geometry.radius_m;
  if (!c.start.empty()) {
    const auto pose = ParsePoseArg(c.start, &why);
    if (!pose || !FreePose(*world, *pose, clearance, &why)) {
      std::fprintf(stderr, "irslam-sim: --start %s: %s\n", c.start.c_str(), why.c_str());
      return false;
    }
    world->start = *pose;
  }
  for (const FaultSpec::Kidnap& k : faults.kidnap) {
    if (!FreePose(*world, k.to, clearance, &why)) {
      std::fprintf(stderr, "irslam-sim: --faults: kidnap at %g s: %s\n", k.at, why.c_str());
      return false;
    }
  }
  if (!c.map_in.empty()) {
    auto map = LoadSavedMap(c.map_in, &why);
    if (!map) {
      std::fprintf(stderr, "irslam-sim: --map-in %s: %s\n", c.map_in.c_str(), why.c_str());
      return false;
    }
    // Its odometry calibration, as the daemon does with its saved map.
    if (map->calibration) core->slam.initial_calibration = map->calibration;
    setup->saved_map = std::move(map);
  }
  return true;
}

// The CPU time of this thread (ns): what the work costs, without the time the
// host gave to other processes (--tick-clock cpu, for a loaded host).
static int64_t ThreadCpuNs() {
  timespec ts{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

// run's optional logs (an empty path: not asked for): every extracted line
// observation (irslam-weights reads them) and every change of mission state,
// reason or behaviour, with the true and the estimated pose (world frame / map
// frame).
class RunLogs {
 public:
  bool Open(const std::string& lines_out, const std::string& events_out) {
    return OpenOut(lines_out, &lines_file_) && OpenOut(events_out, &events_file_);
  }

  void Record(const InProcessRun& r) {
    if (events_file_.is_open()) RecordEvent(r);
    const auto& s = r.core->slam();
    if (!lines_file_.is_open() || s.stats().windows == windows_seen_) return;
    windows_seen_ = s.stats().windows;
    for (const auto& l : s.last_window_lines()) {
      lines_file_ << nlohmann::json{{"t", r.t},
                                    {"rho", l.rho},
                                    {"theta", l.theta},
                                    {"length", l.length},
                                    {"c_rho_rho", l.cov(0, 0)},
                                    {"c_theta_theta", l.cov(1, 1)},
                                    {"points", l.points}}
                         .dump()
                  << "\n";
    }
  }

 private:
  static bool OpenOut(const std::string& path, std::ofstream* out) {
    if (path.empty()) return true;
    out->open(path);
    if (!*out) std::fprintf(stderr, "irslam-sim: cannot write %s\n", path.c_str());
    return static_cast<bool>(*out);
  }

  void RecordEvent(const InProcessRun& r) {
    const auto st = ToJson(r.core->Status(r.t));
    const std::string key = st["state"].dump() + st["reason"].dump() + st["behaviour"].dump();
    if (key == last_event_) return;
    last_event_ = key;
    const Pose2& p = r.sim->true_pose();
    events_file_ << nlohmann::json{{"t", r.t},
                                   {"state", st["state"]},
                                   {"reason", st["reason"]},
                                   {"behaviour", st["behaviour"]},
                                   {"target_object", st["target_object"]},
                                   {"true_pose", {p.x, p.y, p.theta}},
                                   {"pose", st["pose"]}}
                        .dump()
                 << "\n";
  }

  std::ofstream lines_file_;
  std::ofstream events_file_;
  std::string last_event_;
  int windows_seen_ = 0;
};

// run's result files: the map, the truth, and the optional SVG and PGM; false
// after a one-line message.
bool WriteRunFiles(const Common& c, const InProcessRun& run, const std::string& map_out,
                   const std::string& svg_out) {
  const SimController& sim = *run.sim;
  const robot::RobotCore& core = *run.core;
  if (!WriteJson(map_out, ToJson(core.Map()))) {
    std::fprintf(stderr, "irslam-sim: cannot write %s\n", map_out.c_str());
    return false;
  }
  nlohmann::json truth = sim.Truth();
  if (run.faults) truth["faults"] = FaultsJson(run.faults->counters());
  if (!WriteJson(c.truth_out, truth)) {
    std::fprintf(stderr, "irslam-sim: cannot write %s\n", c.truth_out.c_str());
    return false;
  }
  if (!svg_out.empty()) {
    std::string error;
    auto world_json = ParseJsonText(ReadText(c.world_path), &error);
    std::ofstream svg(svg_out);
    svg << RenderMapSvg(ToJson(core.Map()), sim.Truth(), world_json.value_or(nlohmann::json()));
    if (!svg) {
      std::fprintf(stderr, "irslam-sim: cannot write %s\n", svg_out.c_str());
      return false;
    }
  }
  if (std::string error; !c.pgm_out.empty() && !WritePgmMap(ToJson(core.Map()), c.pgm_out, c.pgm_res, &error)) {
    std::fprintf(stderr, "irslam-sim: %s\n", error.c_str());
    return false;
  }
  return true;
}

// The control loop's work per period (issue 15), this process's clock.
void PrintWorkProfile(const InProcessRun& run) {
  const auto& w = run.profile.work();
  const auto& worst = run.profile.worst();
  std::fprintf(
      stderr,
      "irslam-sim: work per period p50 %.3f ms, p99 %.3f ms, p99.9 %.3f ms, max %.3f ms "
      "(at %.2f s, mostly %s: slam %.3f, mission %.3f, planning %.3f ms); %.0fx real time\n",
      w.Quantile(0.5) * 1e-6, w.Quantile(0.99) * 1e-6, w.Quantile(0.999) * 1e-6, w.max() * 1e-6,
      run.profile.worst_t(), robot::ToString(run.profile.worst_phase()),
      worst[robot::TickPhase::kSlam] * 1e-6, worst[robot::TickPhase::kMission] * 1e-6,
      worst[robot::TickPhase::kPlanning] * 1e-6, run.wall_s > 0 ? run.t / run.wall_s : 0.0);
  std::fprintf(stderr,
               "irslam-sim: largest per phase: slam %.3f ms, mission %.3f ms, planning %.3f ms\n",
               run.profile.phase_max(robot::TickPhase::kSlam) * 1e-6,
               run.profile.phase_max(robot::TickPhase::kMission) * 1e-6,
               run.profile.phase_max(robot::TickPhase::kPlanning) * 1e-6);
  const auto& ps = run.core->planner_stats();
  std::fprintf(stderr,
               "irslam-sim: planner (exploring): %llu plans, %llu searches, %llu failed, %llu pops, the "
               "longest search %llu pops\n",
               static_cast<unsigned long long>(ps.plans), static_cast<unsigned long long>(ps.searches),
               static_cast<unsigned long long>(ps.failed), static_cast<unsigned long long>(ps.pops),
               static_cast<unsigned long long>(ps.max_pops));
}

// run's summary on stderr: the outcome, the work per period, the faults and
// the cleaning.
void PrintRunSummary(const InProcessRun& run, const nlohmann::json& status) {
  const SimController& sim = *run.sim;
  std::fprintf(stderr,
               "irslam-sim: %s after %.1f s robot time, %.1f m driven, %llu collisions, "
               "min clearance %.3f m\n",
               status["state"].get<std::string>().c_str(), run.t, run.core->slam().distance_m(),
               static_cast<unsigned long long>(sim.collisions()), sim.min_clearance());
  PrintWorkProfile(run);
  if (run.faults) {
    std::fprintf(stderr, "irslam-sim: injected %s; irslamd's frame counters: %s\n",
                 FaultsJson(run.faults->counters()).dump().c_str(), status["frames"].dump().c_str());
  }
  if (status.contains("cleaning")) {
    const auto& cl = status["cleaning"];
    std::fprintf(stderr,
                 "irslam-sim: cleaning %s: %d of %d cells, %.2f of %.2f m2 (%.1f %%, estimated), "
                 "%.1f m path, %.2f m2 unreachable, cross-track rms %.3f m\n",
                 cl["state"].get<std::string>().c_str(), cl["cells_done"].get<int>(),
                 cl["cells_total"].get<int>(), cl["covered_m2"].get<double>(),
                 cl["total_m2"].get<double>(), 100 * cl["fraction"].get<double>(),
                 cl["path_m"].get<double>(), cl["unreachable_m2"].get<double>(),
                 cl["cross_track_rms_m"].get<double>());
  }
}

int Run(const Common& c, double max_time, const std::string& map_out, const std::string& svg_out,
        const std::string& lines_out, const std::string& events_out,
        const std::string& tick_clock) {
  World world;
  robot::CoreOptions core_opts;
  uint64_t seed;
  FaultSpec faults;
  RunSetup setup;
  if (!Load(c, &world, &core_opts, &seed) || !LoadFaults(c, &faults) ||
      !LoadRunSetup(c, faults, &world, &core_opts, &setup))
    return kExitUsage;
  // Cleaning has its own time budget after the exploration's.
  if (max_time <= 0) {
    max_time = core_opts.mission.max_time_s +
               (core_opts.mission.mode == "clean" ? core_opts.mission.cleaning.max_time_s : 0);
  }
  RunLogs logs;
  if (!logs.Open(lines_out, events_out)) return 1;
  InProcessRun run = RunInProcess(
      world, core_opts, seed, max_time, [&logs](const InProcessRun& r) { logs.Record(r); },
      faults.any() ? &faults : nullptr,
      tick_clock == "cpu" ? robot::WorkClockNs(ThreadCpuNs) : robot::WorkClockNs(), setup);
  if (!run.error.empty()) {
    std::fprintf(stderr, "irslam-sim: cannot start the mission: %s\n", run.error.c_str());
    return 1;
  }
  if (!WriteRunFiles(c, run, map_out, svg_out)) return 1;
  const auto status = ToJson(run.core->Status(run.t));
  PrintRunSummary(run, status);
  if (run.core->state() != control::MissionState::kDone) {
    std::fprintf(
        stderr, "irslam-sim: mission did not finish: state %s, %s\n",
        status["state"].get<std::string>().c_str(),
        run.t >= max_time ? "--max-time reached" : status["reason"].get<std::string>().c_str());
    return 1;
  }
  return 0;
}

// run --baseline bounce: the random-bounce cleaner (sim/bounce.h) instead of the
// mission, for --max-time of robot time (default: the cleaning budget,
// [cleaning].max_time_s), scored against the truth like planned cleaning
// (sim/coverage.h): the true body disc's sweep of the floor it could reach.
int RunBounceBaseline(const Common& c, double max_time, const std::string& map_out, const std::string& svg_out) {
  World world;
  robot::CoreOptions core_opts;
  uint64_t seed;
  if (!Load(c, &world, &core_opts, &seed)) return kExitUsage;
  if (max_time <= 0) max_time = core_opts.mission.cleaning.max_time_s;
  const auto sim = RunBounce(world, core_opts, seed, max_time);
  const nlohmann::json truth = sim->Truth();
  std::vector<TimedPose> traj;
  for (const auto& p : truth["trajectory"]) traj.push_back({p[0], {p[1], p[2], p[3]}});
  const double radius = core_opts.slam.geometry.radius_m;
  std::vector<std::pair<double, double>> curve;
  const CoverageScore cov = ScoreCoverage(world, radius, traj, 0, max_time, 0.02, &curve);
  // The map file's cleaning block (contracts §7) with the true numbers, so what
  // reads a cleaning run's reads the baseline's; no lines, no cells.
  const nlohmann::json result = {
      {"baseline", "bounce"},
      {"seed", seed},
      {"state", "done"},
      {"trajectory", truth["trajectory"]},
      {"cleaning",
       {{"state", "done"}, {"started_t", 0.0}, {"finished_t", max_time}, {"covered_m2", cov.covered_m2},
        {"total_m2", cov.reachable_m2}, {"fraction", cov.fraction}, {"path_m", cov.path_m},
        {"width_m", 2 * radius}, {"cells", nlohmann::json::array()}, {"curve", curve}}}};
  if (!WriteJson(map_out, result) || !WriteJson(c.truth_out, truth)) {
    std::fprintf(stderr, "irslam-sim: cannot write %s\n", (map_out.empty() ? c.truth_out : map_out).c_str());
    return 1;
  }
  if (!svg_out.empty()) {
    std::string error;
    const auto world_json = ParseJsonText(ReadText(c.world_path), &error);
    if (!WriteFileReplacing(svg_out, RenderMapSvg(result, truth, world_json.value_or(nlohmann::json())))) {
      std::fprintf(stderr, "irslam-sim: cannot write %s\n", svg_out.c_str());
      return 1;
    }
  }
  std::fprintf(stderr,
               "irslam-sim: baseline bounce: %.1f s robot time, covered %.2f of %.2f m2 reachable (%.1f %%, true), "
               "%.1f m path, %llu collisions\n",
               max_time, cov.covered_m2, cov.reachable_m2, 100 * cov.fraction, cov.path_m,
               static_cast<unsigned long long>(sim->collisions()));
  return 0;
}

// serve's tick: the simulated controller advances every 1 ms of wall time.
// A tick that comes later than kStallS after the one before is a stall: the
// host did not run the simulator (the robot time it missed is then simulated
// in one burst, under the last wheel command: a latency a real controller,
// which is its own microcontroller, never has). Stalls are counted and the
// longest is reported, so a test rig can tell a starved simulator from the
// robot's own behaviour.
constexpr double kStallS = 0.010;

// --realtime-priority: SCHED_FIFO for the simulator's thread (sched(7)), so
// that a loaded test host cannot starve the simulated hardware. Refused (no
// CAP_SYS_NICE, RLIMIT_RTPRIO too low) it says why and keeps normal scheduling.
// The daemon's own call (daemon/realtime.h): SCHED_RESET_ON_FORK included.
void SetRealtime(int priority) {
  if (priority <= 0) return;
  const ThreadScheduling s = SetThreadScheduling(pthread_self(), priority);
  if (!s.realtime) std::fprintf(stderr, "irslam-sim: scheduling %s\n", s.Describe(priority).c_str());
}

int Serve(const Common& c, const std::string& iface, double time_scale, int realtime_priority) {
  World world;
  robot::CoreOptions core_opts;
  uint64_t seed;
  FaultSpec faults;
  if (!Load(c, &world, &core_opts, &seed) || !LoadFaults(c, &faults)) return kExitUsage;
  SimController sim(world, SimOptionsFrom(core_opts), seed);
  FaultInjector injector(faults, seed);

  boost::asio::io_context io;
  std::string error;
  auto bus = drivers::OpenCanBus(io, {iface, {proto::kWheelCmdId, proto::kDaemonHeartbeatId}},
                                 &error);
  if (!bus) {
    std::fprintf(stderr, "irslam-sim: %s\n", error.c_str());
    return 1;
  }
  SetRealtime(realtime_priority);
  bus->Start([&](const can_frame& f, double) { sim.HandleFrame(f); });

  using Clock = std::chrono::steady_clock;
  const auto start = Clock::now();
  const auto tick = std::chrono::microseconds(1000);
  boost::asio::steady_timer timer(io);
  timer.expires_at(start + tick);
  std::vector<can_frame> frames, out;
  double last_wall = 0;
  uint64_t stalls = 0;
  double longest_stall = 0;  // wall seconds between two ticks
  std::function<void(const boost::system::error_code&)> on_tick =
      [&](const boost::system::error_code& ec) {
        if (ec) return;
        const double wall = std::chrono::duration<double>(Clock::now() - start).count();
        const double gap = wall - last_wall;
        if (gap > kStallS && ++stalls <= 10) {
          std::fprintf(stderr, "irslam-sim: stalled %.1f ms wall at %.2f s robot time\n", 1000 * gap,
                       sim.time());
        }
        longest_stall = std::max(longest_stall, gap);
        frames.clear();
        out.clear();
        while (const auto to = injector.TakeKidnap(wall * time_scale)) sim.Teleport(*to);
        sim.AdvanceTo(wall * time_scale, &frames);
        injector.Process(sim.time(), frames, &out);
        injector.Flood(sim.time(), gap, &out);
        last_wall = wall;
        for (const can_frame& f : out) bus->Send(f);
        timer.expires_at(timer.expiry() + tick);
        if (timer.expiry() < Clock::now()) timer.expires_at(Clock::now() + tick);
        timer.async_wait(on_tick);
      };
  timer.async_wait(on_tick);

  boost::asio::signal_set signals(io, SIGINT, SIGTERM);
  signals.async_wait([&](const boost::system::error_code&, int) {
    timer.cancel();
    bus->Close();
    io.stop();
  });
  std::fprintf(stderr, "irslam-sim: serving world '%s' on %s at time scale %g\n",
               world.name.c_str(), bus->name().c_str(), time_scale);
  if (faults.any()) std::fprintf(stderr, "irslam-sim: injecting faults: %s\n", c.faults.c_str());
  io.run();
  nlohmann::json truth = sim.Truth();
  if (faults.any()) truth["faults"] = FaultsJson(injector.counters());
  truth["serve"] = {{"time_scale", time_scale}, {"stalls", stalls}, {"longest_stall_s", longest_stall}};
  if (!WriteJson(c.truth_out, truth)) {
    std::fprintf(stderr, "irslam-sim: cannot write %s\n", c.truth_out.c_str());
    return 1;
  }
  std::fprintf(stderr,
               "irslam-sim: stopped at %.1f s robot time, %llu collisions; %llu stalls over %.0f ms, "
               "longest %.1f ms wall (%.0f ms robot)\n",
               sim.time(), static_cast<unsigned long long>(sim.collisions()),
               static_cast<unsigned long long>(stalls), 1000 * kStallS, 1000 * longest_stall,
               1000 * longest_stall * time_scale);
  return 0;
}

int Generate(uint64_t seed, const std::string& profile_name, const std::string& out) {
  const auto profile = ParseNoiseProfile(profile_name);
  if (!profile) {
    std::fprintf(stderr, "irslam-sim: --profile must be nominal, realistic or harsh (got '%s')\n",
                 profile_name.c_str());
    return kExitUsage;
  }
  const nlohmann::json world = WorldToJson(GenerateWorld(seed, *profile));
  if (out.empty()) {
    std::printf("%s\n", world.dump(1).c_str());
    return 0;
  }
  if (!WriteJson(out, world)) {
    std::fprintf(stderr, "irslam-sim: cannot write %s\n", out.c_str());
    return 1;
  }
  return 0;
}

// The options 'run' and 'serve' share.
void AddCommon(CLI::App* sub, Common* common) {
  sub->add_option("--world", common->world_path, "World file (JSON, contracts §1)")->required();
  sub->add_option("--seed", common->seed, "Random seed (default: the world's, else 1)");
  sub->add_option("--truth-out", common->truth_out, "Write the truth file here (contracts §5)");
  sub->add_option("--faults", common->faults,
                  "Inject faults between the controller and the bus: NAME[:KEY=VALUE...],... "
                  "(loss, burst, corrupt, duplicate, reorder, delay, silence, flood, stuck_ir, "
                  "encoder_glitch, kidnap; docs/reliability.md)");
  sub->add_option("--config", common->config_path,
                  "irslamd config file (robot geometry, sensors; and the core in 'run')");
}

}  // namespace
}  // namespace irslam::sim

int main(int argc, char** argv) {
  CLI::App app{"irslam-sim: simulated motor controller, IR sensors and world for irslamd"};
  app.require_subcommand(1);
  irslam::sim::Common common;
  auto* run = app.add_subcommand("run", "Run the whole mission in process, as fast as possible");
  irslam::sim::AddCommon(run, &common);
  double max_time = 0;
  std::string map_out;
  run->add_option("--max-time", max_time,
                  "Robot-time limit in seconds (default: mission.max_time_s, plus "
                  "cleaning.max_time_s in mode clean)")
      ->check(CLI::PositiveNumber);
  run->add_option("--mode", common.mode,
                  "explore: map the room (default); clean: map it, clean it, return to the start")
      ->check(CLI::IsMember({"explore", "clean"}));
  run->add_option("--map-out", map_out, "Write the map here (contracts §4)");
  run->add_option("--map-in", common.map_in,
                  "Start from this saved map (contracts §4, or the daemon's map file): relocalise in it "
                  "first; the map written is in its frame with its ids");
  run->add_option("--start", common.start,
                  "X,Y,THETA: the robot starts here instead of the world's start pose (world frame)");
  std::string svg_out, lines_out, events_out;
  run->add_option("--svg", svg_out, "Draw the map, the true room and trajectories as SVG");
  run->add_option("--pgm", common.pgm_out, "Write the map as an occupancy grid FILE.pgm and FILE.yaml (ROS map_server)");
  run->add_option("--pgm-resolution", common.pgm_res, "Cell size of --pgm in metres")
      ->check(CLI::Range(0.005, 1.0))
      ->capture_default_str();
  run->add_option("--lines-out", lines_out,
                  "Record every extracted line observation (JSON lines; input of irslam-weights)");
  run->add_option("--events-out", events_out,
                  "Record every change of mission state, reason or behaviour with the true and "
                  "estimated pose (JSON lines)");
  std::string tick_clock = "wall";
  run->add_option("--tick-clock", tick_clock,
                  "What the work per control period is measured in: wall (the monotonic clock) or cpu "
                  "(this thread's CPU time: without the time a loaded host gave to others)")
      ->check(CLI::IsMember({"wall", "cpu"}));
  std::string baseline;
  run->add_option("--baseline", baseline,
                  "bounce: drive the random-bounce cleaner (no map, no plan) instead of the mission, for "
                  "--max-time (default: cleaning.max_time_s), and print its true coverage")
      ->check(CLI::IsMember({"bounce"}));

  auto* serve = app.add_subcommand("serve", "Be the motor controller on a CAN bus");
  irslam::sim::AddCommon(serve, &common);
  std::string iface;
  double time_scale = 1.0;
  serve->add_option("--can", iface, "vcan0, can0 or unix:PATH")->required();
  serve->add_option("--time-scale", time_scale, "Robot time runs K times faster than wall time")
      ->check(CLI::Range(0.01, 1000.0));
  int realtime_priority = 0;
  serve->add_option("--realtime-priority", realtime_priority,
                    "SCHED_FIFO priority for the simulator (the test rig's hardware must not be starved by "
                    "a loaded host); 0 = normal scheduling")
      ->check(CLI::Range(0, 99));
  auto* generate = app.add_subcommand("generate", "Write a random world (the robustness campaign's rooms)");
  uint64_t gen_seed = 1;
  std::string profile = "nominal", gen_out;
  generate->add_option("--seed", gen_seed, "Same seed, same world")->required();
  generate->add_option("--profile", profile, "Noise profile: nominal, realistic or harsh");
  generate->add_option("--out", gen_out, "Write the world file here (default: standard output)");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  if (*generate) return irslam::sim::Generate(gen_seed, profile, gen_out);
  if (*run && !baseline.empty()) return irslam::sim::RunBounceBaseline(common, max_time, map_out, svg_out);
  if (*run) return irslam::sim::Run(common, max_time, map_out, svg_out, lines_out, events_out, tick_clock);
  return irslam::sim::Serve(common, iface, time_scale, realtime_priority);
}
