#include "daemon/api_server.h"

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <array>
#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/post.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/write.hpp>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <deque>
#include <future>

#include "io/json_text.h"

#ifndef SO_PEERGROUPS
#define SO_PEERGROUPS 59  // Linux >= 4.13 (asm-generic/socket.h)
#endif

namespace irslam {

namespace asio = boost::asio;
using boost::system::error_code;
using Local = asio::local::stream_protocol;
using Clock = std::chrono::steady_clock;

namespace {

// A subscription period longer than a day is a day (1/rate of a tiny rate
// overflowed the clock's duration and sent notifications unthrottled).
constexpr double kMaxSubscriptionPeriodS = 86400;

Clock::duration Seconds(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

bool IsControlMethod(const std::string& m) { return m == "start" || m == "stop" || m == "clean"; }

// The rate a subscribe request asks for, or nullopt when it is not a number in (0, max].
std::optional<double> SubscribeRate(const nlohmann::json& params, double max_rate_hz) {
  const auto it = params.find("rate");
  if (it == params.end()) return std::min(5.0, max_rate_hz);
  if (!it->is_number()) return std::nullopt;
  const double rate = it->get<double>();
  if (!(rate > 0) || !(rate <= max_rate_hz)) return std::nullopt;  // NaN fails both
  return rate;
}

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

// Best effort, never blocks: one line to a client that is being closed.
void SendAndForget(int fd, const std::string& text) {
  const std::string line = text + "\n";
  (void)::send(fd, line.data(), line.size(), MSG_DONTWAIT | MSG_NOSIGNAL);
}

}  // namespace

size_t MaxClientsForFdLimit() {
  rlimit rl{};
  if (::getrlimit(RLIMIT_NOFILE, &rl) != 0 || rl.rlim_cur == RLIM_INFINITY) return 1024;
  const auto soft = static_cast<size_t>(rl.rlim_cur);
  // One descriptor per client plus the reserved control slot.
  return soft > kReservedFds + 2 ? soft - kReservedFds - 1 : 1;
}

struct ApiServer::Loop {
  asio::io_context io{1};
};

struct ApiServer::Counters {
  std::atomic<uint64_t> accepted{0}, rejected_full{0}, requests{0}, errors{0}, dropped_slow{0},
      dropped_long_line{0}, dropped_idle{0}, dropped_line_timeout{0}, evicted_idle{0},
      control_slot{0}, accept_backoffs{0}, coalesced{0}, paused{0}, cpu_pauses{0};
};

// Lives on the API thread: every member function runs there.
class ApiServer::Session : public std::enable_shared_from_this<Session> {
 public:
  Session(ApiServer* server, Local::socket socket, PeerCred peer, bool control_only)
      : server_(server),
        limits_(server->limits_),
        socket_(std::move(socket)),
        peer_(std::move(peer)),
        control_only_(control_only),
        idle_timer_(server->loop_->io),
        line_timer_(server->loop_->io),
        sub_timer_(server->loop_->io),
        last_request_(Clock::now()) {}

  void Start() {
    ArmIdle();
    ReadMore();
  }

  void Close() {
    if (closed_) return;
    closed_ = true;
    error_code ec;
    idle_timer_.cancel();
    line_timer_.cancel();
    sub_timer_.cancel();
    socket_.shutdown(Local::socket::shutdown_both, ec);
    socket_.close(ec);
    server_->Remove(this);
  }

  // Closed at once to make room (or for a broken rule), with a last line if it fits.
  void Evict(const std::string& why) {
    if (closed_) return;
    SendAndForget(socket_.native_handle(),
                  rpc::MessageText(rpc::MakeError(nullptr, rpc::kRejected, why)));
    Close();
  }

  // Goes on after a pause for the API thread's CPU budget.
  // It may handle one line whatever the budget: every waiting client makes
  // progress in every window (a `stop` waits at most one window).
  void Resume() {
    deferred_ = false;
    turn_ = true;
    Continue();
  }

  // No request of this client is waiting for the control loop.
  bool idle() const { return at_control_ == 0; }
  bool control_only() const { return control_only_; }
  Clock::time_point last_request() const { return last_request_; }

  // The control loop's answer to one of this client's requests (request null:
  // a notification payload).
  void OnAnswer(const std::shared_ptr<const rpc::Request>& req, Outcome o) {
    if (!req) {
      notify_pending_ = false;
      if (!closed_ && o.result) Send(server_->SharedText(o.key, o.result));
      return;
    }
    --at_control_;
    if (closed_) return;
    const bool error = !o.result && o.response.contains("error");
    if (error) ++server_->counters_->errors;
    if (!error && req->method == "subscribe") {
      StartSubscription(SubscribeRate(req->params, limits_.max_rate_hz).value_or(1));
    }
    if (!req->notification) {
      Send(o.result ? rpc::ResultText(req->id, server_->SharedText(o.key, o.result))
                    : rpc::MessageText(o.response));
    }
    if (control_only_) close_after_write_ = true;
    Continue();
  }

 private:
  size_t InFlight() const { return at_control_ + queue_.size(); }

  // After anything that may have freed budget: handle buffered lines, read on, or finish.
  void Continue() {
    if (closed_) return;
    ProcessLines();
    ReadMore();
    MaybeFinish();
  }

  void MaybeFinish() {
    if (closed_ || writing_ || !queue_.empty()) return;
    // Requests already at the control loop are answered first (a `stop` in the
    // reserved slot followed by something else still gets its reply).
    if ((close_after_write_ || eof_) && at_control_ == 0) Close();
  }

  void ArmIdle() {
    idle_timer_.expires_after(Seconds(limits_.idle_timeout_s));
    idle_timer_.async_wait([self = shared_from_this()](const error_code& ec) {
      if (ec || self->closed_ || self->subscribed_) return;
      ++self->server_->counters_->dropped_idle;
      self->Close();
    });
  }

  void ArmLineTimer() {
    if (line_timer_armed_) return;
    line_timer_armed_ = true;
    line_timer_.expires_at(partial_since_ + Seconds(limits_.line_timeout_s));
    line_timer_.async_wait([self = shared_from_this()](const error_code& ec) {
      self->line_timer_armed_ = false;
      if (ec || self->closed_ || !self->partial_) return;
      // Not the client's fault while we do not read it (its budget is full).
      const bool paused = self->InFlight() >= self->limits_.max_inflight;
      if (!paused && Clock::now() >= self->partial_since_ + Seconds(self->limits_.line_timeout_s)) {
        ++self->server_->counters_->dropped_line_timeout;
        std::fprintf(stderr, "<4>api: dropping client pid=%d: a line unfinished after %gs\n",
                     static_cast<int>(self->peer_.pid), self->limits_.line_timeout_s);
        self->Evict("request line not finished within " +
                    std::to_string(static_cast<int>(self->limits_.line_timeout_s)) + " s");
        return;
      }
      if (paused) self->partial_since_ = Clock::now();
      self->ArmLineTimer();
    });
  }

  void ReadMore() {
    if (closed_ || reading_ || eof_ || close_after_write_ || line_waiting_) return;
    if (InFlight() >= limits_.max_inflight) return;
    reading_ = true;
    socket_.async_read_some(asio::buffer(chunk_), [self = shared_from_this()](const error_code& ec,
                                                                              size_t n) {
      self->reading_ = false;
      if (self->closed_) return;
      if (ec) {  // EOF (maybe with half a line) or reset: answer what is asked, then close
        self->eof_ = true;
        self->partial_ = false;
        self->MaybeFinish();
        return;
      }
      if (self->head_ > 0) {
        self->inbuf_.erase(0, self->head_);
        self->scan_ = self->scan_ > self->head_ ? self->scan_ - self->head_ : 0;
        self->head_ = 0;
      }
      self->inbuf_.append(self->chunk_.data(), n);
      self->Continue();
    });
  }

  void ProcessLines() {
    line_waiting_ = false;
    while (!closed_ && !close_after_write_) {
      const size_t from = std::max(head_, scan_);
      const size_t nl = inbuf_.find('\n', from);
      if (nl == std::string::npos) {
        scan_ = inbuf_.size();
        const size_t partial = inbuf_.size() - head_;
        if (partial > limits_.max_line_bytes) {
          LongLine();
        } else if (partial > 0 && !partial_) {
          partial_ = true;
          partial_since_ = Clock::now();
          ArmLineTimer();
        } else if (partial == 0) {
          partial_ = false;
        }
        return;
      }
      if (InFlight() >= limits_.max_inflight) {
        // Pipelined past the budget: this client is not read again until answered.
        if (!line_waiting_) ++server_->counters_->paused;
        line_waiting_ = true;
        return;
      }
      if (nl - head_ > limits_.max_line_bytes) {
        LongLine();
        return;
      }
      if (!turn_ && !server_->CpuBudgetLeft()) {
        // The API thread used its share of this window: go on in the next one.
        line_waiting_ = true;
        if (!deferred_) server_->Defer(weak_from_this());  // once: one turn per window
        deferred_ = true;
        return;
      }
      std::string_view line(inbuf_.data() + head_, nl - head_);
      while (!line.empty() && (line.back() == '\r' || line.back() == '\n')) line.remove_suffix(1);
      head_ = nl + 1;
      scan_ = head_;
      partial_ = false;  // a next line starts now
      if (!line.empty()) {
        const auto t0 = Clock::now();
        turn_ = false;
        HandleLine(line);
        server_->Spent(Clock::now() - t0);
      }
    }
  }

  void LongLine() {
    // The line did not fit in max_line_bytes: answer once, then hang up.
    ++server_->counters_->dropped_long_line;
    Send(rpc::MessageText(rpc::MakeError(
        nullptr, rpc::kInvalidRequest,
        "request line longer than " + std::to_string(limits_.max_line_bytes) + " bytes")));
    close_after_write_ = true;
    inbuf_.clear();
    head_ = scan_ = 0;
    partial_ = false;
    MaybeFinish();
  }

  void HandleLine(std::string_view line) {
    ++server_->counters_->requests;
    last_request_ = Clock::now();
    ArmIdle();
    rpc::ParseResult parsed = rpc::ParseRequest(line);
    if (auto* err = std::get_if<nlohmann::json>(&parsed)) {
      ++server_->counters_->errors;
      Send(rpc::MessageText(*err));
      return;
    }
    auto req = std::make_shared<const rpc::Request>(std::move(std::get<rpc::Request>(parsed)));
    if (control_only_ && !IsControlMethod(req->method)) {
      ++server_->counters_->errors;
      if (!req->notification) {
        Send(rpc::MessageText(rpc::MakeError(
            req->id, rpc::kRejected,
            "too many clients: this connection may only start or stop the robot")));
      }
      close_after_write_ = true;
      MaybeFinish();
      return;
    }
    if (req->method == "subscribe" && !SubscribeRate(req->params, limits_.max_rate_hz)) {
      ++server_->counters_->errors;
      char msg[96];
      std::snprintf(msg, sizeof msg, "invalid params: rate must be > 0 and <= %g (Hz)",
                    limits_.max_rate_hz);
      if (!req->notification) Send(rpc::MessageText(rpc::MakeError(req->id, rpc::kInvalidParams, msg)));
      return;
    }
    ++at_control_;
    server_->PostToControl(weak_from_this(), std::move(req), peer_);
  }

  void StartSubscription(double rate) {
    sub_period_ = Seconds(std::min(1.0 / rate, kMaxSubscriptionPeriodS));
    if (!subscribed_) {
      subscribed_ = true;
      sub_timer_.expires_after(sub_period_);
      Notify();
    }
  }

  void Notify() {
    sub_timer_.async_wait([self = shared_from_this()](const error_code& ec) {
      if (ec || self->closed_) return;
      // One payload at a time: a slow control loop does not pile requests up.
      if (!self->notify_pending_) {
        self->notify_pending_ = true;
        self->server_->PostToControl(self->weak_from_this(), nullptr, self->peer_);
      }
      self->sub_timer_.expires_at(self->sub_timer_.expiry() + self->sub_period_);
      if (self->sub_timer_.expiry() < Clock::now()) self->sub_timer_.expires_after(self->sub_period_);
      self->Notify();
    });
  }

  void Send(std::string text) {
    if (closed_) return;
    text.push_back('\n');
    pending_bytes_ += text.size();
    if (pending_bytes_ > limits_.max_pending_bytes) {
      ++server_->counters_->dropped_slow;
      std::fprintf(stderr, "<4>api: dropping client pid=%d: %zu bytes unread\n",
                   static_cast<int>(peer_.pid), pending_bytes_);
      Close();
      return;
    }
    queue_.push_back(std::move(text));
    if (!writing_) WriteNext();
  }

  void WriteNext() {
    if (queue_.empty()) {
      writing_ = false;
      return;
    }
    writing_ = true;
    asio::async_write(socket_, asio::buffer(queue_.front()),
                      [self = shared_from_this()](const error_code& ec, size_t n) {
                        if (self->closed_) return;
                        if (ec) {
                          self->Close();
                          return;
                        }
                        self->pending_bytes_ -= n;
                        self->queue_.pop_front();
                        self->writing_ = false;
                        self->WriteNext();
                        self->Continue();
                      });
  }

  ApiServer* server_;
  const ApiLimits& limits_;
  Local::socket socket_;
  PeerCred peer_;
  const bool control_only_;
  asio::steady_timer idle_timer_;
  asio::steady_timer line_timer_;
  asio::steady_timer sub_timer_;
  Clock::time_point last_request_;
  Clock::time_point partial_since_{};
  Clock::duration sub_period_{};
  std::array<char, 16384> chunk_{};
  std::string inbuf_;
  size_t head_ = 0;  // start of the unhandled input in inbuf_
  size_t scan_ = 0;  // inbuf_ has no newline before this
  std::deque<std::string> queue_;
  size_t pending_bytes_ = 0;
  size_t at_control_ = 0;  // requests posted to the control loop, not answered yet
  bool reading_ = false;
  bool writing_ = false;
  bool line_waiting_ = false;  // a complete line waits for budget
  bool turn_ = false;          // resumed after a CPU pause: one line is due
  bool deferred_ = false;      // waiting in the server's list for the next window
  bool partial_ = false;       // inbuf_ ends with an unfinished line, begun at partial_since_
  bool line_timer_armed_ = false;
  bool subscribed_ = false;
  bool notify_pending_ = false;
  bool eof_ = false;
  bool closed_ = false;
  bool close_after_write_ = false;
};

ApiServer::ApiServer(asio::io_context& control, std::string path, ApiLimits limits,
                     Dispatcher* dispatcher)
    : control_(control),
      path_(std::move(path)),
      limits_(limits),
      dispatcher_(dispatcher),
      loop_(std::make_shared<Loop>()),
      counters_(std::make_unique<Counters>()),
      resume_timer_(std::make_unique<asio::steady_timer>(loop_->io)) {}

ApiServer::~ApiServer() {
  Close();
  alive_.reset();
  acceptor_.reset();
  resume_timer_.reset();
  deferred_.clear();
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
  // Only a socket nobody listens on may be replaced: never another kind of file.
  struct stat st {};
  if (::lstat(path_.c_str(), &st) == 0) {
    if (!S_ISSOCK(st.st_mode)) {
      *error = "api: " + path_ + " exists and is not a socket: refusing to replace it";
      return false;
    }
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    if (path_.size() >= sizeof addr.sun_path) {
      *error = "api: socket path too long: " + path_;
      return false;
    }
    std::memcpy(addr.sun_path, path_.c_str(), path_.size() + 1);
    const int probe = ::socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    const int r = probe < 0 ? -1 : ::connect(probe, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
    const int err = errno;
    if (probe >= 0) ::close(probe);
    if (r == 0 || (r < 0 && (err == EAGAIN || err == EINPROGRESS))) {
      *error = "api: another process is already listening on " + path_;
      return false;
    }
    ::unlink(path_.c_str());
  }
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
      // Out of descriptors: the pending connection stays in the backlog; trying
      // again at once would spin a core.
      const uint64_t n = ++counters_->accept_backoffs;
      if (n == 1 || n % 100 == 0) {
        std::fprintf(stderr, "<4>api: cannot accept a client (%s, %llu times): pausing %gs\n",
                     ec.message().c_str(), static_cast<unsigned long long>(n),
                     limits_.accept_backoff_s);
      }
      auto timer = std::make_shared<asio::steady_timer>(loop_->io, Seconds(limits_.accept_backoff_s));
      timer->async_wait([this, timer](const error_code& e) {
        if (!e) Accept();
      });
      return;
    }
    if (ec == asio::error::operation_aborted) return;
    if (!ec) Admit(std::move(socket), ReadPeer(socket.native_handle()));
    Accept();
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
      SendAndForget(socket.native_handle(),
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

bool ApiServer::CpuBudgetLeft() {
  const auto now = Clock::now();
  const auto window = Seconds(limits_.cpu_window_s);
  if (now - window_start_ >= window) {
    window_start_ = now;
    window_spent_ = {};
  }
  return window_spent_ < Seconds(limits_.cpu_window_s * limits_.cpu_share);
}

void ApiServer::Spent(Clock::duration d) { window_spent_ += d; }

void ApiServer::Defer(std::weak_ptr<Session> s) {
  deferred_.push_back(std::move(s));
  if (resume_armed_) return;
  resume_armed_ = true;
  ++counters_->cpu_pauses;
  resume_timer_->expires_at(window_start_ + Seconds(limits_.cpu_window_s));
  resume_timer_->async_wait([this](const error_code& ec) {
    resume_armed_ = false;
    if (ec) return;
    auto waiting = std::move(deferred_);
    deferred_.clear();
    for (auto& w : waiting) {
      if (const auto session = w.lock()) session->Resume();
    }
  });
}

void ApiServer::Remove(Session* s) {
  sessions_.remove_if([s](const std::shared_ptr<Session>& p) { return p.get() == s; });
  clients_ = sessions_.size();
}

void ApiServer::PostToControl(std::weak_ptr<Session> session,
                              std::shared_ptr<const rpc::Request> request, PeerCred peer) {
  asio::post(control_, [this, alive = std::weak_ptr<int>(alive_), session = std::move(session),
                        request = std::move(request), peer = std::move(peer)]() mutable {
    if (alive.expired()) return;
    OnControl(std::move(session), std::move(request), peer);
  });
}

void ApiServer::OnControl(std::weak_ptr<Session> session,
                          std::shared_ptr<const rpc::Request> req, const PeerCred& peer) {
  // The way back to the API thread; harmless when the client or the server is gone.
  auto deliver = [loop = std::weak_ptr<Loop>(loop_), session, req](Outcome o) {
    const auto l = loop.lock();
    if (!l) return;
    asio::post(l->io, [session, req, o = std::move(o)]() mutable {
      if (const auto s = session.lock()) s->OnAnswer(req, std::move(o));
    });
  };
  if (!req) {  // a status notification's payload, built once per period
    Cached& c = cache_["@notify"];
    if (c.result && c.period == period_) {
      ++counters_->coalesced;
    } else {
      c = {period_, std::make_shared<const nlohmann::json>(dispatcher_->StatusNotification())};
    }
    deliver(Outcome{nullptr, c.result, "@notify"});
    return;
  }
  if (req->method == "subscribe") {
    if (!dispatcher_->MaySubscribe(peer)) {
      deliver(Outcome{rpc::MakeError(req->id, rpc::kAccessDenied, "access denied: subscribe"), {}, {}});
    } else {
      const double rate = SubscribeRate(req->params, limits_.max_rate_hz).value_or(1);
      deliver(Outcome{rpc::MakeResult(req->id, {{"subscribed", true}, {"rate", rate}}), {}, {}});
    }
    return;
  }
  const bool readable = req->method == "status" || req->method == "map";
  // Neither takes params (contracts.md §6): padded params must not get past the sharing.
  if (readable && dispatcher_->MaySubscribe(peer)) {
    const auto it = cache_.find(req->method);
    if (it != cache_.end() && it->second.result && it->second.period == period_) {
      ++counters_->coalesced;
      deliver(Outcome{nullptr, it->second.result, req->method});
      return;
    }
    dispatcher_->Handle(*req, peer,
                        [this, alive = std::weak_ptr<int>(alive_), deliver,
                         key = req->method](nlohmann::json response) {
                          if (alive.expired() || !response.contains("result")) {
                            deliver(Outcome{std::move(response), {}, {}});
                            return;
                          }
                          auto r = std::make_shared<const nlohmann::json>(
                              std::move(response["result"]));
                          cache_[key] = {period_, r};
                          deliver(Outcome{nullptr, std::move(r), key});
                        });
    return;
  }
  if (!readable) cache_.clear();  // a command may change what status and map say
  dispatcher_->Handle(*req, peer, [deliver](nlohmann::json response) {
    deliver(Outcome{std::move(response), {}, {}});
  });
}

const std::string& ApiServer::SharedText(const std::string& key,
                                         const std::shared_ptr<const nlohmann::json>& result) {
  auto& [held, text] = texts_[key];
  if (held != result) {
    held = result;
    text = key == "@notify" ? rpc::MessageText(rpc::MakeNotification("status", *result))
                            : rpc::MessageText(*result);
  }
  return text;
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
      resume_timer_->cancel();
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
