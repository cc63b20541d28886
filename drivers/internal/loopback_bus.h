#ifndef IRSLAM_DRIVERS_INTERNAL_LOOPBACK_BUS_H_
#define IRSLAM_DRIVERS_INTERNAL_LOOPBACK_BUS_H_

#include <boost/asio/posix/stream_descriptor.hpp>
#include <memory>
#include <string>
#include <vector>

#include "drivers/can_bus.h"

namespace irslam::drivers {

class LoopbackBus final : public CanBus {
 public:
  LoopbackBus(boost::asio::io_context& io, std::string dir, std::vector<uint32_t> ids);
  ~LoopbackBus() override;

  bool Open(std::string* error);
  void Start(FrameHandler handler) override;
  bool Send(const can_frame& frame) override;
  void Close() override;
  const CanStats& stats() const override { return stats_; }
  std::string name() const override { return "unix:" + dir_; }

 private:
  static constexpr size_t kMaxBatch = 64;

  void WaitRead();
  void Drain();
  void Flush();
  void SendBatch(const can_frame* frames, size_t count);
  void RefreshPeers();
  bool Wanted(uint32_t id) const;

  std::string dir_;
  std::vector<uint32_t> ids_;
  boost::asio::posix::stream_descriptor descriptor_;
  FrameHandler handler_;
  CanStats stats_;
  std::string own_name_;
  std::string own_path_;
  std::vector<std::string> peers_;
  double peers_mtime_ = 0;
  bool peers_valid_ = false;
  bool open_ = false;
  std::vector<can_frame> pending_;
  bool flush_posted_ = false;
  std::shared_ptr<bool> alive_ = std::make_shared<bool>(true);
};

class SocketCanBus final : public CanBus {
 public:
  SocketCanBus(boost::asio::io_context& io, std::string iface, std::vector<uint32_t> ids);
  ~SocketCanBus() override;

  bool Open(std::string* error);
  void Start(FrameHandler handler) override;
  bool Send(const can_frame& frame) override;
  void Close() override;
  const CanStats& stats() const override { return stats_; }
  std::string name() const override { return iface_; }

 private:
  void WaitRead();
  void Drain();
  void HandleErrorFrame(const can_frame& f);
  void SetLink(bool up, const char* why);

  std::string iface_;
  std::vector<uint32_t> ids_;
  boost::asio::posix::stream_descriptor descriptor_;
  FrameHandler handler_;
  CanStats stats_;
  uint32_t last_drop_count_ = 0;
  bool open_ = false;
};

}  // namespace irslam::drivers

#endif  // IRSLAM_DRIVERS_INTERNAL_LOOPBACK_BUS_H_
