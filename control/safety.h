// The safety lines of the robot (GPIO: emergency stop, bumpers, motor-driver enable,
// status LED) as pure logic: debouncing and the LED pattern per state. The lines
// and their settings are drivers/gpio's; RobotCore decides what they mean.
#ifndef IRSLAM_CONTROL_SAFETY_H_
#define IRSLAM_CONTROL_SAFETY_H_

#include <optional>

#include "control/mission.h"
#include "types/options.h"

namespace irslam::control {

// The safety inputs' own option (config key [gpio].debounce_s: it sits beside the
// GPIO lines in the file, but the lines are the daemon's and this is the core's).
struct SafetyOptions {
  double debounce_s = 0.02;  // a release counts once the input stayed released this long
};
options::Table<SafetyOptions> SafetyKeys();  // [gpio].debounce_s

// A switch input, debounced the safe way: an activation acts at once (an
// emergency stop or a bump must not wait), a release only once the input has
// stayed released for the debounce time, so contact bounce never reads as a
// release followed by a new press.
class Debouncer {
 public:
  explicit Debouncer(double debounce_s) : debounce_s_(debounce_s) {}
  // The raw (active-level-corrected) input seen at time t.
  void Input(bool active, double t);
  // Advances time to t; returns the debounced state.
  bool Poll(double t);
  bool active() const { return stable_; }

 private:
  double debounce_s_;
  bool stable_ = false;
  std::optional<double> released_at_;  // raw input inactive since, while stable_ is true
};

// The status LED for a state, at time t: idle steady on; driving (wall_follow,
// model, go_to_p1, contour_follow) blinks at 1 Hz; done flashes 0.1 s every 2 s;
// fault (and a latched emergency stop) blinks at 5 Hz.
bool LedOn(MissionState state, double t);

}  // namespace irslam::control

#endif  // IRSLAM_CONTROL_SAFETY_H_
