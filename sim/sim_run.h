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

// What a run starts from besides the world (irslam-sim run --map-in; the
// relocalisation evaluation).
struct RunSetup {
  // Handed to the core before the start (RobotCore::SetSavedMap): the mission
  // relocalises in it first (issue 14).
  std::optional<robot::MapSnapshot> saved_map;
  // Checked after every control period (after on_tick): true ends the run there.
  std::function<bool(const InProcessRun&)> stop_when;
  // Checked after every control period until it is first true: then the
  // mission is stopped and started again at once, as a client's stop and
  // start do (the core keeps its map: RobotCore::Start continues in it).
  std::function<bool(const InProcessRun&)> stop_and_start_when;
};

// Runs until the mission is done or idle again, or max_time_s of robot time.
// on_tick (optional) is called after every control period. work_clock: what
// the work per period (run.profile) is measured with (default: the monotonic clock).
// Kidnap faults teleport the simulated robot when their time comes.
InProcessRun RunInProcess(const World& world, const robot::CoreOptions& options, uint64_t seed,
                          double max_time_s,
                          const std::function<void(const InProcessRun&)>& on_tick = nullptr,
                          const FaultSpec* faults = nullptr,
                          robot::WorkClockNs work_clock = nullptr,
                          const std::optional<robot::MapSnapshot>& saved_map = std::nullopt);
// The same with a RunSetup: its saved_map, and stop_when to end the run early.
InProcessRun RunInProcess(const World& world, const robot::CoreOptions& options, uint64_t seed,
                          double max_time_s, const std::function<void(const InProcessRun&)>& on_tick,
                          const FaultSpec* faults, robot::WorkClockNs work_clock, const RunSetup& setup);

// Whether p is a pose the robot can be put at in the world: inside the room,
// outside every box, its centre at least clearance_m from every wall and box
// side. Otherwise false and a one-line *why ("(1.00, 9.00) lies outside the
// room", "... lies inside object 2 [0.0, 2.0, 0.6, 3.2]", "... is 0.12 m from
// a wall or object side (at least 0.20 m needed)").
bool FreePose(const World& world, const Pose2& p, double clearance_m, std::string* why);

// "X,Y,THETA" (irslam-sim run --start): three finite numbers, theta normalised;
// else nullopt and a one-line *why.
std::optional<Pose2> ParsePoseArg(const std::string& text, std::string* why);

}  // namespace irslam::sim

#endif  // IRSLAM_SIM_SIM_RUN_H_
