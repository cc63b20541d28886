// libFuzzer target: a whole API session. The input is what one client sends on
// one connection (any number of lines, pipelined); it goes through the real
// server (ApiServer::Adopt on one end of a socketpair: the API thread reads,
// parses, budgets and serialises; the dispatcher runs on this thread as the
// control loop). Covered: line splitting and partial lines, the long-line hang-up
// (max_line_bytes 1024, within -max_len), the max_inflight pause (2), the API
// thread's CPU share (the daemon's defaults, 25 % of 20 ms windows: reached by
// sessions with many lines), subscribe and its rate check (max_rate_hz 1000),
// `status`/`map` served from the per-period cache (rpc::ResultText), errors for
// any id/method/params, invalid UTF-8. Every line that comes back must be valid
// JSON, the session must end (the server closes once everything asked is
// answered) and the server must then forget it (client_count() back to 0).
// Speed: this thread sleeps in the control loop's io_context (the client socket
// is on it too) instead of spinning on poll(0) + yield, which took a core from
// the API thread on a 2-core machine; waiting for the session to be removed
// keeps libFuzzer's malloc/free balance per input, so LeakSanitizer runs only
// when something really stays allocated (before, most inputs ended with the
// session still being torn down and each paid for a whole-heap leak scan).
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <boost/asio/io_context.hpp>
#include <boost/asio/local/stream_protocol.hpp>
#include <boost/asio/write.hpp>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <string>
#include <thread>

#include "daemon/api_server.h"

namespace {

class Dispatcher : public irslam::ApiServer::Dispatcher {
 public:
  void Handle(const irslam::rpc::Request& r, const irslam::PeerCred&, Reply reply) override {
    namespace rpc = irslam::rpc;
    if (r.method == "status") {
      reply(rpc::MakeResult(r.id, {{"state", "idle"}, {"echo", r.params}}));
    } else if (r.method == "map") {
      reply(rpc::MakeResult(r.id, {{"lines", nlohmann::json::array({{{"a", {0, 0}}, {"b", {1, 2}}}})}}));
    } else if (r.method == "start" || r.method == "stop") {
      reply(rpc::MakeResult(r.id, {{"state", r.method}}));
    } else {
      reply(rpc::MakeError(r.id, rpc::kMethodNotFound, "method not found: " + r.method));
    }
  }
  bool MaySubscribe(const irslam::PeerCred&) override { return true; }
  nlohmann::json StatusNotification() override { return {{"state", "idle"}}; }
};

struct Harness {
  Harness() : server(io, "/nonexistent/fuzz.sock", Limits(), &dispatcher) {}
  static irslam::ApiLimits Limits() {
    irslam::ApiLimits l;
    l.max_line_bytes = 1024;  // the long-line path is reachable within -max_len
    l.max_inflight = 2;
    l.max_rate_hz = 1000;
    l.max_clients = 4;
    return l;
  }
  boost::asio::io_context io;
  Dispatcher dispatcher;
  irslam::ApiServer server;
};

void CheckLines(const std::string& out) {
  size_t start = 0;
  for (size_t nl; (nl = out.find('\n', start)) != std::string::npos; start = nl + 1) {
    if (!nlohmann::json::accept(out.begin() + static_cast<long>(start),
                                out.begin() + static_cast<long>(nl))) {
      std::fprintf(stderr, "fuzz_api_session: invalid JSON sent: %s\n",
                   out.substr(start, nl - start).c_str());
      std::abort();
    }
  }
  if (start != out.size()) {
    std::fprintf(stderr, "fuzz_api_session: unterminated line sent\n");
    std::abort();
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static Harness* h = new Harness();  // one server for the whole run, like the daemon's
  using Local = boost::asio::local::stream_protocol;
  int fds[2];
  if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds) != 0) std::abort();
  irslam::PeerCred peer;
  peer.uid = ::getuid();
  peer.gid = ::getgid();
  peer.groups = {peer.gid};
  h->server.Adopt(fds[1], peer);
  // The client's end on the control loop's io_context: this thread sleeps in
  // epoll until the server answers or posts a request to the control loop.
  Local::socket client(h->io);
  boost::system::error_code ec;
  client.assign(Local(), fds[0], ec);
  if (ec) std::abort();
  std::string out;
  bool read_done = false, write_done = false;
  boost::asio::async_write(client, boost::asio::buffer(data, size),
                           [&](const boost::system::error_code& e, size_t) {
                             // All sent, or the server hung up (a long line): EOF either way.
                             boost::system::error_code ignored;
                             if (!e) client.shutdown(Local::socket::shutdown_send, ignored);
                             write_done = true;
                           });
  std::array<char, 65536> buf;
  std::function<void()> read = [&] {
    client.async_read_some(boost::asio::buffer(buf), [&](const boost::system::error_code& e, size_t n) {
      if (e) {  // the server closed (EOF or reset): done
        read_done = true;
        boost::system::error_code ignored;
        client.close(ignored);  // a write still pending ends now
        return;
      }
      out.append(buf.data(), n);
      read();
    });
  };
  read();
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  h->io.restart();
  while (!read_done || !write_done) {
    const auto left = deadline - std::chrono::steady_clock::now();
    if (left <= std::chrono::steady_clock::duration::zero() || h->io.run_one_for(left) == 0) {
      if (std::chrono::steady_clock::now() < deadline) continue;
      std::fprintf(stderr, "fuzz_api_session: the session never ended\n");
      std::abort();
    }
  }
  // The server forgets the session (Remove) right after closing it: a session
  // still counted here once its socket is closed would be one it never frees.
  while (h->server.client_count() != 0) {
    if (std::chrono::steady_clock::now() > deadline) {
      std::fprintf(stderr, "fuzz_api_session: a closed session was never removed\n");
      std::abort();
    }
    h->io.poll();  // the control loop's side of anything still posted
    h->io.restart();
    std::this_thread::yield();
  }
  h->io.poll();
  CheckLines(out);
  return 0;
}
