// The in-process mission: the simulated controller and a RobotCore exchanging
// the same CAN frames as over a bus, as fast as the CPU allows.
#ifndef IRSLAM_SIM_SIM_RUN_H_
#define IRSLAM_SIM_SIM_RUN_H_

#include <functional>
#include <memory>
#include <optional>
#include <string>

#include "robot/robot_core.h"
#include "robot/tick_profile.h"
#include "sim/faults.h"
#include "sim/sim_controller.h"

namespace irslam::sim {

SimOptions SimOptionsFrom(const robot::CoreOptions& core);

struct InProcessRun {
  std::unique_ptr<SimController> sim;
  std::unique_ptr<robot::RobotCore> core;
  std::unique_ptr<FaultInjector> faults;  // when faults were injected
  double t = 0;
  std::string error;  // set when the mission could not start
  // Each control period's work (the frames since the last period, then the
  // tick; planning apart), measured on this process's monotonic clock; and the
  // whole run's wall time (simulator included).
  robot::TickProfile profile;
  double wall_s = 0;
};

// Runs until the mission is done or idle again, or max_time_s of robot time.
// on_tick (optional) is called after every control period. work_clock: what
// the work per period (run.profile) is measured with (default: the monotonic clock).
InProcessRun RunInProcess(const World& world, const robot::CoreOptions& options, uint64_t seed,
                          double max_time_s,
                          const std::function<void(const InProcessRun&)>& on_tick = nullptr,
                          const FaultSpec* faults = nullptr,
                          robot::WorkClockNs work_clock = nullptr,
                          const std::optional<robot::MapSnapshot>& saved_map = std::nullopt);

}  // namespace irslam::sim

#endif  // IRSLAM_SIM_SIM_RUN_H_
