#include "daemon/foxglove_bridge.h"

#include <algorithm>
#include <boost/asio/read_until.hpp>
#include <boost/asio/write.hpp>
#include <cstdio>
#include <istream>

#include "io/json_text.h"

namespace irslam::foxglove {

namespace asio = boost::asio;
using boost::system::error_code;
using nlohmann::json;

uint64_t WallTimeNs() {
  return static_cast<uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                   std::chrono::system_clock::now().time_since_epoch())
                                   .count());
}

namespace {
std::chrono::steady_clock::duration Seconds(double s) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(s));
}
}  // namespace

Bridge::Bridge(asio::io_context& io, Server* server, BridgeOptions options)
    : io_(io),
      server_(server),
      options_(std::move(options)),
      socket_(io),
      reconnect_timer_(io),
      tick_timer_(io),
      in_(options_.max_line_bytes) {}

void Bridge::Start() {
  stopped_ = false;
  backoff_s_ = options_.backoff_min_s;
  PublishDisconnected();
  Connect();
  Tick();
}

void Bridge::Stop() {
  stopped_ = true;
  ++generation_;
  error_code ec;
  socket_.close(ec);
  reconnect_timer_.cancel();
  tick_timer_.cancel();
}

void Bridge::Connect() {
  if (stopped_) return;
  const uint64_t gen = ++generation_;
  error_code ec;
  socket_.close(ec);
  socket_ = asio::local::stream_protocol::socket(io_);
  socket_.async_connect(
      asio::local::stream_protocol::endpoint(options_.socket_path),
      [this, gen](const error_code& e) {
        if (gen != generation_ || stopped_) return;
        if (e) return Lost("cannot reach irslamd at " + options_.socket_path + ": " + e.message());
        OnConnected();
      });
}

void Bridge::OnConnected() {
  connected_ = true;
  ++stats_.connects;
  last_status_ = std::chrono::steady_clock::now();
  std::fprintf(stderr, "<6>foxglove: connected to irslamd at %s\n", options_.socket_path.c_str());
  out_.clear();
  writing_ = false;
  in_.consume(in_.size());
  map_id_ = 0;
  subscribe_id_ = next_id_++;
  Send(json{{"jsonrpc", "2.0"},
            {"id", subscribe_id_},
            {"method", "subscribe"},
            {"params", {{"rate", options_.status_rate_hz}}}}
           .dump());
  ReadLine();
}

void Bridge::Send(std::string line) {
  out_.push_back(std::move(line) + "\n");
  if (!writing_) WriteNext();
}

void Bridge::WriteNext() {
  if (out_.empty()) {
    writing_ = false;
    return;
  }
  writing_ = true;
  const uint64_t gen = generation_;
  asio::async_write(socket_, asio::buffer(out_.front()), [this, gen](const error_code& ec, size_t) {
    if (gen != generation_ || stopped_) return;
    if (ec) return Lost("irslamd: write: " + ec.message());
    out_.pop_front();
    WriteNext();
  });
}

void Bridge::ReadLine() {
  const uint64_t gen = generation_;
  asio::async_read_until(socket_, in_, '\n', [this, gen](const error_code& ec, size_t n) {
    if (gen != generation_ || stopped_) return;
    if (ec) {
      if (ec == asio::error::not_found) return Lost("irslamd sent a line over the size limit");
      return Lost(ec == asio::error::eof ? "irslamd closed the connection"
                                         : "irslamd: read: " + ec.message());
    }
    std::string line(asio::buffers_begin(in_.data()),
                     asio::buffers_begin(in_.data()) + static_cast<std::ptrdiff_t>(n));
    in_.consume(n);
    HandleLine(line);
    if (gen == generation_ && !stopped_) ReadLine();
  });
}

void Bridge::HandleLine(const std::string& line) {
  std::string error;
  auto j = ParseJsonText(line, &error);
  if (!j || !j->is_object()) {
    std::fprintf(stderr, "<4>foxglove: irslamd sent something that is not a JSON object\n");
    return;
  }
  const uint64_t t = WallTimeNs();
  if (j->contains("method") && !j->contains("id")) {  // a status notification
    if ((*j).contains("params") && (*j)["params"].is_object()) {
      last_status_ = std::chrono::steady_clock::now();
      OnStatus((*j)["params"], t);
    }
    return;
  }
  if (!j->contains("id")) return;
  const json& id = (*j)["id"];
  const bool is_error = j->contains("error");
  const std::string message =
      is_error && (*j)["error"].is_object() ? (*j)["error"].value("message", "error") : "";
  if (id == subscribe_id_) {
    if (is_error) Lost("irslamd refused the subscription: " + message);
    return;
  }
  if (map_id_ != 0 && id == map_id_) {
    map_id_ = 0;
    if (is_error) {
      std::fprintf(stderr, "<4>foxglove: irslamd: map: %s\n", message.c_str());
    } else if (j->contains("result")) {
      OnMap((*j)["result"], t);
    }
  }
}

void Bridge::Lost(const std::string& why) {
  ++generation_;
  error_code ec;
  socket_.close(ec);
  out_.clear();
  writing_ = false;
  map_id_ = 0;
  if (connected_ || why != last_error_) {
    std::fprintf(stderr, "<4>foxglove: %s; trying again (every %g s at most)\n", why.c_str(),
                 options_.backoff_max_s);
  }
  if (connected_) {
    ++stats_.disconnects;
    backoff_s_ = options_.backoff_min_s;
  }
  connected_ = false;
  last_error_ = why;
  PublishDisconnected();
  if (stopped_) return;
  reconnect_timer_.expires_after(Seconds(backoff_s_));
  backoff_s_ = std::min(options_.backoff_max_s, backoff_s_ * 2);
  reconnect_timer_.async_wait([this](const error_code& ec2) {
    if (!ec2 && !stopped_) Connect();
  });
}

bool Bridge::MapWanted() const {
  return server_->HasSubscribers(kTrajectory) || server_->HasSubscribers(kMapLines) ||
         server_->HasSubscribers(kMapObjects) || server_->HasSubscribers(kMapRoom);
}

void Bridge::Tick() {
  if (stopped_) return;
  if (connected_) {
    if (std::chrono::steady_clock::now() - last_status_ > Seconds(options_.status_timeout_s)) {
      Lost("no status from irslamd for " +
           std::to_string(static_cast<int>(options_.status_timeout_s)) + " s");
    } else if (map_id_ == 0 && MapWanted()) {
      map_id_ = next_id_++;
      Send(json{{"jsonrpc", "2.0"}, {"id", map_id_}, {"method", "map"}}.dump());
    }
  }
  tick_timer_.expires_after(Seconds(options_.map_period_s));
  tick_timer_.async_wait([this](const error_code& ec) {
    if (!ec) Tick();
  });
}

void Bridge::OnStatus(const json& status, uint64_t t_ns) {
  ++stats_.statuses;
  if (connected_) backoff_s_ = options_.backoff_min_s;
  if (auto m = FrameTransformMessage(status, t_ns)) server_->Publish(kTf, t_ns, m->dump());
  if (auto m = PoseMessage(status, t_ns)) server_->Publish(kPose, t_ns, m->dump());
  if (auto m = IrMessage(status, options_.robot, t_ns)) server_->Publish(kIr, t_ns, m->dump());
  server_->Publish(kState, t_ns, StateMessage(status, true, "", t_ns).dump());
}

void Bridge::OnMap(const json& map, uint64_t t_ns) {
  ++stats_.maps;
  server_->Publish(kTrajectory, t_ns, TrajectoryMessage(map, t_ns).dump());
  server_->Publish(kMapLines, t_ns, LinesMessage(map, t_ns).dump());
  server_->Publish(kMapObjects, t_ns, ObjectsMessage(map, t_ns).dump());
  server_->Publish(kMapRoom, t_ns, RoomMessage(map, t_ns).dump());
}

void Bridge::PublishDisconnected() {
  const uint64_t t = WallTimeNs();
  server_->Publish(
      kState, t,
      StateMessage(json(), false, last_error_.empty() ? "not connected yet" : last_error_, t)
          .dump());
}

}  // namespace irslam::foxglove
