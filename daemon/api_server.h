// The control API server: JSON-RPC 2.0 over a Unix stream socket, one JSON
// object per line (contracts.md §6). Bounded everywhere: request line length
// and nesting depth, number of clients, unanswered requests per client, time to
// finish a line, idle time, bytes queued for a client that does not read.
//
// Threads: the server runs its own io_context on one dedicated thread (the "API
// thread"): accepting, reading, parsing, subscriptions and serialising replies
// all happen there. A parsed request is posted to the control loop's io_context
// (the one passed in), where the Dispatcher runs; its reply json is posted back
// to the API thread and serialised there. Nothing else is shared between the
// two threads except the statistics counters (atomics). No client can delay a
// control period by more than the Dispatcher's own work for one request, and
// `status`, `map` and status notifications are built at most once per control
// period however many clients ask (NewPeriod()).
//
// Files: api_server.cc (life cycle, accepting, admission), api_session.cc (one
// client connection), api_dispatch.cc (the control loop's side, per-period
// sharing), api_cpu_share.cc (the API thread's CPU share); private headers in
// daemon/internal/.
#ifndef IRSLAM_DAEMON_API_SERVER_H_
#define IRSLAM_DAEMON_API_SERVER_H_

#include <pthread.h>

#include <sys/types.h>

#include <atomic>
#include <boost/asio/io_context.hpp>
#include <boost/asio/steady_timer.hpp>
#include <boost/asio/local/stream_protocol.hpp>
#include <cstdint>
#include <functional>
#include <list>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "daemon/jsonrpc.h"

namespace irslam {

class ApiCpuShare;

// Upper bounds of the limits (config.cc should use the same ones).
inline constexpr size_t kMaxLineBytesLimit = 1 << 20;  // 1 MiB
// File descriptors kept free for everything but API clients (bus, GPIO, map saves, logs).
inline constexpr size_t kReservedFds = 64;
// The most API clients the process's RLIMIT_NOFILE (soft limit) allows.
size_t MaxClientsForFdLimit();

struct ApiLimits {
  size_t max_line_bytes = 64 * 1024;   // ≤ kMaxLineBytesLimit
  size_t max_clients = 16;             // ≤ MaxClientsForFdLimit(); one more is kept for control calls
  double idle_timeout_s = 300;         // a client that sends nothing (and is not subscribed)
  size_t max_pending_bytes = 1 << 20;  // queued for a client that does not read
  double max_rate_hz = 50;             // subscription rate limit
  size_t max_inflight = 4;             // unanswered requests per client before it is no longer read
  double line_timeout_s = 10;          // a line must be complete this long after its first byte
  double accept_backoff_s = 0.1;       // pause before accepting again when out of file descriptors
  // The API thread handles requests for at most cpu_share of each cpu_window_s
  // (then every client waits for the next window), so a flood of requests
  // cannot take a whole core from the control loop on a small machine.
  double cpu_share = 0.25;
  double cpu_window_s = 0.02;
};

struct PeerCred {
  pid_t pid = -1;
  uid_t uid = static_cast<uid_t>(-1);
  gid_t gid = static_cast<gid_t>(-1);
  // The peer's primary and supplementary groups as the kernel knows them
  // (SO_PEERGROUPS; only the primary gid where the kernel lacks it).
  std::vector<gid_t> groups;
};

struct ApiStats {
  uint64_t accepted = 0;
  uint64_t rejected_full = 0;
  uint64_t requests = 0;
  uint64_t errors = 0;
  uint64_t dropped_slow = 0;
  uint64_t dropped_long_line = 0;
  uint64_t dropped_idle = 0;
  uint64_t dropped_line_timeout = 0;  // a line not finished within line_timeout_s (slowloris)
  uint64_t evicted_idle = 0;          // closed to admit a new client when full
  uint64_t control_slot = 0;          // clients admitted to the reserved control-only slot
  uint64_t accept_backoffs = 0;       // accept failed for lack of file descriptors
  uint64_t coalesced = 0;             // status/map/notification answers served from this period's result
  uint64_t paused = 0;                // a client hit max_inflight and was not read until answered
  uint64_t cpu_pauses = 0;            // windows in which the API thread used up its CPU share
};

class ApiServer {
 public:
  class Dispatcher {
   public:
    virtual ~Dispatcher() = default;
    // Takes the full response (MakeResult or MakeError). Callable exactly once,
    // on the control thread, possibly later; harmless if the client is gone.
    using Reply = std::function<void(nlohmann::json response)>;
    // Called on the control thread.
    virtual void Handle(const rpc::Request& request, const PeerCred& peer, Reply reply) = 0;
    // Whether this peer may read (subscribe, and `status`/`map` served from the
    // result already built this period). Called on the control thread.
    virtual bool MaySubscribe(const PeerCred& peer) = 0;
    // The payload of a status notification. Called on the control thread.
    virtual nlohmann::json StatusNotification() = 0;
  };

  // control: the control loop's io_context, where the Dispatcher is called.
  ApiServer(boost::asio::io_context& control, std::string path, ApiLimits limits,
            Dispatcher* dispatcher);
  ~ApiServer();
  ApiServer(const ApiServer&) = delete;
  ApiServer& operator=(const ApiServer&) = delete;

  // Checks the limits, binds and listens (mode 0660, the group given when set),
  // starts the API thread; false with a one-line *error otherwise. An existing
  // file at the path is only replaced when it is a socket nobody listens on.
  bool Listen(std::string* error, std::optional<gid_t> socket_group = std::nullopt);
  // Serves an already connected socket (fuzzing, tests); takes ownership of fd.
  void Adopt(int fd, PeerCred peer);
  // Stops the API thread and closes every client. Control thread.
  void Close();
  // The API thread, for its scheduling (daemon/realtime.h); false before it runs.
  bool ApiThread(pthread_t* thread) {
    if (!thread_.joinable()) return false;
    *thread = thread_.native_handle();
    return true;
  }
  // The control loop calls this once per period: `status`, `map` and
  // notification payloads are rebuilt at most once per period. Control thread.
  void NewPeriod() { ++period_; }

  size_t client_count() const { return clients_.load(); }
  ApiStats stats() const;
  // client_count() and stats() as the `api` object of `status`.
  nlohmann::json StatsJson() const;
  const std::string& path() const { return path_; }

  class Session;

 private:
  friend class Session;
  struct Loop;  // the API thread's io_context (shared so a late reply can still post to it)
  struct Outcome {
    nlohmann::json response;                      // a whole response, or
    std::shared_ptr<const nlohmann::json> result;  // a shared result (coalesced)
    std::string key;                              // its cache key ("status", "map", "@notify")
  };
  struct Counters;
  struct Cached {
    uint64_t period = 0;
    std::shared_ptr<const nlohmann::json> result;
  };

  void StartThread();
  void Accept();
  // API thread: accept failed for want of descriptors (or memory): try again later.
  void BackOff(const boost::system::error_code& ec);
  void Admit(boost::asio::local::stream_protocol::socket socket, PeerCred peer);
  void Remove(Session* s);
  // API thread: hands a request (null: a notification payload) to the control loop.
  void PostToControl(std::weak_ptr<Session> session, std::shared_ptr<const rpc::Request> request,
                     PeerCred peer);
  // Control thread: runs it and posts the outcome back to the session.
  void OnControl(std::weak_ptr<Session> session, std::shared_ptr<const rpc::Request> request,
                 const PeerCred& peer);
  // API thread: the text for a shared result, serialised once per result.
  const std::string& SharedText(const std::string& key,
                                const std::shared_ptr<const nlohmann::json>& result);

  boost::asio::io_context& control_;
  std::string path_;
  ApiLimits limits_;
  Dispatcher* dispatcher_;
  std::shared_ptr<Loop> loop_;
  std::unique_ptr<Counters> counters_;
  std::atomic<size_t> clients_{0};
  std::jthread thread_;
  bool open_ = false;
  bool listening_ = false;
  // Control thread only.
  uint64_t period_ = 1;
  std::map<std::string, Cached> cache_;
  std::shared_ptr<int> alive_ = std::make_shared<int>(0);
  // API thread only.
  std::unique_ptr<boost::asio::local::stream_protocol::acceptor> acceptor_;
  std::list<std::shared_ptr<Session>> sessions_;
  std::map<std::string, std::pair<std::shared_ptr<const nlohmann::json>, std::string>> texts_;
  std::unique_ptr<ApiCpuShare> cpu_share_;
  std::unique_ptr<boost::asio::steady_timer> accept_timer_;  // the back-off (made beforehand)
  bool accepting_ = false;
};

}  // namespace irslam

#endif  // IRSLAM_DAEMON_API_SERVER_H_
