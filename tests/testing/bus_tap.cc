#include "tests/testing/bus_tap.h"

#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/post.hpp>

namespace irslam::testing {

BusTap::BusTap(const std::string& iface) {
  bus_ = drivers::OpenCanBus(io_, {iface, {}}, &error_);
  if (!bus_) return;
  bus_->Start([this](const can_frame& f, double) {
    std::lock_guard<std::mutex> l(mu_);
    seen_.push_back({f, std::chrono::steady_clock::now()});
  });
  thread_ = std::thread([this] {
    auto guard = boost::asio::make_work_guard(io_);
    io_.run();
  });
}

BusTap::~BusTap() {
  if (bus_) boost::asio::post(io_, [this] { bus_->Close(); });
  io_.stop();
  if (thread_.joinable()) thread_.join();
}

void BusTap::Send(const can_frame& f) {
  boost::asio::post(io_, [this, f] { bus_->Send(f); });
}

std::vector<BusTap::Seen> BusTap::Frames() {
  std::lock_guard<std::mutex> l(mu_);
  return seen_;
}

void BusTap::Clear() {
  std::lock_guard<std::mutex> l(mu_);
  seen_.clear();
}

}  // namespace irslam::testing
