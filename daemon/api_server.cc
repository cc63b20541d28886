// ApiServer's life cycle, the listening socket, accepting (with a back-off
// when out of file descriptors) and admission. A client connection is an
// ApiServer::Session (api_session.cc); the way to the control loop and back is
// api_dispatch.cc; the API thread's CPU share is ApiCpuShare (api_cpu_share.cc).
#include "daemon/api_server.h"

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <algorithm>
#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <future>

#include "daemon/internal/api_cpu_share.h"
#include "daemon/internal/api_session.h"

#ifndef SO_PEERGROUPS
#define SO_PEERGROUPS 59  // Linux >= 4.13 (asm-generic/socket.h)
#endif

namespace irslam {

namespace asio = boost::asio;
using boost::system::error_code;
using Local = asio::local::stream_protocol;
using api_internal::Seconds;

namespace {

// The peer's credentials as the kernel gives them (SO_PEERCRED, SO_PEERGROUPS).
PeerCred ReadPeer(int fd) {
  PeerCred peer;
  ucred cred{};
  socklen_t len = sizeof cred;
  if (::getsockopt(fd, SOL_SOCKET, SO_PEERCRED, &cred, &len) == 0) {
    peer.pid = cred.pid;
    peer.uid = cred.uid;
    peer.gid = cred.gid;
  }
  // The groups the kernel gives the peer's process (supplementary ones included),
  // not what /etc/group says about its user.
  std::vector<gid_t> groups(64);
  socklen_t glen = static_cast<socklen_t>(groups.size() * sizeof(gid_t));
  int r = ::getsockopt(fd, SOL_SOCKET, SO_PEERGROUPS, groups.data(), &glen);
  if (r != 0 && errno == ERANGE) {
    groups.resize(glen / sizeof(gid_t) + 1);
    glen = static_cast<socklen_t>(groups.size() * sizeof(gid_t));
    r = ::getsockopt(fd, SOL_SOCKET, SO_PEERGROUPS, groups.data(), &glen);
  }
  if (r == 0) {
    groups.resize(glen / sizeof(gid_t));
  } else {
    if (errno != ENOPROTOOPT) {
      std::fprintf(stderr, "<4>api: SO_PEERGROUPS: %s: only the primary group counts\n",
                   std::strerror(errno));
    }
    groups.clear();
  }
  if (peer.gid != static_cast<gid_t>(-1) &&
      std::find(groups.begin(), groups.end(), peer.gid) == groups.end()) {
    groups.insert(groups.begin(), peer.gid);
  }
  peer.groups = std::move(groups);
  return peer;
}

// Only a socket nobody listens on may be replaced: never another kind of file.
// True when nothing is at path or it may be replaced (then it is removed).
bool ClearStaleSocket(const std::string& path, std::string* error) {
  struct stat st {};
  if (::lstat(path.c_str(), &st) != 0) return true;
  if (!S_ISSOCK(st.st_mode)) {
    *error = "api: " + path + " exists and is not a socket: refusing to replace it";
    return false;
  }
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  if (path.size() >= sizeof addr.sun_path) {
    *error = "api: socket path too long: " + path;
    return false;
  }
  std::memcpy(addr.sun_path, path.c_str(), path.size() + 1);
  const int probe = ::socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  const int r = probe < 0 ? -1 : ::connect(probe, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
  const int err = errno;
  if (probe >= 0) ::close(probe);
  if (r == 0 || (r < 0 && (err == EAGAIN || err == EINPROGRESS))) {
    *error = "api: another process is already listening on " + path;
    return false;
  }
  ::unlink(path.c_str());
  return true;
}

}  // namespace

size_t MaxClientsForFdLimit() {
  rlimit rl{};
  if (::getrlimit(RLIMIT_NOFILE, &rl) != 0 || rl.rlim_cur == RLIM_INFINITY) return 1024;
  const auto soft = static_cast<size_t>(rl.rlim_cur);
  // One descriptor per client plus the reserved control slot.
  return soft > kReservedFds + 2 ? soft - kReservedFds - 1 : 1;
}

ApiServer::ApiServer(asio::io_context& control, std::string path, ApiLimits limits,
                     Dispatcher* dispatcher)
    : control_(control),
      path_(std::move(path)),
      limits_(limits),
      dispatcher_(dispatcher),
      loop_(std::make_shared<Loop>()),
      counters_(std::make_unique<Counters>()),
      cpu_share_(std::make_unique<ApiCpuShare>(loop_->io, limits_, &counters_->cpu_pauses)),
      accept_timer_(std::make_unique<asio::steady_timer>(loop_->io)) {}

ApiServer::~ApiServer() {
  Close();
  alive_.reset();
  acceptor_.reset();
  cpu_share_.reset();
  accept_timer_.reset();
  sessions_.clear();
  loop_.reset();  // pending handlers (and the sessions they hold) go with it
}

bool ApiServer::Listen(std::string* error, std::optional<gid_t> socket_group) {
  if (limits_.max_line_bytes < 1 || limits_.max_line_bytes > kMaxLineBytesLimit) {
    *error = "api: max_line_bytes " + std::to_string(limits_.max_line_bytes) +
             " is outside 1.." + std::to_string(kMaxLineBytesLimit);
    return false;
  }
  const size_t fd_max = MaxClientsForFdLimit();
  if (limits_.max_clients < 1 || limits_.max_clients > fd_max) {
    *error = "api: max_clients " + std::to_string(limits_.max_clients) +
             " is outside 1.." + std::to_string(fd_max) +
             " (what the file descriptor limit RLIMIT_NOFILE allows)";
    return false;
  }
  if (limits_.max_inflight < 1) limits_.max_inflight = 1;
  if (!ClearStaleSocket(path_, error)) return false;
  acceptor_ = std::make_unique<Local::acceptor>(loop_->io);
  error_code ec;
  acceptor_->open(Local(), ec);
  if (!ec) acceptor_->bind(Local::endpoint(path_), ec);
  if (!ec) acceptor_->listen(16, ec);
  if (ec) {
    *error = "api: cannot listen on " + path_ + ": " + ec.message();
    acceptor_.reset();
    return false;
  }
  ::chmod(path_.c_str(), 0660);
  if (socket_group) {
    // Skipped when the socket already has the group (the daemon's own group
    // under systemd): chown is in @chown, which a unit's filter may forbid.
    struct stat now {};
    const bool has = ::lstat(path_.c_str(), &now) == 0 && now.st_gid == *socket_group;
    if (!has && ::fchownat(AT_FDCWD, path_.c_str(), static_cast<uid_t>(-1), *socket_group,
                           AT_SYMLINK_NOFOLLOW) != 0) {
      *error = "api: cannot give " + path_ + " to group " + std::to_string(*socket_group) + ": " +
               std::strerror(errno) +
               (errno == EINVAL || errno == EPERM
                    ? " (with PrivateUsers=yes only the daemon's own group can be used)"
                    : "");
      acceptor_.reset();
      ::unlink(path_.c_str());
      return false;
    }
  }
  listening_ = true;
  open_ = true;
  accepting_ = true;
  StartThread();
  asio::post(loop_->io, [this] { Accept(); });
  return true;
}

void ApiServer::StartThread() {
  if (thread_.joinable()) return;
  thread_ = std::jthread([loop = loop_] {
    auto guard = asio::make_work_guard(loop->io);
    loop->io.run();
  });
}

void ApiServer::Adopt(int fd, PeerCred peer) {
  open_ = true;
  StartThread();
  asio::post(loop_->io, [this, fd, peer = std::move(peer)]() mutable {
    Local::socket socket(loop_->io);
    error_code ec;
    socket.assign(Local(), fd, ec);
    if (ec) {
      ::close(fd);
      return;
    }
    Admit(std::move(socket), std::move(peer));
  });
}

void ApiServer::Accept() {
  if (!accepting_ || !acceptor_) return;
  acceptor_->async_accept([this](const error_code& ec, Local::socket socket) {
    if (!accepting_) return;
    if (ec == asio::error::no_descriptors || ec.value() == ENFILE ||
        ec == asio::error::no_buffer_space || ec == asio::error::no_memory) {
      BackOff(ec);
      return;
    }
    if (ec == asio::error::operation_aborted) return;
    if (!ec) {
      // Read before the socket is moved (argument order is unspecified).
      PeerCred peer = ReadPeer(socket.native_handle());
      Admit(std::move(socket), std::move(peer));
    }
    Accept();
  });
}

void ApiServer::BackOff(const error_code& ec) {
  // The pending connection stays in the backlog; trying again at once would
  // spin a core. One timer made beforehand: no timer object is created here.
  const uint64_t n = ++counters_->accept_backoffs;
  if (n == 1 || n % 100 == 0) {
    std::fprintf(stderr, "<4>api: cannot accept a client (%s, %llu times): pausing %gs\n",
                 ec.message().c_str(), static_cast<unsigned long long>(n),
                 limits_.accept_backoff_s);
  }
  accept_timer_->expires_after(Seconds(limits_.accept_backoff_s));
  accept_timer_->async_wait([this](const error_code& e) {
    if (!e) Accept();
  });
}

void ApiServer::Admit(Local::socket socket, PeerCred peer) {
  size_t normal = 0;
  bool control_busy = false;
  for (const auto& s : sessions_) {
    if (s->control_only()) {
      control_busy = true;
    } else {
      ++normal;
    }
  }
  bool control_only = false;
  if (normal >= limits_.max_clients) {
    // Full: the client idle longest makes room (slowloris, silent subscribers);
    // when every client has a request at the control loop, the reserved slot
    // takes the newcomer for start/stop only.
    std::shared_ptr<Session> victim;
    for (const auto& s : sessions_) {
      if (s->control_only() || !s->idle()) continue;
      if (!victim || s->last_request() < victim->last_request()) victim = s;
    }
    if (victim) {
      ++counters_->evicted_idle;
      victim->Evict("closed to admit a new client: the server is full and this client was idle longest");
    } else if (!control_busy) {
      control_only = true;
      ++counters_->control_slot;
    } else {
      ++counters_->rejected_full;
      api_internal::SendAndForget(
          socket.native_handle(),
          rpc::MessageText(rpc::MakeError(nullptr, rpc::kRejected, "too many clients")));
      error_code ignored;
      socket.close(ignored);
      return;
    }
  }
  ++counters_->accepted;
  auto s = std::make_shared<Session>(this, std::move(socket), std::move(peer), control_only);
  sessions_.push_back(s);
  clients_ = sessions_.size();
  s->Start();
}

void ApiServer::Remove(Session* s) {
  sessions_.remove_if([s](const std::shared_ptr<Session>& p) { return p.get() == s; });
  clients_ = sessions_.size();
}

void ApiServer::Close() {
  if (!open_) return;
  open_ = false;
  if (thread_.joinable()) {
    std::promise<void> done;
    asio::post(loop_->io, [this, &done] {
      accepting_ = false;
      error_code ec;
      if (acceptor_) acceptor_->close(ec);
      auto copy = sessions_;
      for (auto& s : copy) s->Close();
      cpu_share_->Cancel();
      accept_timer_->cancel();
      done.set_value();
    });
    done.get_future().wait();
    loop_->io.stop();
    thread_.join();
  }
  if (listening_) {
    listening_ = false;
    ::unlink(path_.c_str());
  }
}

ApiStats ApiServer::stats() const {
  const Counters& c = *counters_;
  ApiStats s;
  s.accepted = c.accepted;
  s.rejected_full = c.rejected_full;
  s.requests = c.requests;
  s.errors = c.errors;
  s.dropped_slow = c.dropped_slow;
  s.dropped_long_line = c.dropped_long_line;
  s.dropped_idle = c.dropped_idle;
  s.dropped_line_timeout = c.dropped_line_timeout;
  s.evicted_idle = c.evicted_idle;
  s.control_slot = c.control_slot;
  s.accept_backoffs = c.accept_backoffs;
  s.coalesced = c.coalesced;
  s.paused = c.paused;
  s.cpu_pauses = c.cpu_pauses;
  return s;
}

nlohmann::json ApiServer::StatsJson() const {
  const ApiStats a = stats();
  return {{"clients", client_count()},
          {"requests", a.requests},
          {"errors", a.errors},
          {"dropped_slow", a.dropped_slow},
          {"dropped_long_line", a.dropped_long_line},
          {"dropped_idle", a.dropped_idle},
          {"dropped_line_timeout", a.dropped_line_timeout},
          {"rejected_full", a.rejected_full},
          {"evicted_idle", a.evicted_idle},
          {"control_slot", a.control_slot},
          {"accept_backoffs", a.accept_backoffs},
          {"coalesced", a.coalesced},
          {"paused", a.paused},
          {"cpu_pauses", a.cpu_pauses}};
}

}  // namespace irslam
