// A node on a CAN bus for tests: records every frame with its arrival time and
// can inject frames (like candump/cansend beside the real nodes).
#ifndef IRSLAM_TESTS_TESTING_BUS_TAP_H_
#define IRSLAM_TESTS_TESTING_BUS_TAP_H_

#include <linux/can.h>

#include <boost/asio/io_context.hpp>
#include <chrono>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "drivers/can_bus.h"

namespace irslam::testing {

class BusTap {
 public:
  struct Seen {
    can_frame frame;
    std::chrono::steady_clock::time_point at;
  };
  explicit BusTap(const std::string& iface);
  ~BusTap();
  bool ok() const { return bus_ != nullptr; }
  const std::string& error() const { return error_; }
  void Send(const can_frame& f);
  std::vector<Seen> Frames();
  void Clear();

 private:
  boost::asio::io_context io_;
  std::unique_ptr<drivers::CanBus> bus_;
  std::string error_;
  std::mutex mu_;
  std::vector<Seen> seen_;
  std::thread thread_;
};

}  // namespace irslam::testing

#endif  // IRSLAM_TESTS_TESTING_BUS_TAP_H_
