// The time-stamped values that flow between the drivers and the pure core. Every
// input carries its own time stamp t in robot seconds: the core has no clock.
#ifndef IRSLAM_TYPES_SIGNALS_H_
#define IRSLAM_TYPES_SIGNALS_H_

#include <array>
#include <cstdint>
#include <optional>

#include "types/robot.h"

namespace irslam {

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

#endif  // IRSLAM_TYPES_SIGNALS_H_
