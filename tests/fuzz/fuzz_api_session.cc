// libFuzzer target: a whole API session. The input is what one client sends on
// one connection (any number of lines, pipelined); it goes through the real
// server (ApiServer::Adopt on one end of a socketpair: the API thread reads,
// parses, budgets and serialises; the dispatcher runs on this thread as the
// control loop). Every line that comes back must be valid JSON, and the session
// must end (the server closes once everything asked is answered).
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <boost/asio/io_context.hpp>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
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
  int fds[2];
  if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, fds) != 0) std::abort();
  irslam::PeerCred peer;
  peer.uid = ::getuid();
  peer.gid = ::getgid();
  peer.groups = {peer.gid};
  h->server.Adopt(fds[1], peer);
  std::string out;
  size_t sent = 0;
  bool shut = false;
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  for (;;) {
    if (sent < size) {
      const ssize_t n = ::send(fds[0], data + sent, size - sent, MSG_DONTWAIT | MSG_NOSIGNAL);
      if (n > 0) sent += static_cast<size_t>(n);
      if (n < 0 && errno != EAGAIN) sent = size;  // the server hung up (a long line)
    }
    if (sent >= size && !shut) {
      ::shutdown(fds[0], SHUT_WR);
      shut = true;
    }
    h->io.poll();
    h->io.restart();
    char buf[65536];
    const ssize_t n = ::recv(fds[0], buf, sizeof buf, MSG_DONTWAIT);
    if (n > 0) {
      out.append(buf, static_cast<size_t>(n));
      continue;
    }
    if (n == 0 || (n < 0 && errno == ECONNRESET)) break;  // the server closed: done
    if (std::chrono::steady_clock::now() > deadline) {
      std::fprintf(stderr, "fuzz_api_session: the session never ended\n");
      std::abort();
    }
    pollfd p{fds[0], POLLIN, 0};
    ::poll(&p, 1, 0);
    std::this_thread::yield();
  }
  ::close(fds[0]);
  CheckLines(out);
  return 0;
}
