// Value types shared by the pure core (slam/, control/) and the drivers that feed it.
// Every input carries its own time stamp t in robot seconds: the core has no clock.
#ifndef IRSLAM_SLAM_TYPES_H_
#define IRSLAM_SLAM_TYPES_H_

#include <array>
#include <cmath>
#include <cstdint>
#include <optional>

namespace irslam {

inline constexpr int kNumIrSensors = 7;

// Normalises an angle to (-pi, pi].
inline double NormalizeAngle(double a) {
  a = std::remainder(a, 2.0 * M_PI);
  if (a <= -M_PI) a += 2.0 * M_PI;
  return a;
}

struct Pose2 {
  double x = 0;
  double y = 0;
  double theta = 0;
};

// Composes a with b (b expressed in a's frame).
inline Pose2 Compose(const Pose2& a, const Pose2& b) {
  const double c = std::cos(a.theta), s = std::sin(a.theta);
  return {a.x + c * b.x - s * b.y, a.y + s * b.x + c * b.y, NormalizeAngle(a.theta + b.theta)};
}

// Cumulative (unwrapped) wheel encoder counts at controller time t.
struct WheelTicks {
  double t = 0;
  int64_t left = 0;
  int64_t right = 0;
};

// One reading of all IR sensors at controller time t, already converted to metres.
// A sensor without a usable reading (outside the calibrated range) is nullopt.
struct RangeScan {
  double t = 0;
  std::array<std::optional<double>, kNumIrSensors> range_m{};
};

// Wheel velocity command in m/s.
struct WheelCommand {
  double left_mps = 0;
  double right_mps = 0;
  bool enable = false;
};

}  // namespace irslam

#endif  // IRSLAM_SLAM_TYPES_H_
