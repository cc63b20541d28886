// SocketCAN backend (see can_bus.h): one raw CAN socket, non-blocking, on the
// io_context. Kernel-side id filter (CAN_RAW_FILTER), error frames
// (CAN_RAW_ERR_FILTER: bus-off, controller and protocol errors), kernel drop
// counter (SO_RXQ_OVFL) and receive timestamps (SO_TIMESTAMP). ENETDOWN is
// "interface down": reported in the stats, the socket stays open, and frames flow
// again when the interface comes back up.
#include <linux/can/error.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "drivers/internal/loopback_bus.h"

#ifndef AF_CAN
#define AF_CAN 29
#endif

namespace irslam::drivers {

SocketCanBus::SocketCanBus(boost::asio::io_context& io, std::string iface,
                           std::vector<uint32_t> ids)
    : DescriptorBus(io), iface_(std::move(iface)), ids_(std::move(ids)) {}

SocketCanBus::~SocketCanBus() { Close(); }

bool SocketCanBus::Open(std::string* error) {
  if (iface_.empty() || iface_.size() >= IFNAMSIZ) {
    *error = "can: interface name '" + iface_ + "' is empty or longer than " +
             std::to_string(IFNAMSIZ - 1) + " characters";
    return false;
  }
  const int fd = ::socket(AF_CAN, SOCK_RAW | SOCK_NONBLOCK | SOCK_CLOEXEC, CAN_RAW);
  if (fd < 0) {
    if (errno == EAFNOSUPPORT || errno == EPROTONOSUPPORT || errno == EINVAL) {
      *error = "can: this kernel has no CAN support (socket(AF_CAN): " +
               std::string(std::strerror(errno)) +
               "); load can/can_raw/vcan or use the loopback bus: --can unix:/run/irslam/bus";
    } else {
      *error = std::string("can: socket(AF_CAN): ") + std::strerror(errno);
    }
    return false;
  }
  const unsigned ifindex = ::if_nametoindex(iface_.c_str());
  if (ifindex == 0) {
    *error = "can: no such interface '" + iface_ + "' (create it: vcan-scripts/vcan-up.sh " +
             iface_ + ")";
    ::close(fd);
    return false;
  }
  if (!ids_.empty()) {
    std::vector<can_filter> filters;
    for (uint32_t id : ids_) {
      filters.push_back({id, CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG});
    }
    ::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_FILTER, filters.data(),
                 static_cast<socklen_t>(filters.size() * sizeof(can_filter)));
  }
  const can_err_mask_t err_mask = CAN_ERR_TX_TIMEOUT | CAN_ERR_CRTL | CAN_ERR_PROT |
                                  CAN_ERR_ACK | CAN_ERR_BUSOFF | CAN_ERR_BUSERROR |
                                  CAN_ERR_RESTARTED;
  ::setsockopt(fd, SOL_CAN_RAW, CAN_RAW_ERR_FILTER, &err_mask, sizeof err_mask);
  const int one = 1;
  ::setsockopt(fd, SOL_SOCKET, SO_RXQ_OVFL, &one, sizeof one);
  ::setsockopt(fd, SOL_SOCKET, SO_TIMESTAMP, &one, sizeof one);

  sockaddr_can addr{};
  addr.can_family = AF_CAN;
  addr.can_ifindex = static_cast<int>(ifindex);
  if (::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    *error = "can: bind " + iface_ + ": " + std::strerror(errno);
    ::close(fd);
    return false;
  }
  descriptor_.assign(fd);
  open_ = true;
  return true;
}

void SocketCanBus::SetLink(bool up, const char* why) {
  if (stats_.link_up && !up) {
    ++stats_.link_down_events;
    stats_.last_error = why;
    std::fprintf(stderr, "<4>can: interface down iface=%s (%s)\n", iface_.c_str(), why);
  } else if (!stats_.link_up && up) {
    std::fprintf(stderr, "<5>can: interface up again iface=%s\n", iface_.c_str());
  }
  stats_.link_up = up;
}

void SocketCanBus::HandleErrorFrame(const can_frame& f) {
  ++stats_.error_frames;
  char buf[96];
  if (f.can_id & CAN_ERR_BUSOFF) {
    ++stats_.bus_off;
    std::snprintf(buf, sizeof buf, "bus-off");
  } else if (f.can_id & CAN_ERR_CRTL) {
    std::snprintf(buf, sizeof buf, "controller error 0x%02x", f.data[1]);
  } else if (f.can_id & CAN_ERR_PROT) {
    std::snprintf(buf, sizeof buf, "protocol error 0x%02x/0x%02x", f.data[2], f.data[3]);
  } else {
    std::snprintf(buf, sizeof buf, "error frame id=0x%08x", f.can_id);
  }
  stats_.last_error = buf;
  std::fprintf(stderr, "<4>can: %s iface=%s\n", buf, iface_.c_str());
}

void SocketCanBus::Drain() {
  // recvmmsg: up to 16 frames per call (a period's IR and encoder frames in
  // one or two calls instead of one each), and a short count means drained.
  constexpr size_t kCtrl = CMSG_SPACE(sizeof(timeval)) + CMSG_SPACE(sizeof(uint32_t));
  RecvBurst<can_frame, kCtrl, 16> burst;
  for (int i = 0; i < 256 / burst.size(); ++i) {
    const int got = burst.Receive(fd());
    if (got < 0) {
      if (errno == EINTR) continue;
      if (errno == ENETDOWN) {
        SetLink(false, "ENETDOWN on receive");
      }
      return;
    }
    if (got > 0) SetLink(true, "");
    for (int k = 0; k < got; ++k) {
      Deliver(burst.slots[k].data, burst.msgs[k].msg_len, &burst.msgs[k].msg_hdr);
    }
    if (got < burst.size()) return;  // fewer than asked: nothing more queued
  }
}

void SocketCanBus::Deliver(const can_frame& f, size_t bytes, msghdr* msg) {
  if (bytes != CAN_MTU) return;  // CAN FD or truncated: not ours
  double rx_time = 0;
  for (cmsghdr* c = CMSG_FIRSTHDR(msg); c != nullptr; c = CMSG_NXTHDR(msg, c)) {
    if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_TIMESTAMP) {
      timeval tv;
      std::memcpy(&tv, CMSG_DATA(c), sizeof tv);
      rx_time = static_cast<double>(tv.tv_sec) + 1e-6 * static_cast<double>(tv.tv_usec);
    } else if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_RXQ_OVFL) {
      uint32_t drops;
      std::memcpy(&drops, CMSG_DATA(c), sizeof drops);
      if (drops != last_drop_count_) {
        stats_.rx_dropped += drops - last_drop_count_;
        std::fprintf(stderr, "<4>can: rx drop count=%u iface=%s\n", drops, iface_.c_str());
        last_drop_count_ = drops;
      }
    }
  }
  if (f.can_id & CAN_ERR_FLAG) {
    HandleErrorFrame(f);
    return;
  }
  ++stats_.rx_frames;
  if (rx_time > 0) {
    stats_.last_rx_time = rx_time;
    stats_.kernel_timestamps = true;
  }
  if (handler_) handler_(f, rx_time);
}

bool SocketCanBus::Send(const can_frame& frame) {
  if (!open_) {
    ++stats_.tx_dropped;
    return false;
  }
  const ssize_t n = ::send(fd(), &frame, CAN_MTU, MSG_DONTWAIT);
  if (n == static_cast<ssize_t>(CAN_MTU)) {
    SetLink(true, "");
    ++stats_.tx_frames;
    return true;
  }
  ++stats_.tx_dropped;
  if (n < 0 && errno == ENETDOWN) {
    SetLink(false, "ENETDOWN on send");
  } else if (n < 0) {
    stats_.last_error = std::string("send: ") + std::strerror(errno);
  }
  return false;
}

void SocketCanBus::Close() {
  if (!open_) return;
  open_ = false;
  CloseFd();
}

std::unique_ptr<CanBus> OpenCanBus(boost::asio::io_context& io, const CanBusOptions& options,
                                   std::string* error) {
  if (options.iface.rfind("unix:", 0) == 0) {
    auto bus = std::make_unique<LoopbackBus>(io, options.iface.substr(5), options.rx_ids);
    if (!bus->Open(error)) return nullptr;
    return bus;
  }
  auto bus = std::make_unique<SocketCanBus>(io, options.iface, options.rx_ids);
  if (!bus->Open(error)) return nullptr;
  return bus;
}

}  // namespace irslam::drivers
