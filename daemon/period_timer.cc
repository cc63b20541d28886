#include "daemon/period_timer.h"

#include <sys/timerfd.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace irslam {
namespace {

timespec ToTimespec(int64_t ns) {
  return timespec{static_cast<time_t>(ns / 1000000000), static_cast<long>(ns % 1000000000)};
}

}  // namespace

bool PeriodTimer::Start(int64_t first_ns, int64_t period_ns, std::function<void()> on_expiry,
                        std::string* error) {
  Cancel();
  const int fd = ::timerfd_create(CLOCK_MONOTONIC, TFD_NONBLOCK | TFD_CLOEXEC);
  if (fd < 0) {
    *error = std::string("timerfd_create: ") + std::strerror(errno);
    return false;
  }
  itimerspec spec{};
  spec.it_value = ToTimespec(first_ns);
  spec.it_interval = ToTimespec(period_ns);
  if (spec.it_value.tv_sec == 0 && spec.it_value.tv_nsec == 0)
    spec.it_value.tv_nsec = 1;  // 0 disarms
  if (::timerfd_settime(fd, TFD_TIMER_ABSTIME, &spec, nullptr) != 0) {
    *error = std::string("timerfd_settime: ") + std::strerror(errno);
    ::close(fd);
    return false;
  }
  boost::system::error_code ec;
  fd_.assign(fd, ec);
  if (ec) {
    *error = "timerfd on the event loop: " + ec.message();
    ::close(fd);
    return false;
  }
  on_expiry_ = std::move(on_expiry);
  Wait();
  return true;
}

void PeriodTimer::Cancel() {
  boost::system::error_code ec;
  fd_.cancel(ec);
  fd_.close(ec);
}

void PeriodTimer::Wait() {
  fd_.async_wait(boost::asio::posix::stream_descriptor::wait_read,
                 [this](const boost::system::error_code& ec) {
                   if (ec) return;  // cancelled
                   uint64_t expirations = 0;
                   const ssize_t n = ::read(fd_.native_handle(), &expirations, sizeof expirations);
                   // EAGAIN: woken without an expiry (another reader, or a clock change); wait
                   // again.
                   if (n == static_cast<ssize_t>(sizeof expirations) && on_expiry_) on_expiry_();
                   if (fd_.is_open()) Wait();
                 });
}

}  // namespace irslam
