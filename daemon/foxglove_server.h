// The Foxglove WebSocket server of irslam-foxglove (Boost.Beast on the one
// single-threaded io_context): accepts clients that offer foxglove.websocket.v1,
// sends serverInfo and the advertise of its channels, carries out subscribe and
// unsubscribe, and fans published messages out to the subscribers. Each client
// has a bounded send queue: a slow client loses messages (counted), never blocks
// the others or grows memory. Bad input from a client: one log line, that client
// is closed.
#ifndef IRSLAM_DAEMON_FOXGLOVE_SERVER_H_
#define IRSLAM_DAEMON_FOXGLOVE_SERVER_H_

#include <boost/asio/io_context.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <cstdint>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "daemon/foxglove_protocol.h"

namespace irslam::foxglove {

struct ServerOptions {
  std::string name = "irslam-foxglove";
  size_t max_clients = 16;
  size_t max_queued_frames = 64;        // per client; data beyond it is dropped
  size_t max_queued_bytes = 16u << 20;  // per client
  size_t max_client_message_bytes = 64u << 10;
  double handshake_timeout_s = 10;
  double idle_timeout_s = 30;  // a client that answers no ping this long is closed
};

struct ServerStats {
  uint64_t accepted = 0;
  uint64_t rejected = 0;   // over max_clients, not a websocket, no foxglove subprotocol
  uint64_t bad_input = 0;  // clients closed for what they sent
  uint64_t dropped = 0;    // messages not sent to a slow client
  uint64_t sent = 0;       // message data frames queued to clients
};

class Server {
 public:
  Server(boost::asio::io_context& io, std::vector<Channel> channels, ServerOptions options = {});
  ~Server();
  Server(const Server&) = delete;
  Server& operator=(const Server&) = delete;

  // Binds and starts accepting; false with *error (one line) when it cannot.
  bool Listen(const boost::asio::ip::tcp::endpoint& endpoint, std::string* error);
  boost::asio::ip::tcp::endpoint local_endpoint() const;

  // Sends payload (the channel's JSON text) to every subscriber of channel_id, and
  // keeps it as the channel's latest: a client that subscribes later gets it at once.
  void Publish(uint32_t channel_id, uint64_t log_time_ns, std::string payload);
  bool HasSubscribers(uint32_t channel_id) const;
  // Sends a status message (op "status") to every client.
  void Broadcast(Level level, const std::string& message);
  size_t clients() const { return sessions_.size(); }
  const ServerStats& stats() const { return stats_; }
  // Stops accepting and closes every client.
  void Close();

 private:
  class Session;
  struct Latest {
    uint64_t t_ns = 0;
    std::shared_ptr<const std::string> payload;
  };
  void Accept();
  void Remove(Session* s);

  boost::asio::ip::tcp::acceptor acceptor_;
  std::vector<Channel> channels_;
  std::string server_info_;  // the serverInfo and advertise texts, made once
  std::string advertise_;
  ServerOptions options_;
  ServerStats stats_;
  std::set<std::shared_ptr<Session>> sessions_;
  std::map<uint32_t, Latest> latest_;
  bool closed_ = false;
};

}  // namespace irslam::foxglove

#endif  // IRSLAM_DAEMON_FOXGLOVE_SERVER_H_
