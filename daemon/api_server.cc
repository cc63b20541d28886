#include "daemon/api_server.h"

#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <boost/asio/read_until.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/streambuf.hpp>
#include <boost/asio/write.hpp>
#include <chrono>
#include <cstdio>
#include <deque>

namespace irslam {

namespace asio = boost::asio;
using boost::system::error_code;
using Local = asio::local::stream_protocol;

class ApiServer::Session : public std::enable_shared_from_this<Session> {
 public:
  Session(ApiServer* server, Local::socket socket, PeerCred peer)
      : server_(server),
        socket_(std::move(socket)),
        peer_(peer),
        buffer_(server->limits_.max_line_bytes + 1),
        idle_timer_(server->io_),
        sub_timer_(server->io_) {}

  void Start() {
    ArmIdle();
    Read();
  }

  void Close() {
    if (closed_) return;
    closed_ = true;
    error_code ec;
    idle_timer_.cancel();
    sub_timer_.cancel();
    socket_.shutdown(Local::socket::shutdown_both, ec);
    socket_.close(ec);
    server_->Remove(this);
  }

 private:
  void ArmIdle() {
    idle_timer_.expires_after(std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(server_->limits_.idle_timeout_s)));
    idle_timer_.async_wait([self = shared_from_this()](const error_code& ec) {
      if (ec || self->closed_ || self->subscribed_) return;
      ++self->server_->stats_.dropped_idle;
      self->Close();
    });
  }

  void Read() {
    asio::async_read_until(
        socket_, buffer_, '\n', [self = shared_from_this()](const error_code& ec, size_t n) {
          if (self->closed_) return;
          if (ec == asio::error::not_found) {
            // The line did not fit in max_line_bytes: answer once, then hang up.
            ++self->server_->stats_.dropped_long_line;
            self->Send(rpc::MakeError(nullptr, rpc::kInvalidRequest,
                                      "request line longer than " +
                                          std::to_string(self->server_->limits_.max_line_bytes) +
                                          " bytes")
                           .dump());
            self->close_after_write_ = true;
            return;
          }
          if (ec) {  // EOF (maybe with half a line) or reset: just close
            self->Close();
            return;
          }
          std::string line(asio::buffers_begin(self->buffer_.data()),
                           asio::buffers_begin(self->buffer_.data()) + static_cast<long>(n));
          self->buffer_.consume(n);
          while (!line.empty() && (line.back() == '\n' || line.back() == '\r')) line.pop_back();
          if (!line.empty()) self->HandleLine(line);
          if (!self->closed_) self->Read();
        });
  }

  void HandleLine(const std::string& line) {
    ++server_->stats_.requests;
    ArmIdle();
    rpc::ParseResult parsed = rpc::ParseRequest(line);
    if (auto* err = std::get_if<nlohmann::json>(&parsed)) {
      ++server_->stats_.errors;
      Send(err->dump());
      return;
    }
    const rpc::Request& req = std::get<rpc::Request>(parsed);
    nlohmann::json response;
    if (req.method == "subscribe") {
      response = Subscribe(req);
    } else {
      response = server_->dispatcher_->Handle(req, peer_);
    }
    if (response.contains("error")) ++server_->stats_.errors;
    if (!req.notification) Send(response.dump());
  }

  nlohmann::json Subscribe(const rpc::Request& req) {
    if (!server_->dispatcher_->MaySubscribe(peer_)) {
      return rpc::MakeError(req.id, rpc::kAccessDenied, "access denied: subscribe");
    }
    double rate = 5;
    if (auto it = req.params.find("rate"); it != req.params.end()) {
      if (!it->is_number() || it->get<double>() <= 0) {
        return rpc::MakeError(req.id, rpc::kInvalidParams, "invalid params: rate must be > 0 (Hz)");
      }
      rate = std::min(it->get<double>(), server_->limits_.max_rate_hz);
    }
    sub_period_ = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
        std::chrono::duration<double>(1.0 / rate));
    if (!subscribed_) {
      subscribed_ = true;
      sub_timer_.expires_after(sub_period_);
      Notify();
    }
    return rpc::MakeResult(req.id, {{"subscribed", true}, {"rate", rate}});
  }

  void Notify() {
    sub_timer_.async_wait([self = shared_from_this()](const error_code& ec) {
      if (ec || self->closed_) return;
      self->Send(rpc::MakeNotification("status", self->server_->dispatcher_->StatusNotification())
                     .dump());
      self->sub_timer_.expires_at(self->sub_timer_.expiry() + self->sub_period_);
      if (self->sub_timer_.expiry() < std::chrono::steady_clock::now()) {
        self->sub_timer_.expires_after(self->sub_period_);
      }
      self->Notify();
    });
  }

  void Send(std::string text) {
    if (closed_) return;
    text.push_back('\n');
    pending_bytes_ += text.size();
    if (pending_bytes_ > server_->limits_.max_pending_bytes) {
      ++server_->stats_.dropped_slow;
      std::fprintf(stderr, "<4>api: dropping client pid=%d: %zu bytes unread\n", peer_.pid,
                   pending_bytes_);
      Close();
      return;
    }
    queue_.push_back(std::move(text));
    if (!writing_) WriteNext();
  }

  void WriteNext() {
    if (queue_.empty()) {
      writing_ = false;
      if (close_after_write_) Close();
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
                        self->WriteNext();
                      });
  }

  ApiServer* server_;
  Local::socket socket_;
  PeerCred peer_;
  asio::streambuf buffer_;
  asio::steady_timer idle_timer_;
  asio::steady_timer sub_timer_;
  std::chrono::steady_clock::duration sub_period_{};
  std::deque<std::string> queue_;
  size_t pending_bytes_ = 0;
  bool writing_ = false;
  bool subscribed_ = false;
  bool closed_ = false;
  bool close_after_write_ = false;
};

ApiServer::ApiServer(asio::io_context& io, std::string path, ApiLimits limits,
                     Dispatcher* dispatcher)
    : io_(io), path_(std::move(path)), limits_(limits), dispatcher_(dispatcher), acceptor_(io) {}

ApiServer::~ApiServer() { Close(); }

bool ApiServer::Listen(std::string* error) {
  // A live daemon already on this path must not be displaced; a stale file is removed.
  {
    Local::socket probe(io_);
    error_code ec;
    probe.connect(Local::endpoint(path_), ec);
    if (!ec) {
      *error = "api: another process is already listening on " + path_;
      return false;
    }
  }
  ::unlink(path_.c_str());
  error_code ec;
  acceptor_.open(Local(), ec);
  if (!ec) acceptor_.bind(Local::endpoint(path_), ec);
  if (!ec) acceptor_.listen(16, ec);
  if (ec) {
    *error = "api: cannot listen on " + path_ + ": " + ec.message();
    return false;
  }
  ::chmod(path_.c_str(), 0660);
  open_ = true;
  Accept();
  return true;
}

void ApiServer::Accept() {
  acceptor_.async_accept([this](const error_code& ec, Local::socket socket) {
    if (!open_) return;
    if (!ec) {
      PeerCred peer;
      ucred cred{};
      socklen_t len = sizeof cred;
      if (::getsockopt(socket.native_handle(), SOL_SOCKET, SO_PEERCRED, &cred, &len) == 0) {
        peer = {cred.pid, cred.uid, cred.gid};
      }
      if (sessions_.size() >= limits_.max_clients) {
        ++stats_.rejected_full;
        const std::string msg =
            rpc::MakeError(nullptr, rpc::kRejected, "too many clients").dump() + "\n";
        error_code ignored;
        socket.non_blocking(true, ignored);
        ::send(socket.native_handle(), msg.data(), msg.size(), MSG_DONTWAIT | MSG_NOSIGNAL);
        socket.close(ignored);
      } else {
        ++stats_.accepted;
        auto s = std::make_shared<Session>(this, std::move(socket), peer);
        sessions_.push_back(s);
        s->Start();
      }
    }
    Accept();
  });
}

void ApiServer::Remove(Session* s) {
  sessions_.remove_if([s](const std::shared_ptr<Session>& p) { return p.get() == s; });
}

void ApiServer::Close() {
  if (!open_) return;
  open_ = false;
  error_code ec;
  acceptor_.close(ec);
  auto copy = sessions_;
  for (auto& s : copy) s->Close();
  ::unlink(path_.c_str());
}

}  // namespace irslam
