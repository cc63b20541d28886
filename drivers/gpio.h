// The robot's GPIO safety lines through libgpiod (1.6 C++ bindings): the
// emergency-stop button and the bumpers as edge events on the io_context, the
// motor-driver enable and the status LED as outputs. Every line is optional and
// named in the config by chip (label, name, path or number) and line (name or
// offset); see drivers/gpio_settings.h and docs/gpio.md.
#ifndef IRSLAM_DRIVERS_GPIO_H_
#define IRSLAM_DRIVERS_GPIO_H_

#include <boost/asio/io_context.hpp>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "drivers/gpio_settings.h"

namespace irslam::drivers {

class Gpio {
 public:
  enum class Input { kEstop, kBumperLeft, kBumperRight };
  // A line's level changed (active = pressed, after the active-low correction).
  using InputHandler = std::function<void(Input input, bool active)>;

  // One line in use, for status.
  struct LineInfo {
    std::string role;    // "estop", "bumper_left", "bumper_right", "motor_enable", "status_led"
    std::string chip;    // the chip's name (gpiochipN) and label
    std::string label;
    unsigned offset = 0;
    std::string name;    // the line's name, if it has one
    bool output = false;
    bool active = false; // last level read or written
  };

  // Opens the chips and requests every configured line (outputs start inactive).
  // Returns nullptr and a one-line *error if a line cannot be had; an empty
  // settings object gives a Gpio with no lines.
  static std::unique_ptr<Gpio> Open(boost::asio::io_context& io, const GpioSettings& settings,
                                    std::string* error);
  ~Gpio();
  Gpio(const Gpio&) = delete;
  Gpio& operator=(const Gpio&) = delete;

  // Reports every input's present level once, then each change, on the io_context.
  void Start(InputHandler handler);
  // Reports every input's present level again (after the core was replaced).
  void Replay();
  void SetMotorEnable(bool active);
  void SetLed(bool active);
  // Lines in use and the number of edge events seen.
  std::vector<LineInfo> lines() const;
  uint64_t events() const { return events_; }
  void Close();

 private:
  struct Line;
  Gpio();
  void Arm(Line* line);
  void Set(Line* line, bool active);
  bool ReadLevel(Line* line);

  std::vector<std::unique_ptr<Line>> lines_;
  Line* motor_enable_ = nullptr;
  Line* status_led_ = nullptr;
  InputHandler handler_;
  uint64_t events_ = 0;
};

}  // namespace irslam::drivers

#endif  // IRSLAM_DRIVERS_GPIO_H_
