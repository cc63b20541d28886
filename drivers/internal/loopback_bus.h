#ifndef IRSLAM_DRIVERS_INTERNAL_LOOPBACK_BUS_H_
#define IRSLAM_DRIVERS_INTERNAL_LOOPBACK_BUS_H_

#include <sys/socket.h>
#include <unistd.h>

#include <boost/asio/posix/stream_descriptor.hpp>
#include <boost/asio/steady_timer.hpp>
#include <deque>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "drivers/can_bus.h"

namespace irslam::drivers {

// Receive buffers for recvmmsg: up to kCount messages read in one call, each
// into its own Payload and control (cmsg) buffer of kCtrlBytes. A count below
// kCount means the socket held no more.
template <typename Payload, size_t kCtrlBytes, unsigned kCount>
struct RecvBurst {
  struct Slot {
    Payload data;
    alignas(cmsghdr) char ctrl[kCtrlBytes];
  };
  Slot slots[kCount];
  iovec iov[kCount];
  mmsghdr msgs[kCount];

  // Reads without blocking: the number of messages read (msgs[k].msg_len bytes
  // into slots[k].data), or -1 with errno set.
  int Receive(int fd) {
    for (unsigned k = 0; k < kCount; ++k) {
      iov[k] = iovec{&slots[k].data, sizeof slots[k].data};
      msgs[k] = mmsghdr{};
      msgs[k].msg_hdr.msg_iov = &iov[k];
      msgs[k].msg_hdr.msg_iovlen = 1;
      msgs[k].msg_hdr.msg_control = slots[k].ctrl;
      msgs[k].msg_hdr.msg_controllen = sizeof slots[k].ctrl;
    }
    return ::recvmmsg(fd, msgs, kCount, MSG_DONTWAIT, nullptr);
  }
  static constexpr int size() { return static_cast<int>(kCount); }
};

// What both backends share: a non-blocking fd, drained of all it holds each time
// it becomes readable (Start: on the io_context) or when polled (StartPolled).
class DescriptorBus : public CanBus {
 public:
  explicit DescriptorBus(boost::asio::io_context& io) : descriptor_(io) {}
  void Start(FrameHandler handler) override {
    handler_ = std::move(handler);
    WaitRead();
  }
  void StartPolled(FrameHandler handler) override {
    handler_ = std::move(handler);
    // Off the io_context's reactor: asio keeps an assigned descriptor in epoll
    // whether or not a wait is pending, so every datagram would still wake the
    // loop, only for it to find nothing to do.
    if (descriptor_.is_open()) polled_fd_ = descriptor_.release();
  }
  void Poll() override {
    if (open_) Drain();
  }
  const CanStats& stats() const override { return stats_; }

 protected:
  // The socket, on the reactor (Start) or off it (StartPolled).
  int fd() { return polled_fd_ >= 0 ? polled_fd_ : descriptor_.native_handle(); }
  void CloseFd() {
    boost::system::error_code ec;
    descriptor_.cancel(ec);
    descriptor_.close(ec);
    if (polled_fd_ >= 0) ::close(polled_fd_);
    polled_fd_ = -1;
  }
  // Reads until the fd would block, delivering frames to handler_.
  virtual void Drain() = 0;
  void WaitRead() {
    if (!open_) return;
    descriptor_.async_wait(boost::asio::posix::stream_descriptor::wait_read,
                           [this](const boost::system::error_code& ec) {
                             if (ec || !open_) return;
                             Drain();
                             WaitRead();
                           });
  }

  boost::asio::posix::stream_descriptor descriptor_;
  int polled_fd_ = -1;  // the socket, released from descriptor_ by StartPolled
  FrameHandler handler_;
  CanStats stats_;
  bool open_ = false;
};

class LoopbackBus final : public DescriptorBus {
 public:
  LoopbackBus(boost::asio::io_context& io, std::string dir, std::vector<uint32_t> ids);
  ~LoopbackBus() override;

  bool Open(std::string* error);
  bool Send(const can_frame& frame) override;
  bool SendNow(const std::vector<can_frame>& frames) override;
  void Close() override;
  std::string name() const override { return "unix:" + dir_; }

 private:
  static constexpr size_t kMaxBatch = 64;
  // Frames held for a node whose receive queue is full, like the receive buffer
  // of a vcan socket (~300 frames of 212992 bytes); beyond it the oldest are lost.
  static constexpr size_t kMaxBacklogFrames = 512;

  void Drain() override;
  // One received datagram's frames (msg: its header, for the receive time).
  void Deliver(const can_frame* batch, size_t bytes, msghdr* msg);
  void Flush();
  void SendBatch(const can_frame* frames, size_t count);
  // sendto() one datagram to one peer: 1 sent, 0 queue full, -1 the peer is gone.
  int SendTo(const std::string& peer, const std::vector<can_frame>& batch);
  void RetryBacklog();
  void ArmRetry();
  void RefreshPeers();
  bool Wanted(uint32_t id) const;

  std::string dir_;
  std::vector<uint32_t> ids_;
  std::string own_name_;
  std::string own_path_;
  std::vector<std::string> peers_;
  double peers_mtime_ = 0;
  bool peers_valid_ = false;
  std::vector<can_frame> pending_;
  bool flush_posted_ = false;
  std::map<std::string, std::deque<std::vector<can_frame>>> backlog_;  // per peer
  boost::asio::steady_timer retry_timer_;
  bool retry_armed_ = false;
  std::shared_ptr<bool> alive_ = std::make_shared<bool>(true);
};

class SocketCanBus final : public DescriptorBus {
 public:
  SocketCanBus(boost::asio::io_context& io, std::string iface, std::vector<uint32_t> ids);
  ~SocketCanBus() override;

  bool Open(std::string* error);
  bool Send(const can_frame& frame) override;
  void Close() override;
  std::string name() const override { return iface_; }

 private:
  void Drain() override;
  // One received frame (msg: its header, for the receive time and drop count).
  void Deliver(const can_frame& f, size_t bytes, msghdr* msg);
  void HandleErrorFrame(const can_frame& f);
  void SetLink(bool up, const char* why);

  std::string iface_;
  std::vector<uint32_t> ids_;
  uint32_t last_drop_count_ = 0;
};

}  // namespace irslam::drivers

#endif  // IRSLAM_DRIVERS_INTERNAL_LOOPBACK_BUS_H_
