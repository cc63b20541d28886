// The in-process mission: the simulated controller and a RobotCore exchanging
// the same CAN frames as over a bus, as fast as the CPU allows.
#ifndef IRSLAM_SIM_SIM_RUN_H_
#define IRSLAM_SIM_SIM_RUN_H_

#include <functional>
#include <memory>
#include <string>

#include "robot/robot_core.h"
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
};

// Runs until the mission is done or idle again, or max_time_s of robot time.
// on_tick (optional) is called after every control period.
InProcessRun RunInProcess(const World& world, const robot::CoreOptions& options, uint64_t seed,
                          double max_time_s,
                          const std::function<void(const InProcessRun&)>& on_tick = nullptr,
                          const FaultSpec* faults = nullptr);

}  // namespace irslam::sim

#endif  // IRSLAM_SIM_SIM_RUN_H_
