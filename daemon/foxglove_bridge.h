// irslam-foxglove's side towards irslamd: a client of the control API (contracts
// §6) on the one io_context, like irslamctl but non-blocking. It subscribes to
// status notifications and polls `map` while someone looks at a map topic, and
// turns both into the Foxglove channels (daemon/foxglove_messages.h). When
// irslamd goes away (restart, not yet started) it reconnects with back-off and
// /state says "disconnected".
#ifndef IRSLAM_DAEMON_FOXGLOVE_BRIDGE_H_
#define IRSLAM_DAEMON_FOXGLOVE_BRIDGE_H_

#include <boost/asio/io_context.hpp>
#include <boost/asio/local/stream_protocol.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/streambuf.hpp>
#include <chrono>
#include <cstdint>
#include <deque>
#include <nlohmann/json.hpp>
#include <string>

#include "daemon/foxglove_messages.h"
#include "daemon/foxglove_server.h"

namespace irslam::foxglove {

struct BridgeOptions {
  std::string socket_path;     // irslamd's control socket
  double status_rate_hz = 10;  // the subscribe rate asked of irslamd
  double map_period_s = 1;     // map polls while a map topic has subscribers
  double backoff_min_s = 0.2;  // reconnect delays, doubling up to the max
  double backoff_max_s = 5;
  double status_timeout_s = 5;  // no status this long: reconnect (a hung daemon)
  size_t max_line_bytes = 64u << 20;
  RobotShape robot;
};

struct BridgeStats {
  uint64_t connects = 0;
  uint64_t statuses = 0;
  uint64_t maps = 0;
  uint64_t disconnects = 0;
};

class Bridge {
 public:
  Bridge(boost::asio::io_context& io, Server* server, BridgeOptions options);
  Bridge(const Bridge&) = delete;
  Bridge& operator=(const Bridge&) = delete;

  void Start();
  void Stop();
  bool connected() const { return connected_; }
  const BridgeStats& stats() const { return stats_; }

  // The messages of one status / one map (also what the tests call).
  void OnStatus(const nlohmann::json& status, uint64_t t_ns);
  void OnMap(const nlohmann::json& map, uint64_t t_ns);

 private:
  void Connect();
  void OnConnected();
  void Send(std::string line);
  void WriteNext();
  void ReadLine();
  void HandleLine(const std::string& line);
  void Lost(const std::string& why);
  void Tick();
  bool MapWanted() const;
  void PublishDisconnected();

  boost::asio::io_context& io_;
  Server* server_;
  BridgeOptions options_;
  boost::asio::local::stream_protocol::socket socket_;
  boost::asio::steady_timer reconnect_timer_;
  boost::asio::steady_timer tick_timer_;
  boost::asio::streambuf in_;
  std::deque<std::string> out_;
  bool writing_ = false;
  bool connected_ = false;
  bool stopped_ = false;
  uint64_t generation_ = 0;  // bumps at each (re)connect: stale handlers see it
  double backoff_s_ = 0;
  int next_id_ = 1;
  int subscribe_id_ = 0;
  int map_id_ = 0;  // the map request in flight (0: none)
  std::chrono::steady_clock::time_point last_status_;
  std::string last_error_;
  BridgeStats stats_;
};

// Wall-clock time in ns since the epoch (the log and header time of every message).
uint64_t WallTimeNs();

}  // namespace irslam::foxglove

#endif  // IRSLAM_DAEMON_FOXGLOVE_BRIDGE_H_
