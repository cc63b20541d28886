// Loopback CAN bus over Unix datagram sockets (see can_bus.h).
//
// PATH is a directory; each node binds one SOCK_DGRAM socket "node-<pid>-<fd>" in it.
// Sending a frame sends the 16-byte struct can_frame to every other socket in the
// directory. Frames sent in one turn of the event loop travel together in one
// datagram (a whole number of can_frames, at most kMaxBatch): the kernel limits a
// datagram socket's queue to net.unix.max_dgram_qlen datagrams (10 by default),
// which one frame per datagram would overflow in any burst. A node whose queue is
// still full gets its frames a little later, in order (bounded, kMaxBacklogFrames),
// as a vcan socket's receive buffer would hold them. The peer list is re-read whenever the directory changed (its mtime,
// compared conservatively because the kernel stamps it with a coarse clock), so a
// node that joined is reached by the very next frame. A peer that died leaves a
// socket file nobody listens on: sendto() says ECONNREFUSED and we unlink it.
#include "drivers/internal/loopback_bus.h"

#include <dirent.h>
#include <fcntl.h>
#include <sys/socket.h>
#include <sys/uio.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <ctime>

#include <boost/asio/post.hpp>

namespace irslam::drivers {
namespace {

bool MakeAddr(const std::string& path, sockaddr_un* addr, socklen_t* len) {
  std::memset(addr, 0, sizeof(*addr));
  addr->sun_family = AF_UNIX;
  if (path.size() >= sizeof(addr->sun_path)) return false;
  std::memcpy(addr->sun_path, path.data(), path.size());
  *len = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + path.size() + 1);
  return true;
}

}  // namespace

LoopbackBus::LoopbackBus(boost::asio::io_context& io, std::string dir, std::vector<uint32_t> ids)
    : DescriptorBus(io), dir_(std::move(dir)), ids_(std::move(ids)), retry_timer_(io) {}

LoopbackBus::~LoopbackBus() { Close(); }

bool LoopbackBus::Open(std::string* error) {
  if (::mkdir(dir_.c_str(), 0770) != 0 && errno != EEXIST) {
    *error = "can: cannot create loopback bus directory " + dir_ + ": " + std::strerror(errno);
    return false;
  }
  struct stat st{};
  if (::stat(dir_.c_str(), &st) != 0 || !S_ISDIR(st.st_mode)) {
    *error = "can: loopback bus path " + dir_ + " is not a directory";
    return false;
  }
  const int fd = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) {
    *error = std::string("can: socket(AF_UNIX): ") + std::strerror(errno);
    return false;
  }
  own_name_ = "node-" + std::to_string(::getpid()) + "-" + std::to_string(fd);
  own_path_ = dir_ + "/" + own_name_;
  sockaddr_un addr;
  socklen_t len;
  if (!MakeAddr(own_path_, &addr, &len)) {
    ::close(fd);
    *error = "can: loopback bus path too long for a Unix socket: " + own_path_;
    return false;
  }
  ::unlink(own_path_.c_str());
  if (::bind(fd, reinterpret_cast<sockaddr*>(&addr), len) != 0) {
    *error = "can: bind " + own_path_ + ": " + std::strerror(errno);
    ::close(fd);
    return false;
  }
  int rcvbuf = 1 << 20;
  ::setsockopt(fd, SOL_SOCKET, SO_RCVBUF, &rcvbuf, sizeof rcvbuf);
  // Each datagram's kernel receive time, as SocketCAN gives (a polled reader
  // drains a period's frames at once and must not stamp them all "now").
  int on = 1;
  stats_.kernel_timestamps = ::setsockopt(fd, SOL_SOCKET, SO_TIMESTAMPNS, &on, sizeof on) == 0;
  descriptor_.assign(fd);
  open_ = true;
  return true;
}

bool LoopbackBus::Wanted(uint32_t id) const {
  if (ids_.empty()) return true;
  if (id & (CAN_EFF_FLAG | CAN_ERR_FLAG)) return false;
  for (uint32_t w : ids_) {
    if ((id & CAN_SFF_MASK) == w) return true;
  }
  return false;
}

void LoopbackBus::Drain() {
  // recvmmsg: a period's datagrams (the controller's IR and encoder batches) in
  // one call, and a short count means drained: no extra call to see EAGAIN.
  RecvBurst<can_frame[kMaxBatch + 1], CMSG_SPACE(sizeof(timespec)), 8> burst;
  for (int i = 0; i < 64 && open_; ++i) {
    const int got = burst.Receive(fd());
    if (got < 0) {
      if (errno == EINTR) continue;
      return;  // EAGAIN: drained
    }
    for (int k = 0; k < got && open_; ++k) {
      Deliver(burst.slots[k].data, burst.msgs[k].msg_len, &burst.msgs[k].msg_hdr);
    }
    if (got < burst.size()) return;  // fewer than asked: nothing more queued
  }
}

void LoopbackBus::Deliver(const can_frame* batch, size_t bytes, msghdr* msg) {
  if (bytes == 0 || bytes % sizeof(can_frame) != 0 || bytes > kMaxBatch * sizeof(can_frame)) {
    ++stats_.rx_dropped;  // not a whole number of CAN_MTU frames: not ours
    return;
  }
  timespec ts{};
  bool stamped = false;
  for (cmsghdr* c = CMSG_FIRSTHDR(msg); c != nullptr; c = CMSG_NXTHDR(msg, c)) {
    if (c->cmsg_level == SOL_SOCKET && c->cmsg_type == SO_TIMESTAMPNS) {
      std::memcpy(&ts, CMSG_DATA(c), sizeof ts);
      stamped = true;
    }
  }
  if (!stamped) ::clock_gettime(CLOCK_REALTIME, &ts);
  const double rx = static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
  const size_t count = bytes / sizeof(can_frame);
  for (size_t k = 0; k < count && open_; ++k) {
    if (!Wanted(batch[k].can_id)) {
      ++stats_.filtered;
      continue;
    }
    ++stats_.rx_frames;
    stats_.last_rx_time = rx;
    if (handler_) handler_(batch[k], rx);
  }
}

void LoopbackBus::RefreshPeers() {
  struct stat st{};
  if (::stat(dir_.c_str(), &st) != 0) return;
  timespec now;
  ::clock_gettime(CLOCK_REALTIME, &now);
  const double mtime = static_cast<double>(st.st_mtim.tv_sec) + 1e-9 * static_cast<double>(st.st_mtim.tv_nsec);
  const double t_now = static_cast<double>(now.tv_sec) + 1e-9 * static_cast<double>(now.tv_nsec);
  // The directory's mtime has coarse (jiffy) resolution: while it is recent, a
  // second change could hide behind an equal stamp, so re-read every time then.
  if (peers_valid_ && mtime == peers_mtime_ && t_now - mtime > 0.05) return;
  peers_mtime_ = mtime;
  peers_valid_ = true;
  peers_.clear();
  DIR* d = ::opendir(dir_.c_str());
  if (d == nullptr) return;
  while (dirent* e = ::readdir(d)) {
    if (std::strncmp(e->d_name, "node-", 5) != 0) continue;
    if (own_name_ == e->d_name) continue;
    peers_.push_back(dir_ + "/" + e->d_name);
  }
  ::closedir(d);
}

bool LoopbackBus::Send(const can_frame& frame) {
  if (!open_) {
    ++stats_.tx_dropped;
    return false;
  }
  pending_.push_back(frame);
  if (!flush_posted_) {
    flush_posted_ = true;
    boost::asio::post(descriptor_.get_executor(), [this, alive = alive_] {
      if (*alive) Flush();
    });
  }
  return true;
}

bool LoopbackBus::SendNow(const std::vector<can_frame>& frames) {
  if (!open_) {
    stats_.tx_dropped += frames.size();
    return frames.empty();
  }
  // Behind anything Send queued earlier in this turn; the posted flush then finds nothing.
  pending_.insert(pending_.end(), frames.begin(), frames.end());
  Flush();
  return true;
}

void LoopbackBus::Flush() {
  flush_posted_ = false;
  for (size_t off = 0; off < pending_.size(); off += kMaxBatch) {
    const size_t count = std::min(kMaxBatch, pending_.size() - off);
    SendBatch(pending_.data() + off, count);
  }
  pending_.clear();
}

int LoopbackBus::SendTo(const std::string& peer, const std::vector<can_frame>& batch) {
  sockaddr_un addr;
  socklen_t len;
  if (!MakeAddr(peer, &addr, &len)) return -1;
  const ssize_t n = ::sendto(fd(), batch.data(), batch.size() * sizeof(can_frame),
                             MSG_DONTWAIT | MSG_NOSIGNAL, reinterpret_cast<sockaddr*>(&addr), len);
  if (n >= 0) return 1;
  if (errno == ECONNREFUSED || errno == ENOENT) {
    // A node that died without cleaning up (ECONNREFUSED) or just left (ENOENT).
    if (errno == ECONNREFUSED) ::unlink(peer.c_str());
    return -1;
  }
  return 0;  // EAGAIN: that node's receive queue is full
}

void LoopbackBus::SendBatch(const can_frame* frames, size_t count) {
  if (!open_) {
    stats_.tx_dropped += count;
    return;
  }
  RefreshPeers();
  const std::vector<can_frame> batch(frames, frames + count);
  for (size_t i = 0; i < peers_.size();) {
    auto& held = backlog_[peers_[i]];
    // Frames stay in order: behind what is already held for that node.
    const int r = held.empty() ? SendTo(peers_[i], batch) : 0;
    if (r < 0) {
      backlog_.erase(peers_[i]);
      peers_.erase(peers_.begin() + static_cast<std::ptrdiff_t>(i));
      continue;
    }
    if (r == 0) {
      // A node that is not keeping up: its frames wait (bounded, like a
      // socket's receive buffer), and are sent as soon as it has room.
      held.push_back(batch);
      size_t frames_held = 0;
      for (const auto& b : held) frames_held += b.size();
      while (frames_held > kMaxBacklogFrames) {
        frames_held -= held.front().size();
        stats_.tx_dropped += held.front().size();
        held.pop_front();
      }
      ArmRetry();
    }
    ++i;
  }
  stats_.tx_frames += count;
}

void LoopbackBus::RetryBacklog() {
  bool again = false;
  for (auto it = backlog_.begin(); it != backlog_.end();) {
    auto& held = it->second;
    int r = 1;
    while (!held.empty() && (r = SendTo(it->first, held.front())) == 1) held.pop_front();
    if (r < 0) {
      stats_.tx_dropped += held.size();
      it = backlog_.erase(it);
      continue;
    }
    again |= !held.empty();
    ++it;
  }
  if (again && open_) ArmRetry();
}

void LoopbackBus::ArmRetry() {
  if (retry_armed_) return;
  retry_armed_ = true;
  retry_timer_.expires_after(std::chrono::milliseconds(1));
  retry_timer_.async_wait([this, alive = alive_](const boost::system::error_code& ec) {
    if (ec || !*alive) return;
    retry_armed_ = false;
    RetryBacklog();
  });
}

void LoopbackBus::Close() {
  if (!open_) return;
  Flush();  // frames sent just before closing (the stop command) still go out
  RetryBacklog();
  open_ = false;
  retry_timer_.cancel();
  *alive_ = false;
  CloseFd();
  ::unlink(own_path_.c_str());
}

}  // namespace irslam::drivers
