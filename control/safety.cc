#include "control/safety.h"

#include <cmath>

namespace irslam::control {

options::Table<SafetyOptions> SafetyKeys() {
  static constexpr options::Key<SafetyOptions> kKeys[] = {
      {"debounce_s", &SafetyOptions::debounce_s, 0, 1, "s",
       "a release counts once stable this long (presses act at once)"},
  };
  return kKeys;
}

void Debouncer::Input(bool active, double t) {
  if (active) {
    stable_ = true;
    released_at_.reset();
  } else if (stable_ && !released_at_) {
    released_at_ = t;
  }
}

bool Debouncer::Poll(double t) {
  if (stable_ && released_at_ && t - *released_at_ >= debounce_s_ - 1e-9) {
    stable_ = false;
    released_at_.reset();
  }
  return stable_;
}

bool LedOn(MissionState state, double t) {
  const auto phase = [t](double period) { return std::fmod(std::max(t, 0.0), period) / period; };
  switch (state) {
    case MissionState::kIdle: return true;
    case MissionState::kDone: return phase(2.0) < 0.05;
    case MissionState::kFault: return phase(0.2) < 0.5;
    default: return phase(1.0) < 0.5;
  }
}

}  // namespace irslam::control
