#include "sim/sim_run.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace irslam::sim {
namespace {

int64_t NowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

// Ray crossing; points on an edge count either way (they fail the clearance).
bool InsideOutline(const std::vector<Vec2>& poly, Vec2 p) {
  bool inside = false;
  for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const Vec2 &a = poly[i], &b = poly[j];
    if ((a.y > p.y) != (b.y > p.y) && p.x < (b.x - a.x) * (p.y - a.y) / (b.y - a.y) + a.x) inside = !inside;
  }
  return inside;
}

std::string Where(const Pose2& p) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "(%.2f, %.2f)", p.x, p.y);
  return buf;
}

}  // namespace

bool FreePose(const World& world, const Pose2& p, double clearance_m, std::string* why) {
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.theta)) {
    *why = "the pose is not finite";
    return false;
  }
  if (world.outline.size() < 3 || !InsideOutline(world.outline, {p.x, p.y})) {
    *why = Where(p) + " lies outside the room";
    return false;
  }
  for (size_t i = 0; i < world.objects.size(); ++i) {
    const Box& o = world.objects[i];
    if (p.x > o.xmin && p.x < o.xmax && p.y > o.ymin && p.y < o.ymax) {
      char buf[96];
      std::snprintf(buf, sizeof buf, " lies inside object %zu [%.2f, %.2f, %.2f, %.2f]", i + 1, o.xmin, o.ymin,
                    o.xmax, o.ymax);
      *why = Where(p) + buf;
      return false;
    }
  }
  double nearest = 1e18;
  for (const Segment& s : world.Segments()) {
    Vec2 c;
    nearest = std::min(nearest, PointSegmentDistance({p.x, p.y}, s, &c));
  }
  if (nearest < clearance_m) {
    char buf[128];
    std::snprintf(buf, sizeof buf, " is %.2f m from a wall or object side (at least %.2f m needed)", nearest,
                  clearance_m);
    *why = Where(p) + buf;
    return false;
  }
  return true;
}

std::optional<Pose2> ParsePoseArg(const std::string& text, std::string* why) {
  std::vector<double> v;
  size_t at = 0;
  for (;;) {
    const size_t comma = text.find(',', at);
    const std::string part = text.substr(at, comma == std::string::npos ? std::string::npos : comma - at);
    char* stop = nullptr;
    const double x = std::strtod(part.c_str(), &stop);
    if (part.empty() || *stop != '\0' || !std::isfinite(x)) break;
    v.push_back(x);
    if (comma == std::string::npos) break;
    at = comma + 1;
  }
  if (v.size() != 3 || std::count(text.begin(), text.end(), ',') != 2) {
    *why = "expected X,Y,THETA (three numbers: metres, metres, radians), got '" + text + "'";
    return std::nullopt;
  }
  return Pose2{v[0], v[1], NormalizeAngle(v[2])};
}

SimOptions SimOptionsFrom(const robot::CoreOptions& core) {
  SimOptions o;
  o.geometry = core.slam.geometry;
  o.mounts = core.slam.mounts;
  o.ir = core.ir;
  return o;
}

InProcessRun RunInProcess(const World& world, const robot::CoreOptions& options, uint64_t seed,
                          double max_time_s,
                          const std::function<void(const InProcessRun&)>& on_tick,
                          const FaultSpec* faults, robot::WorkClockNs work_clock,
                          const std::optional<robot::MapSnapshot>& saved_map) {
  RunSetup setup;
  setup.saved_map = saved_map;
  return RunInProcess(world, options, seed, max_time_s, on_tick, faults, std::move(work_clock), setup);
}

InProcessRun RunInProcess(const World& world, const robot::CoreOptions& options, uint64_t seed,
                          double max_time_s, const std::function<void(const InProcessRun&)>& on_tick,
                          const FaultSpec* faults, robot::WorkClockNs work_clock, const RunSetup& setup) {
  const robot::WorkClockNs now_ns = work_clock ? std::move(work_clock) : robot::WorkClockNs(NowNs);
  InProcessRun run;
  run.sim = std::make_unique<SimController>(world, SimOptionsFrom(options), seed);
  run.core = std::make_unique<robot::RobotCore>(options);
  run.core->SetWorkClock(now_ns);
  if (setup.saved_map) run.core->SetSavedMap(setup.saved_map);
  const int64_t run_start = NowNs();
  robot::TickWork work;
  if (faults) run.faults = std::make_unique<FaultInjector>(*faults, seed);
  // Frames are exchanged every 2 ms of robot time; the core ticks at its period.
  const double io_dt = 0.002;
  double next_tick = options.period_s;
  bool started = false;
  bool restarted = false;
  std::vector<can_frame> frames, faulty;
  for (run.t = 0; run.t < max_time_s;) {
    run.t += io_dt;
    if (run.faults) {
      while (const auto to = run.faults->TakeKidnap(run.t)) run.sim->Teleport(*to);
    }
    frames.clear();
    run.sim->AdvanceTo(run.t, &frames);
    if (run.faults) {
      faulty.clear();
      run.faults->Process(run.t, frames, &faulty);
      run.faults->Flood(run.t, io_dt, &faulty);
      frames.swap(faulty);
    }
    if (!frames.empty()) {
      const int64_t t0 = now_ns();
      for (const can_frame& f : frames) run.core->OnFrame(f, run.t);
      work[robot::TickPhase::kSlam] += now_ns() - t0;
    }
    if (run.t < next_tick - 1e-9) continue;
    next_tick += options.period_s;
    if (!started && run.t > 0.3) {
      if (!run.core->Start(run.t, &run.error)) return run;
      started = true;
    }
    const int64_t planned0 = run.core->planning_ns();
    const int64_t t0 = now_ns();
    const std::vector<can_frame> out = run.core->Tick(run.t);
    const int64_t tick_ns = now_ns() - t0;
    work[robot::TickPhase::kPlanning] = run.core->planning_ns() - planned0;
    work[robot::TickPhase::kMission] = tick_ns - work[robot::TickPhase::kPlanning];
    run.profile.Add(work, run.t);
    work = {};
    for (const can_frame& f : out) run.sim->HandleFrame(f);
    if (on_tick) on_tick(run);
    if (setup.stop_when && setup.stop_when(run)) break;
    if (!restarted && setup.stop_and_start_when && setup.stop_and_start_when(run)) {
      restarted = true;
      run.core->Stop(run.t);
      if (!run.core->Start(run.t, &run.error)) return run;
      continue;
    }
    const auto s = run.core->state();
    if (started && (s == control::MissionState::kDone || s == control::MissionState::kIdle)) break;
  }
  run.wall_s = static_cast<double>(NowNs() - run_start) * 1e-9;
  return run;
}

}  // namespace irslam::sim
