// Private to the API server: the API thread's CPU share.
#ifndef IRSLAM_DAEMON_INTERNAL_API_CPU_SHARE_H_
#define IRSLAM_DAEMON_INTERNAL_API_CPU_SHARE_H_

#include <atomic>
#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>
#include <chrono>
#include <cstdint>
#include <functional>
#include <vector>

#include "daemon/api_server.h"

namespace irslam {

// The scheduler that keeps the API thread to ApiLimits::cpu_share of every
// cpu_window_s: the time spent handling request lines is added up per window;
// once the share is used up, a client with a line to handle is deferred, and
// every deferred client is resumed (one line each) when the next window starts,
// by one timer for all of them. API thread only.
class ApiCpuShare {
 public:
  using Clock = std::chrono::steady_clock;

  // pauses: counts the windows in which the share was used up (ApiStats::cpu_pauses).
  ApiCpuShare(boost::asio::io_context& io, const ApiLimits& limits, std::atomic<uint64_t>* pauses);

  // Whether the current window has budget left (starts a new window when due).
  bool BudgetLeft();
  void Spent(Clock::duration d) { window_spent_ += d; }
  // resume runs when the next window starts (unless Cancel() comes first).
  void Defer(std::function<void()> resume);
  void Cancel() { timer_.cancel(); }

 private:
  const ApiLimits& limits_;
  std::atomic<uint64_t>* pauses_;
  boost::asio::steady_timer timer_;
  std::vector<std::function<void()>> deferred_;
  Clock::time_point window_start_{};
  Clock::duration window_spent_{};
  bool armed_ = false;
};

}  // namespace irslam

#endif  // IRSLAM_DAEMON_INTERNAL_API_CPU_SHARE_H_
