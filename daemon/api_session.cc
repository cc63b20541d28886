// ApiServer::Session: one client connection (see internal/api_session.h).
#include <sys/socket.h>

#include <algorithm>
#include <boost/asio/write.hpp>
#include <cstdio>
#include <variant>

#include "daemon/internal/api_cpu_share.h"
#include "daemon/internal/api_session.h"
#include "daemon/jsonrpc.h"

namespace irslam {

namespace asio = boost::asio;
using boost::system::error_code;
using api_internal::Clock;
using api_internal::Seconds;
using api_internal::SubscribeRate;

namespace {

// A subscription period longer than a day is a day (1/rate of a tiny rate
// overflowed the clock's duration and sent notifications unthrottled).
constexpr double kMaxSubscriptionPeriodS = 86400;

bool IsControlMethod(const std::string& m) { return m == "start" || m == "stop" || m == "clean"; }

}  // namespace

namespace api_internal {

std::optional<double> SubscribeRate(const nlohmann::json& params, double max_rate_hz) {
  const auto it = params.find("rate");
  if (it == params.end()) return std::min(5.0, max_rate_hz);
  if (!it->is_number()) return std::nullopt;
  const double rate = it->get<double>();
  if (!(rate > 0) || !(rate <= max_rate_hz)) return std::nullopt;  // NaN fails both
  return rate;
}

void SendAndForget(int fd, const std::string& text) {
  const std::string line = text + "\n";
  (void)::send(fd, line.data(), line.size(), MSG_DONTWAIT | MSG_NOSIGNAL);
}

}  // namespace api_internal

ApiServer::Session::Session(ApiServer* server, Local::socket socket, PeerCred peer,
                            bool control_only)
    : server_(server),
      limits_(server->limits_),
      socket_(std::move(socket)),
      peer_(std::move(peer)),
      control_only_(control_only),
      idle_timer_(server->loop_->io),
      line_timer_(server->loop_->io),
      sub_timer_(server->loop_->io),
      last_request_(Clock::now()) {}

void ApiServer::Session::Start() {
  ArmIdle();
  ReadMore();
}

void ApiServer::Session::Close() {
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

void ApiServer::Session::Evict(const std::string& why) {
  if (closed_) return;
  api_internal::SendAndForget(socket_.native_handle(),
                              rpc::MessageText(rpc::MakeError(nullptr, rpc::kRejected, why)));
  Close();
}

void ApiServer::Session::Resume() {
  deferred_ = false;
  turn_ = true;
  Continue();
}

void ApiServer::Session::OnAnswer(const std::shared_ptr<const rpc::Request>& req, Outcome o) {
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

void ApiServer::Session::Continue() {
  if (closed_) return;
  ProcessLines();
  ReadMore();
  MaybeFinish();
}

void ApiServer::Session::MaybeFinish() {
  if (closed_ || writing_ || !queue_.empty()) return;
  // Requests already at the control loop are answered first (a `stop` in the
  // reserved slot followed by something else still gets its reply).
  if ((close_after_write_ || eof_) && at_control_ == 0) Close();
}

void ApiServer::Session::ArmIdle() {
  idle_timer_.expires_after(Seconds(limits_.idle_timeout_s));
  idle_timer_.async_wait([self = shared_from_this()](const error_code& ec) {
    if (ec || self->closed_ || self->subscribed_) return;
    ++self->server_->counters_->dropped_idle;
    self->Close();
  });
}

void ApiServer::Session::ArmLineTimer() {
  if (line_timer_armed_) return;
  line_timer_armed_ = true;
  line_timer_.expires_at(partial_since_ + Seconds(limits_.line_timeout_s));
  line_timer_.async_wait([self = shared_from_this()](const error_code& ec) {
    self->line_timer_armed_ = false;
    if (ec || self->closed_ || !self->partial_) return;
    self->OnLineTimer();
  });
}

void ApiServer::Session::OnLineTimer() {
  // Not the client's fault while we do not read it (its budget is full).
  const bool paused = InFlight() >= limits_.max_inflight;
  if (!paused && Clock::now() >= partial_since_ + Seconds(limits_.line_timeout_s)) {
    ++server_->counters_->dropped_line_timeout;
    std::fprintf(stderr, "<4>api: dropping client pid=%d: a line unfinished after %gs\n",
                 static_cast<int>(peer_.pid), limits_.line_timeout_s);
    Evict("request line not finished within " +
          std::to_string(static_cast<int>(limits_.line_timeout_s)) + " s");
    return;
  }
  if (paused) partial_since_ = Clock::now();
  ArmLineTimer();
}

void ApiServer::Session::ReadMore() {
  if (closed_ || reading_ || eof_ || close_after_write_ || line_waiting_) return;
  if (InFlight() >= limits_.max_inflight) return;
  reading_ = true;
  socket_.async_read_some(asio::buffer(chunk_),
                          [self = shared_from_this()](const error_code& ec, size_t n) {
                            self->reading_ = false;
                            if (self->closed_) return;
                            // EOF (maybe with half a line) or reset: answer what is asked, then close.
                            if (ec) {
                              self->eof_ = true;
                              self->partial_ = false;
                              self->MaybeFinish();
                              return;
                            }
                            self->OnRead(n);
                          });
}

void ApiServer::Session::OnRead(size_t n) {
  if (head_ > 0) {
    inbuf_.erase(0, head_);
    scan_ = scan_ > head_ ? scan_ - head_ : 0;
    head_ = 0;
  }
  inbuf_.append(chunk_.data(), n);
  Continue();
}

void ApiServer::Session::ProcessLines() {
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
    if (!MayTakeLine(nl)) return;
    std::string_view line(inbuf_.data() + head_, nl - head_);
    while (!line.empty() && (line.back() == '\r' || line.back() == '\n')) line.remove_suffix(1);
    head_ = nl + 1;
    scan_ = head_;
    partial_ = false;  // a next line starts now
    if (!line.empty()) {
      const auto t0 = Clock::now();
      turn_ = false;
      HandleLine(line);
      server_->cpu_share_->Spent(Clock::now() - t0);
    }
  }
}

bool ApiServer::Session::MayTakeLine(size_t nl) {
  if (InFlight() >= limits_.max_inflight) {
    // Pipelined past the budget: this client is not read again until answered.
    if (!line_waiting_) ++server_->counters_->paused;
    line_waiting_ = true;
    return false;
  }
  if (nl - head_ > limits_.max_line_bytes) {
    LongLine();
    return false;
  }
  if (!turn_ && !server_->cpu_share_->BudgetLeft()) {
    // The API thread used its share of this window: go on in the next one.
    line_waiting_ = true;
    if (!deferred_) {  // once: one turn per window
      server_->cpu_share_->Defer([weak = weak_from_this()] {
        if (const auto session = weak.lock()) session->Resume();
      });
    }
    deferred_ = true;
    return false;
  }
  return true;
}

void ApiServer::Session::LongLine() {
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

void ApiServer::Session::HandleLine(std::string_view line) {
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

void ApiServer::Session::StartSubscription(double rate) {
  sub_period_ = Seconds(std::min(1.0 / rate, kMaxSubscriptionPeriodS));
  if (!subscribed_) {
    subscribed_ = true;
    sub_timer_.expires_after(sub_period_);
    Notify();
  }
}

void ApiServer::Session::Notify() {
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

void ApiServer::Session::Send(std::string text) {
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

void ApiServer::Session::WriteNext() {
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

}  // namespace irslam
