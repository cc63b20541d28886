// The control API server: JSON-RPC 2.0 over a Unix stream socket, one JSON
// object per line (contracts.md §6). Bounded everywhere: request line length,
// number of clients, idle time, bytes queued for a client that does not read.
// A slow or stalled client is dropped; it can never block the control loop.
#ifndef IRSLAM_DAEMON_API_SERVER_H_
#define IRSLAM_DAEMON_API_SERVER_H_

#include <sys/types.h>

#include <boost/asio/io_context.hpp>
#include <boost/asio/local/stream_protocol.hpp>
#include <list>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "daemon/jsonrpc.h"

namespace irslam {

struct ApiLimits {
  size_t max_line_bytes = 64 * 1024;
  size_t max_clients = 16;
  double idle_timeout_s = 300;        // a client that sends nothing (and is not subscribed)
  size_t max_pending_bytes = 1 << 20; // queued for a client that does not read
  double max_rate_hz = 50;            // subscription rate limit
};

struct PeerCred {
  pid_t pid = -1;
  uid_t uid = static_cast<uid_t>(-1);
  gid_t gid = static_cast<gid_t>(-1);
};

struct ApiStats {
  uint64_t accepted = 0;
  uint64_t rejected_full = 0;
  uint64_t requests = 0;
  uint64_t errors = 0;
  uint64_t dropped_slow = 0;
  uint64_t dropped_long_line = 0;
  uint64_t dropped_idle = 0;
};

class ApiServer {
 public:
  class Dispatcher {
   public:
    virtual ~Dispatcher() = default;
    // Returns the full response (MakeResult or MakeError) for a request.
    virtual nlohmann::json Handle(const rpc::Request& request, const PeerCred& peer) = 0;
    // Whether this peer may subscribe to status notifications.
    virtual bool MaySubscribe(const PeerCred& peer) = 0;
    // The payload of a status notification.
    virtual nlohmann::json StatusNotification() = 0;
  };

  ApiServer(boost::asio::io_context& io, std::string path, ApiLimits limits, Dispatcher* dispatcher);
  ~ApiServer();
  ApiServer(const ApiServer&) = delete;
  ApiServer& operator=(const ApiServer&) = delete;

  // Binds and listens (mode 0660); false with a one-line *error otherwise.
  bool Listen(std::string* error);
  void Close();

  size_t client_count() const { return sessions_.size(); }
  const ApiStats& stats() const { return stats_; }
  const std::string& path() const { return path_; }

  class Session;

 private:
  friend class Session;
  void Accept();
  void Remove(Session* s);

  boost::asio::io_context& io_;
  std::string path_;
  ApiLimits limits_;
  Dispatcher* dispatcher_;
  boost::asio::local::stream_protocol::acceptor acceptor_;
  std::list<std::shared_ptr<Session>> sessions_;
  ApiStats stats_;
  bool open_ = false;
};

}  // namespace irslam

#endif  // IRSLAM_DAEMON_API_SERVER_H_
