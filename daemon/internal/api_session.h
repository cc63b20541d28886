// Private to the API server (api_server*.cc, api_session.cc): one client
// connection, and the small helpers the server's files share.
#ifndef IRSLAM_DAEMON_INTERNAL_API_SESSION_H_
#define IRSLAM_DAEMON_INTERNAL_API_SESSION_H_

#include <array>
#include <atomic>
#include <boost/asio/io_context.hpp>
#include <boost/asio/local/stream_protocol.hpp>
#include <boost/asio/steady_timer.hpp>
#include <chrono>
#include <cstdint>
#include <deque>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>

#include "daemon/api_server.h"

namespace irslam {

namespace api_internal {

using Clock = std::chrono::steady_clock;

inline Clock::duration Seconds(double s) {
  return std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(s));
}

// The rate a subscribe request asks for, or nullopt when it is not a number in (0, max].
std::optional<double> SubscribeRate(const nlohmann::json& params, double max_rate_hz);

// Best effort, never blocks: one line to a client that is being closed.
void SendAndForget(int fd, const std::string& text);

}  // namespace api_internal

struct ApiServer::Loop {
  boost::asio::io_context io{1};
};

struct ApiServer::Counters {
  std::atomic<uint64_t> accepted{0}, rejected_full{0}, requests{0}, errors{0}, dropped_slow{0},
      dropped_long_line{0}, dropped_idle{0}, dropped_line_timeout{0}, evicted_idle{0},
      control_slot{0}, accept_backoffs{0}, coalesced{0}, paused{0}, cpu_pauses{0};
};

// One client connection. It reads request lines within the limits (line
// length, time to finish a line, unanswered requests, the API thread's CPU
// share), hands each parsed request to the server for the control loop, queues
// the answers for a client that may read slowly (and drops it when too much is
// queued), and sends status notifications while subscribed. Lives on the API
// thread: every member function runs there; handlers hold it by shared_ptr.
class ApiServer::Session : public std::enable_shared_from_this<Session> {
 public:
  using Local = boost::asio::local::stream_protocol;

  Session(ApiServer* server, Local::socket socket, PeerCred peer, bool control_only);

  void Start();
  void Close();
  // Closed at once to make room (or for a broken rule), with a last line if it fits.
  void Evict(const std::string& why);
  // Goes on after a pause for the API thread's CPU budget.
  // It may handle one line whatever the budget: every waiting client makes
  // progress in every window (a `stop` waits at most one window).
  void Resume();

  // No request of this client is waiting for the control loop.
  bool idle() const { return at_control_ == 0; }
  bool control_only() const { return control_only_; }
  api_internal::Clock::time_point last_request() const { return last_request_; }

  // The control loop's answer to one of this client's requests (request null:
  // a notification payload).
  void OnAnswer(const std::shared_ptr<const rpc::Request>& req, Outcome o);

 private:
  using Clock = api_internal::Clock;

  size_t InFlight() const { return at_control_ + queue_.size(); }
  // After anything that may have freed budget: handle buffered lines, read on, or finish.
  void Continue();
  void MaybeFinish();
  void ArmIdle();
  void ArmLineTimer();
  void OnLineTimer();
  void ReadMore();
  void OnRead(size_t n);
  void ProcessLines();
  // Whether the complete line ending at nl may be handled now (else it waits).
  bool MayTakeLine(size_t nl);
  void LongLine();
  void HandleLine(std::string_view line);
  void StartSubscription(double rate);
  void Notify();
  void Send(std::string text);
  void WriteNext();

  ApiServer* server_;
  const ApiLimits& limits_;
  Local::socket socket_;
  PeerCred peer_;
  const bool control_only_;
  boost::asio::steady_timer idle_timer_;
  boost::asio::steady_timer line_timer_;
  boost::asio::steady_timer sub_timer_;
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

}  // namespace irslam

#endif  // IRSLAM_DAEMON_INTERNAL_API_SESSION_H_
