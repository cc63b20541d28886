#include "drivers/gpio.h"

#include <unistd.h>

#include <boost/asio/posix/stream_descriptor.hpp>
#include <chrono>
#include <gpiod.hpp>
#include <system_error>

namespace irslam::drivers {

struct Gpio::Line {
  explicit Line(boost::asio::io_context& io) : fd(io) {}
  LineInfo info;
  Input input = Input::kEstop;
  gpiod::chip chip;
  gpiod::line line;
  boost::asio::posix::stream_descriptor fd;  // a dup of the line's event fd
};

namespace {

bool IsNumber(const std::string& s) {
  return !s.empty() && s.find_first_not_of("0123456789") == std::string::npos;
}

}  // namespace

Gpio::Gpio() = default;

Gpio::~Gpio() { Close(); }

std::unique_ptr<Gpio> Gpio::Open(boost::asio::io_context& io, const GpioSettings& s,
                                 std::string* error) {
  std::unique_ptr<Gpio> g(new Gpio());
  struct Want {
    const char* role;
    const GpioLineSpec* spec;
    bool output;
    Input input;
  };
  const Want wants[] = {{"estop", &s.estop, false, Input::kEstop},
                        {"bumper_left", &s.bumper_left, false, Input::kBumperLeft},
                        {"bumper_right", &s.bumper_right, false, Input::kBumperRight},
                        {"motor_enable", &s.motor_enable, true, Input::kEstop},
                        {"status_led", &s.status_led, true, Input::kEstop}};
  for (const Want& w : wants) {
    if (!w.spec->used()) continue;
    const std::string what = std::string("gpio: ") + w.role + " (chip '" + w.spec->chip + "' line '" +
                             w.spec->line + "'): ";
    auto line = std::make_unique<Line>(io);
    try {
      line->chip.open(w.spec->chip, gpiod::chip::OPEN_LOOKUP);
    } catch (const std::exception& e) {
      *error = what + "no such chip (" + e.what() + ")";
      return nullptr;
    }
    try {
      if (IsNumber(w.spec->line)) {
        const unsigned long off = std::stoul(w.spec->line);
        if (off >= line->chip.num_lines()) {
          *error = what + "the chip has only " + std::to_string(line->chip.num_lines()) + " lines";
          return nullptr;
        }
        line->line = line->chip.get_line(static_cast<unsigned>(off));
      } else {
        line->line = line->chip.find_line(w.spec->line);
        if (!line->line) {
          *error = what + "the chip has no line of that name";
          return nullptr;
        }
      }
      gpiod::line_request req;
      req.consumer = "irslamd";
      req.request_type = w.output ? gpiod::line_request::DIRECTION_OUTPUT
                                  : gpiod::line_request::EVENT_BOTH_EDGES;
      if (w.spec->active_low) req.flags |= gpiod::line_request::FLAG_ACTIVE_LOW;
      line->line.request(req, 0);  // outputs start inactive
      if (!w.output) {
        const int fd = ::dup(line->line.event_get_fd());
        if (fd < 0) throw std::system_error(errno, std::generic_category(), "dup");
        line->fd.assign(fd);
      }
    } catch (const std::exception& e) {
      *error = what + "cannot request the line (" + e.what() + ")";
      return nullptr;
    }
    line->input = w.input;
    line->info = {w.role, line->chip.name(), line->chip.label(), line->line.offset(), line->line.name(),
                  w.output, false};
    if (w.output) (std::string(w.role) == "motor_enable" ? g->motor_enable_ : g->status_led_) = line.get();
    g->lines_.push_back(std::move(line));
  }
  return g;
}

bool Gpio::ReadLevel(Line* l) {
  try {
    l->info.active = l->line.get_value() != 0;
  } catch (const std::exception&) {
    // Keep the last level; a line that cannot be read is reported by its events.
  }
  return l->info.active;
}

void Gpio::Start(InputHandler handler) {
  handler_ = std::move(handler);
  Replay();
  for (auto& l : lines_) {
    if (!l->info.output) Arm(l.get());
  }
}

void Gpio::Replay() {
  for (auto& l : lines_) {
    if (!l->info.output && handler_) handler_(l->input, ReadLevel(l.get()));
  }
}

void Gpio::Arm(Line* l) {
  l->fd.async_wait(boost::asio::posix::stream_descriptor::wait_read,
                   [this, l](const boost::system::error_code& ec) {
                     if (ec) return;
                     // Drain the queued edges, then report the level now: contact
                     // bounce is the debouncer's business (control/safety.h).
                     try {
                       while (l->line.event_wait(std::chrono::nanoseconds(0))) {
                         l->line.event_read();
                         ++events_;
                       }
                     } catch (const std::exception&) {
                     }
                     if (handler_) handler_(l->input, ReadLevel(l));
                     Arm(l);
                   });
}

void Gpio::Set(Line* l, bool active) {
  if (l == nullptr || l->info.active == active) return;
  try {
    l->line.set_value(active ? 1 : 0);
    l->info.active = active;
  } catch (const std::exception&) {
    // Left as it was; retried at the next call.
  }
}

void Gpio::SetMotorEnable(bool active) { Set(motor_enable_, active); }
void Gpio::SetLed(bool active) { Set(status_led_, active); }

std::vector<Gpio::LineInfo> Gpio::lines() const {
  std::vector<LineInfo> out;
  for (const auto& l : lines_) out.push_back(l->info);
  return out;
}

void Gpio::Close() {
  for (auto& l : lines_) {
    boost::system::error_code ec;
    l->fd.cancel(ec);
    l->fd.close(ec);
    if (l->info.output) {
      try {
        l->line.set_value(0);  // motor driver disabled, LED off
      } catch (const std::exception&) {
      }
    }
    try {
      l->line.release();
    } catch (const std::exception&) {
    }
  }
  lines_.clear();
  motor_enable_ = status_led_ = nullptr;
}

}  // namespace irslam::drivers
