#include "daemon/internal/api_cpu_share.h"

#include <utility>

#include "daemon/internal/api_session.h"

namespace irslam {

using api_internal::Seconds;

ApiCpuShare::ApiCpuShare(boost::asio::io_context& io, const ApiLimits& limits,
                         std::atomic<uint64_t>* pauses)
    : limits_(limits), pauses_(pauses), timer_(io) {}

bool ApiCpuShare::BudgetLeft() {
  const auto now = Clock::now();
  const auto window = Seconds(limits_.cpu_window_s);
  if (now - window_start_ >= window) {
    window_start_ = now;
    window_spent_ = {};
  }
  return window_spent_ < Seconds(limits_.cpu_window_s * limits_.cpu_share);
}

void ApiCpuShare::Defer(std::function<void()> resume) {
  deferred_.push_back(std::move(resume));
  if (armed_) return;
  armed_ = true;
  ++*pauses_;
  timer_.expires_at(window_start_ + Seconds(limits_.cpu_window_s));
  timer_.async_wait([this](const boost::system::error_code& ec) {
    armed_ = false;
    if (ec) return;
    auto waiting = std::move(deferred_);
    deferred_.clear();
    for (auto& go_on : waiting) go_on();
  });
}

}  // namespace irslam
