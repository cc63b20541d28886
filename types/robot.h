// The robot's fixed facts, shared by the protocol, the drivers, SLAM and control:
// how many IR sensors it has and where they sit, its wheels and body, its bumpers.
#ifndef IRSLAM_TYPES_ROBOT_H_
#define IRSLAM_TYPES_ROBOT_H_

#include <cmath>
#include <cstdint>

#include "types/options.h"

namespace irslam {

inline constexpr int kNumIrSensors = 7;

// A beam's hit is ahead of the robot's centre when its x (robot frame) exceeds
// this: the side beams, mounted at +-90 degrees, have an x of about 1e-17 m
// from rounding and are beside the robot, not ahead.
inline constexpr double kAheadM = 1e-3;

// Bumper bits (CTRL_STATUS.Bumpers on the bus, and the GPIO bumpers).
inline constexpr uint8_t kBumperLeft = 1 << 0;
inline constexpr uint8_t kBumperRight = 1 << 1;

struct RobotGeometry {
  double wheel_base_m = 0.25;      // distance between the wheels' contact points
  double wheel_radius_m = 0.035;
  double counts_per_rev = 2048;    // encoder counts per wheel revolution
  double radius_m = 0.17;          // robot body radius (round robot)
  double max_wheel_speed_mps = 0.5;

  double metres_per_count() const { return 2.0 * M_PI * wheel_radius_m / counts_per_rev; }
};

// Config section [robot].
inline options::Table<RobotGeometry> RobotGeometryKeys() {
  using G = RobotGeometry;
  static constexpr options::Key<G> kKeys[] = {
      {"wheel_base_m", &G::wheel_base_m, 0.05, 2.0, "m", "distance between the wheel contact points"},
      {"wheel_radius_m", &G::wheel_radius_m, 0.005, 0.5, "m", "wheel radius"},
      {"counts_per_rev", &G::counts_per_rev, 1, 1e7, "", "encoder counts per wheel revolution"},
      {"radius_m", &G::radius_m, 0.05, 2.0, "m", "body radius (round robot)"},
      {"max_wheel_speed_mps", &G::max_wheel_speed_mps, 0.01, 5.0, "m/s", "fastest wheel speed commanded"},
  };
  return kKeys;
}

// Where an IR sensor sits on the robot (robot frame: x forward, y left).
struct SensorMount {
  double x = 0;
  double y = 0;
  double theta = 0;
};

// Where a beam of range r from mount m ends, in the robot frame.
struct BeamHit {
  double x, y;
};
inline BeamHit HitPoint(const SensorMount& m, double r) {
  return {m.x + r * std::cos(m.theta), m.y + r * std::sin(m.theta)};
}

}  // namespace irslam

#endif  // IRSLAM_TYPES_ROBOT_H_
