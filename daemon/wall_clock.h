// The daemon's notion of "now", injected: the system's monotonic clock in the
// daemon, a fake one in tests (so the watchdog cadence, save rate limits and
// period statistics can be tested with exact times, without sleeping).
#ifndef IRSLAM_DAEMON_WALL_CLOCK_H_
#define IRSLAM_DAEMON_WALL_CLOCK_H_

#include <chrono>
#include <functional>

namespace irslam {

using WallTime = std::chrono::steady_clock::time_point;
using WallClock = std::function<WallTime()>;

inline WallClock SystemWallClock() {
  return [] { return std::chrono::steady_clock::now(); };
}

// Seconds from a to b.
inline double SecondsBetween(WallTime a, WallTime b) { return std::chrono::duration<double>(b - a).count(); }

}  // namespace irslam

#endif  // IRSLAM_DAEMON_WALL_CLOCK_H_
