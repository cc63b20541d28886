#include "sim/sim_run.h"

namespace irslam::sim {

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
                          const FaultSpec* faults) {
  InProcessRun run;
  run.sim = std::make_unique<SimController>(world, SimOptionsFrom(options), seed);
  run.core = std::make_unique<robot::RobotCore>(options);
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
    for (const can_frame& f : frames) run.core->OnFrame(f, run.t);
    if (run.t < next_tick - 1e-9) continue;
    next_tick += options.period_s;
    if (!started && run.t > 0.3) {
      if (!run.core->Start(run.t, &run.error)) return run;
      started = true;
    }
    for (const can_frame& f : run.core->Tick(run.t)) run.sim->HandleFrame(f);
    if (on_tick) on_tick(run);
    const auto s = run.core->state();
    if (started && (s == control::MissionState::kDone || s == control::MissionState::kIdle)) break;
  }
  return run;
}

}  // namespace irslam::sim
