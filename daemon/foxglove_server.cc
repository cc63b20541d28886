// The Foxglove WebSocket server (daemon/foxglove_server.h). A few lines over
// the ~400-line bar (issue 10): nearly all of it is Session, one client's
// connection (HTTP upgrade, the read loop of client ops, the write loop over
// the bounded queue), whose handlers share that connection's state and
// callbacks; Server itself is the ~90 lines at the end.
#include "daemon/foxglove_server.h"

#include <boost/asio/buffer.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <chrono>
#include <cstdio>
#include <deque>
#include <random>

namespace irslam::foxglove {

namespace asio = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = asio::ip::tcp;
using boost::system::error_code;

namespace {

std::chrono::steady_clock::duration Seconds(double s) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(s));
}

std::string PeerName(const tcp::socket& s) {
  error_code ec;
  const auto ep = s.remote_endpoint(ec);
  if (ec) return "?";
  return ep.address().to_string() + ":" + std::to_string(ep.port());
}

}  // namespace

// One client: the HTTP upgrade, then a read loop of client ops and a write loop
// over the bounded queue.
class Server::Session : public std::enable_shared_from_this<Session> {
 public:
  Session(Server* server, tcp::socket socket)
      : server_(server), peer_(PeerName(socket)), ws_(std::move(socket)) {}

  const std::string& peer() const { return peer_; }

  void Start() {
    beast::get_lowest_layer(ws_).expires_after(Seconds(server_->options_.handshake_timeout_s));
    parser_.emplace();
    parser_->body_limit(4096);
    http::async_read(
        beast::get_lowest_layer(ws_), buffer_, *parser_,
        [self = shared_from_this()](const error_code& ec, size_t) { self->OnRequest(ec); });
  }

  bool Subscribed(uint32_t channel) const {
    for (const auto& [id, ch] : subs_) {
      if (ch == channel) return true;
    }
    return false;
  }

  // Message data for every subscription of this client to channel.
  void SendData(uint32_t channel, uint64_t t_ns,
                const std::shared_ptr<const std::string>& payload) {
    for (const auto& [id, ch] : subs_) {
      if (ch == channel) Enqueue(Frame{MessageDataFrame(id, t_ns, {}), payload, true}, true);
    }
  }

  void SendText(std::string text) { Enqueue(Frame{std::move(text), nullptr, false}, false); }

  // Closes the connection (a close frame when the websocket is open).
  void Close(websocket::close_code code, const std::string& why) {
    if (closing_) return;
    closing_ = true;
    subs_.clear();
    // The frame being written stays until its write completes (its buffers).
    while (queue_.size() > (writing_ ? 1u : 0u)) queue_.pop_back();
    if (!why.empty())
      std::fprintf(stderr, "<6>foxglove: client %s: closed: %s\n", peer_.c_str(), why.c_str());
    auto self = shared_from_this();
    server_->Remove(this);
    if (open_ && !writing_) {
      ws_.async_close(code, [self](const error_code&) { self->Shutdown(); });
    } else if (!open_) {
      Shutdown();
    } else {
      close_code_ = code;  // after the write in progress
    }
  }

 private:
  struct Frame {
    std::string head;  // the text, or a Message Data header before payload
    std::shared_ptr<const std::string> payload;
    bool binary = false;
    size_t size() const { return head.size() + (payload ? payload->size() : 0); }
  };

  void Shutdown() {
    error_code ec;
    auto& sock = beast::get_lowest_layer(ws_).socket();
    sock.shutdown(tcp::socket::shutdown_both, ec);
    sock.close(ec);
  }

  void OnRequest(const error_code& ec) {
    if (closing_) return;
    if (ec) {
      ++server_->stats_.rejected;
      return Close(websocket::close_code::normal, "no websocket handshake: " + ec.message());
    }
    auto req = parser_->release();
    if (!websocket::is_upgrade(req))
      return Reject(http::status::bad_request, "a Foxglove WebSocket server: connect with ws://\n");
    if (!OffersSubprotocol(std::string(req[http::field::sec_websocket_protocol]))) {
      return Reject(http::status::bad_request,
                    "the client must offer the subprotocol foxglove.websocket.v1\n");
    }
    beast::get_lowest_layer(ws_).expires_never();
    websocket::stream_base::timeout t =
        websocket::stream_base::timeout::suggested(beast::role_type::server);
    t.handshake_timeout = Seconds(server_->options_.handshake_timeout_s);
    t.idle_timeout = Seconds(server_->options_.idle_timeout_s);
    t.keep_alive_pings = true;
    ws_.set_option(t);
    ws_.set_option(websocket::stream_base::decorator([](websocket::response_type& res) {
      res.set(http::field::sec_websocket_protocol, std::string(kSubprotocol));
      res.set(http::field::server, "irslam-foxglove");
    }));
    ws_.read_message_max(server_->options_.max_client_message_bytes);
    ws_.async_accept(req, [self = shared_from_this()](const error_code& e) { self->OnAccept(e); });
  }

  void Reject(http::status status, const std::string& text) {
    ++server_->stats_.rejected;
    std::fprintf(stderr, "<5>foxglove: client %s: refused: %s", peer_.c_str(), text.c_str());
    auto res = std::make_shared<http::response<http::string_body>>(status, 11);
    res->set(http::field::content_type, "text/plain");
    res->set(http::field::server, "irslam-foxglove");
    res->keep_alive(false);
    res->body() = text;
    res->prepare_payload();
    closing_ = true;
    server_->Remove(this);
    http::async_write(
        beast::get_lowest_layer(ws_), *res,
        [self = shared_from_this(), res](const error_code&, size_t) { self->Shutdown(); });
  }

  void OnAccept(const error_code& ec) {
    if (closing_) return;
    if (ec) {
      ++server_->stats_.rejected;
      return Close(websocket::close_code::normal, "websocket handshake failed: " + ec.message());
    }
    open_ = true;
    std::fprintf(stderr, "<6>foxglove: client %s connected\n", peer_.c_str());
    SendText(server_->server_info_);
    SendText(server_->advertise_);
    Read();
  }

  void Read() {
    ws_.async_read(buffer_,
                   [self = shared_from_this()](const error_code& ec, size_t) { self->OnRead(ec); });
  }

  void OnRead(const error_code& ec) {
    if (closing_) return;
    if (ec) {
      if (ec == websocket::error::closed)
        return Close(websocket::close_code::normal, "by the client");
      if (ec == websocket::error::message_too_big) return BadInput("message over the size limit");
      return Close(websocket::close_code::normal, ec.message());
    }
    if (!ws_.got_text())
      return BadInput("a binary message (this server takes no client publishing)");
    const std::string text = beast::buffers_to_string(buffer_.data());
    buffer_.consume(buffer_.size());
    std::string error;
    const auto op = ParseClientOp(text, &error);
    if (!op) return BadInput(error);
    switch (op->kind) {
      case ClientOp::Kind::kSubscribe:
        for (const auto& [id, channel] : op->subscribe) Subscribe(id, channel);
        break;
      case ClientOp::Kind::kUnsubscribe:
        for (const auto id : op->unsubscribe) {
          if (subs_.erase(id) == 0) {
            SendText(
                StatusJson(Level::kWarning, "unsubscribe: no subscription " + std::to_string(id))
                    .dump());
          }
        }
        break;
      case ClientOp::Kind::kUnsupported:
        SendText(
            StatusJson(Level::kWarning, "op \"" + op->op + "\" is not supported by irslam-foxglove")
                .dump());
        break;
    }
    if (!closing_) Read();
  }

  void Subscribe(uint32_t id, uint32_t channel) {
    bool known = false;
    for (const auto& c : server_->channels_) known = known || c.id == channel;
    if (!known) {
      SendText(
          StatusJson(Level::kError, "subscribe: no channel " + std::to_string(channel)).dump());
      return;
    }
    if (subs_.count(id) != 0) {
      SendText(StatusJson(Level::kError,
                          "subscribe: subscription id " + std::to_string(id) + " is in use")
                   .dump());
      return;
    }
    if (Subscribed(channel)) {
      SendText(StatusJson(Level::kError,
                          "subscribe: already subscribed to channel " + std::to_string(channel))
                   .dump());
      return;
    }
    subs_[id] = channel;
    // The channel's latest message at once (the map topics come at 1 Hz or less).
    const auto it = server_->latest_.find(channel);
    if (it != server_->latest_.end() && it->second.payload) {
      Enqueue(Frame{MessageDataFrame(id, it->second.t_ns, {}), it->second.payload, true}, true);
    }
  }

  void BadInput(const std::string& why) {
    ++server_->stats_.bad_input;
    std::fprintf(stderr, "<4>foxglove: client %s: bad input: %s\n", peer_.c_str(), why.c_str());
    Close(websocket::close_code::policy_error, "");
  }

  // droppable: message data, which a slow client loses; protocol text is always
  // queued, but a client whose queue is twice over its bounds is closed.
  void Enqueue(Frame f, bool droppable) {
    if (closing_ || !open_) return;
    const ServerOptions& o = server_->options_;
    const bool full =
        queue_.size() >= o.max_queued_frames || queued_bytes_ + f.size() > o.max_queued_bytes;
    if (full && droppable) {
      ++server_->stats_.dropped;
      if (++dropped_ == 1 || dropped_ % 1000 == 0) {
        std::fprintf(stderr, "<5>foxglove: client %s: slow, %llu messages dropped\n", peer_.c_str(),
                     static_cast<unsigned long long>(dropped_));
      }
      return;
    }
    if (full &&
        (queue_.size() >= 2 * o.max_queued_frames || queued_bytes_ > 2 * o.max_queued_bytes)) {
      return Close(websocket::close_code::try_again_later, "does not read");
    }
    if (droppable) ++server_->stats_.sent;
    queued_bytes_ += f.size();
    queue_.push_back(std::move(f));
    if (!writing_) Write();
  }

  void Write() {
    writing_ = true;
    const Frame& f = queue_.front();
    ws_.binary(f.binary);
    std::array<asio::const_buffer, 2> buffers{
        asio::buffer(f.head), f.payload ? asio::buffer(*f.payload) : asio::const_buffer()};
    ws_.async_write(
        buffers, [self = shared_from_this()](const error_code& ec, size_t) { self->OnWrite(ec); });
  }

  void OnWrite(const error_code& ec) {
    writing_ = false;
    if (closing_) {
      if (open_ && close_code_) {
        const auto code = *close_code_;
        close_code_.reset();
        ws_.async_close(code, [self = shared_from_this()](const error_code&) { self->Shutdown(); });
      }
      return;
    }
    if (ec) return Close(websocket::close_code::normal, "write: " + ec.message());
    queued_bytes_ -= queue_.front().size();
    queue_.pop_front();
    if (!queue_.empty()) Write();
  }

  Server* server_;
  std::string peer_;
  websocket::stream<beast::tcp_stream> ws_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
  std::deque<Frame> queue_;
  size_t queued_bytes_ = 0;
  uint64_t dropped_ = 0;
  std::map<uint32_t, uint32_t> subs_;  // subscription id -> channel id
  bool open_ = false;
  bool writing_ = false;
  bool closing_ = false;
  std::optional<websocket::close_code> close_code_;
};

Server::Server(asio::io_context& io, std::vector<Channel> channels, ServerOptions options)
    : acceptor_(io), channels_(std::move(channels)), options_(std::move(options)) {
  // A session id that differs between runs: clients see a restart as a new server.
  std::random_device rd;
  const auto now = std::chrono::system_clock::now().time_since_epoch();
  const std::string session =
      std::to_string(std::chrono::duration_cast<std::chrono::milliseconds>(now).count()) + "-" +
      std::to_string(rd() % 100000);
  server_info_ = ServerInfoJson(options_.name, session).dump();
  advertise_ = AdvertiseJson(channels_).dump();
}

Server::~Server() { Close(); }

bool Server::Listen(const tcp::endpoint& endpoint, std::string* error) {
  error_code ec;
  acceptor_.open(endpoint.protocol(), ec);
  if (!ec) acceptor_.set_option(asio::socket_base::reuse_address(true), ec);
  if (!ec) acceptor_.bind(endpoint, ec);
  if (!ec) acceptor_.listen(asio::socket_base::max_listen_connections, ec);
  if (ec) {
    *error = "cannot listen on " + endpoint.address().to_string() + ":" +
             std::to_string(endpoint.port()) + ": " + ec.message();
    error_code ignored;
    acceptor_.close(ignored);
    return false;
  }
  Accept();
  return true;
}

tcp::endpoint Server::local_endpoint() const {
  error_code ec;
  return acceptor_.local_endpoint(ec);
}

void Server::Accept() {
  acceptor_.async_accept([this](const error_code& ec, tcp::socket socket) {
    if (closed_ || ec == asio::error::operation_aborted) return;
    if (!ec) {
      if (sessions_.size() >= options_.max_clients) {
        ++stats_.rejected;
        std::fprintf(stderr, "<5>foxglove: client %s: refused: %zu clients already\n",
                     PeerName(socket).c_str(), sessions_.size());
        error_code ignored;
        socket.close(ignored);
      } else {
        ++stats_.accepted;
        auto s = std::make_shared<Session>(this, std::move(socket));
        sessions_.insert(s);
        s->Start();
      }
    } else {
      std::fprintf(stderr, "<4>foxglove: accept: %s\n", ec.message().c_str());
    }
    Accept();
  });
}

void Server::Remove(Session* s) {
  for (auto it = sessions_.begin(); it != sessions_.end(); ++it) {
    if (it->get() == s) {
      sessions_.erase(it);
      return;
    }
  }
}

void Server::Publish(uint32_t channel_id, uint64_t log_time_ns, std::string payload) {
  auto shared = std::make_shared<const std::string>(std::move(payload));
  latest_[channel_id] = Latest{log_time_ns, shared};
  // A copy of the set: a send may close (and remove) a session.
  const auto sessions = sessions_;
  for (const auto& s : sessions) s->SendData(channel_id, log_time_ns, shared);
}

bool Server::HasSubscribers(uint32_t channel_id) const {
  for (const auto& s : sessions_) {
    if (s->Subscribed(channel_id)) return true;
  }
  return false;
}

void Server::Broadcast(Level level, const std::string& message) {
  const std::string text = StatusJson(level, message).dump();
  const auto sessions = sessions_;
  for (const auto& s : sessions) s->SendText(text);
}

void Server::Close() {
  if (closed_) return;
  closed_ = true;
  error_code ec;
  acceptor_.close(ec);
  const auto sessions = sessions_;
  for (const auto& s : sessions) s->Close(websocket::close_code::going_away, "");
  sessions_.clear();
}

}  // namespace irslam::foxglove
