// PeriodTimer: the control loop's fixed-period wake-up (issue 15). One timerfd on
// CLOCK_MONOTONIC (std::chrono::steady_clock's clock on Linux), armed once with
// the period's grid (first, first + period, ...), on the io_context's reactor.
// Each period then costs one read() of the expiration count. A one-shot asio
// timer re-armed every period costs two timerfd_settime() calls per period (the
// reactor re-arms its timerfd when the timer fires and again when it is set), and
// at 50 Hz the loop's system calls are most of the daemon's CPU share.
// Missed expirations (a period that overran) are not replayed: the handler runs
// once, and PeriodScheduler counts the skipped deadlines from the wake-up time.
#ifndef IRSLAM_DAEMON_PERIOD_TIMER_H_
#define IRSLAM_DAEMON_PERIOD_TIMER_H_

#include <boost/asio/io_context.hpp>
#include <boost/asio/posix/stream_descriptor.hpp>
#include <cstdint>
#include <functional>
#include <string>

namespace irslam {

class PeriodTimer {
 public:
  explicit PeriodTimer(boost::asio::io_context& io) : fd_(io) {}
  PeriodTimer(const PeriodTimer&) = delete;
  PeriodTimer& operator=(const PeriodTimer&) = delete;

  // First expiry at first_ns (steady-clock nanoseconds), then every period_ns;
  // on_expiry runs on the io_context. False with a one-line *error if the kernel
  // refuses (no timerfd, no file descriptors left).
  bool Start(int64_t first_ns, int64_t period_ns, std::function<void()> on_expiry,
             std::string* error);
  void Cancel();

 private:
  void Wait();

  boost::asio::posix::stream_descriptor fd_;
  std::function<void()> on_expiry_;
};

}  // namespace irslam

#endif  // IRSLAM_DAEMON_PERIOD_TIMER_H_
