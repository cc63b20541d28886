// The GPIO lines irslamd may use (config section [gpio]): plain data for the
// libgpiod driver (drivers/gpio.h), part of the daemon's settings. The inputs'
// debounce time ([gpio].debounce_s) is the core's (control::SafetyOptions).
#ifndef IRSLAM_DRIVERS_GPIO_SETTINGS_H_
#define IRSLAM_DRIVERS_GPIO_SETTINGS_H_

#include <string>

namespace irslam::drivers {

// One GPIO line: the chip (label, name such as "gpiochip0", path or number, as
// libgpiod's lookup takes it) and the line (its name, or its offset as a number).
// An empty chip means the robot has no such line.
struct GpioLineSpec {
  std::string chip;
  std::string line;
  bool active_low = false;  // the line's active (pressed / on) level is low
  bool used() const { return !chip.empty(); }
  bool operator==(const GpioLineSpec&) const = default;
};

// Config section [gpio] but debounce_s; every line is optional.
struct GpioSettings {
  GpioLineSpec estop;         // input: emergency-stop button
  GpioLineSpec bumper_left;   // input: left bumper switch
  GpioLineSpec bumper_right;  // input: right bumper switch
  GpioLineSpec motor_enable;  // output: motor-driver enable
  GpioLineSpec status_led;    // output: status LED
  bool any_used() const {
    return estop.used() || bumper_left.used() || bumper_right.used() || motor_enable.used() ||
           status_led.used();
  }
  // The same lines (a reload that changes them needs a restart; the debounce
  // time, the core's, applies at once).
  bool SameLines(const GpioSettings& o) const {
    return estop == o.estop && bumper_left == o.bumper_left && bumper_right == o.bumper_right &&
           motor_enable == o.motor_enable && status_led == o.status_led;
  }
};

}  // namespace irslam::drivers

#endif  // IRSLAM_DRIVERS_GPIO_SETTINGS_H_
