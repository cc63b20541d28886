#include "sim/sim_run.h"

#include <chrono>

namespace irslam::sim {
namespace {

int64_t NowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

}  // namespace

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
  const robot::WorkClockNs now_ns = work_clock ? std::move(work_clock) : robot::WorkClockNs(NowNs);
  InProcessRun run;
  run.sim = std::make_unique<SimController>(world, SimOptionsFrom(options), seed);
  run.core = std::make_unique<robot::RobotCore>(options);
  run.core->SetWorkClock(now_ns);
  if (saved_map) run.core->SetSavedMap(saved_map);
  const int64_t run_start = NowNs();
  robot::TickWork work;
  if (faults) run.faults = std::make_unique<FaultInjector>(*faults, seed);
  // Frames are exchanged every 2 ms of robot time; the core ticks at its period.
  const double io_dt = 0.002;
  double next_tick = options.period_s;
  bool started = false;
  std::vector<can_frame> frames, faulty;
  for (run.t = 0; run.t < max_time_s;) {
    run.t += io_dt;
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
    const auto s = run.core->state();
    if (started && (s == control::MissionState::kDone || s == control::MissionState::kIdle)) break;
  }
  run.wall_s = static_cast<double>(NowNs() - run_start) * 1e-9;
  return run;
}

}  // namespace irslam::sim
