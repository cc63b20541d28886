// The random-bounce cleaner (issue 13's baseline): no map, no plan; drive
// straight until a bumper or an IR reading closer than 10 cm, then turn on the
// spot by a random angle and go on. It talks to the simulated controller through
// the same motor-controller client and IR conditioning as the core, for a fixed
// robot time, so its coverage can be compared with planned cleaning's over the
// same budget.
#ifndef IRSLAM_SIM_BOUNCE_H_
#define IRSLAM_SIM_BOUNCE_H_

#include <memory>

#include "robot/robot_core.h"
#include "sim/sim_controller.h"

namespace irslam::sim {

struct BounceOptions {
  double speed_mps = 0.15;        // straight ahead
  double turn_rate_rad_s = 1.0;   // turning on the spot
  double near_m = 0.10;           // an IR reading (from the body's edge) this close: turn
  double min_turn_rad = 0.5;      // random turn angle, uniform in [min, max], random side
  double max_turn_rad = 3.14;
};

// Runs the bounce cleaner from the world's start for duration_s of robot time.
std::unique_ptr<SimController> RunBounce(const World& world, const robot::CoreOptions& options,
                                         uint64_t seed, double duration_s,
                                         const BounceOptions& bounce = {});

}  // namespace irslam::sim

#endif  // IRSLAM_SIM_BOUNCE_H_
