#include <fcntl.h>
#include <grp.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <sys/resource.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstring>
#include <functional>

#include <boost/asio/executor_work_guard.hpp>
#include <boost/asio/post.hpp>
#include <future>
#include <thread>

#include "daemon/api_server.h"
#include "daemon/rpc_client.h"
#include "tests/testing/process.h"

namespace irslam {
namespace {

class FakeDispatcher : public ApiServer::Dispatcher {
 public:
  void Handle(const rpc::Request& r, const PeerCred& peer, Reply reply) override {
    ++calls;
    last_uid = peer.uid;
    last_groups = peer.groups;
    if (r.method == "status") {
      ++status_builds;
      reply(rpc::MakeResult(r.id, {{"state", "idle"}}));
    } else if (r.method == "hold") {  // answered only when the test says so
      held.push_back(std::move(reply));
    } else if (r.method == "stop") {
      reply(rpc::MakeResult(r.id, {{"state", "idle"}}));
    } else {
      reply(rpc::MakeError(r.id, rpc::kMethodNotFound, "method not found: " + r.method));
    }
  }
  bool MaySubscribe(const PeerCred&) override { return true; }
  nlohmann::json StatusNotification() override { return {{"state", "idle"}, {"blob", blob}}; }
  std::atomic<int> calls{0};
  std::atomic<uid_t> last_uid{0};
  std::atomic<int> status_builds{0};
  std::vector<Reply> held;           // control thread only
  std::vector<gid_t> last_groups;    // control thread only
  std::string blob;
};

class ApiServerTest : public ::testing::Test {
 protected:
  void StartServer(ApiLimits limits) {
    path_ = testing::MakeTempDir() + "/api.sock";
    server_ = std::make_unique<ApiServer>(io_, path_, limits, &dispatcher_);
    std::string error;
    ASSERT_TRUE(server_->Listen(&error)) << error;
    thread_ = std::thread([this] {
      auto guard = boost::asio::make_work_guard(io_);
      io_.run();
    });
  }
  void TearDown() override {
    if (server_) {
      std::promise<void> done;
      boost::asio::post(io_, [&] {
        server_->Close();
        done.set_value();
      });
      done.get_future().wait();
    }
    io_.stop();
    if (thread_.joinable()) thread_.join();
  }
  std::unique_ptr<RpcClient> Client() {
    auto c = std::make_unique<RpcClient>();
    std::string error;
    EXPECT_TRUE(c->Connect(path_, &error)) << error;
    return c;
  }
  // Runs f on the control thread (io_) and waits for it.
  void OnControl(const std::function<void()>& f) {
    std::promise<void> done;
    boost::asio::post(io_, [&] {
      f();
      done.set_value();
    });
    done.get_future().wait();
  }
  size_t Held() {
    size_t n = 0;
    OnControl([&] { n = dispatcher_.held.size(); });
    return n;
  }
  static nlohmann::json Line(RpcClient& c) {
    std::string error;
    auto l = c.ReadLine(5, &error);
    if (!l) return {{"io_error", error}};
    return nlohmann::json::parse(*l);
  }

  boost::asio::io_context io_;
  FakeDispatcher dispatcher_;
  std::unique_ptr<ApiServer> server_;
  std::string path_;
  std::thread thread_;
};

TEST_F(ApiServerTest, AnswersRequestsAndKnowsThePeer) {
  StartServer({});
  auto c = Client();
  std::string error;
  auto r = c->Call("status", nlohmann::json::object(), 5, &error);
  ASSERT_TRUE(r) << error;
  EXPECT_EQ((*r)["state"], "idle");
  EXPECT_EQ(dispatcher_.last_uid, ::getuid());
  EXPECT_FALSE(c->Call("fly", nlohmann::json::object(), 5, &error));
  EXPECT_EQ(error, "method not found: fly");
}

TEST_F(ApiServerTest, GarbageGetsAParseErrorAndTheConnectionStaysUsable) {
  StartServer({});
  auto c = Client();
  std::string error;
  ASSERT_TRUE(c->SendRaw("this is not json\n", &error));
  auto e = Line(*c);
  EXPECT_EQ(e["error"]["code"], rpc::kParseError);
  EXPECT_EQ(e["id"], nullptr);
  ASSERT_TRUE(c->SendRaw("\r\n\n{\"jsonrpc\":\"2.0\",\"method\":\"status\"}\n", &error));  // notification: no answer
  auto r = c->Call("status", nlohmann::json::object(), 5, &error);
  ASSERT_TRUE(r) << error;
  // The notification's status and the call's: one built, one shared (same period).
  EXPECT_EQ(dispatcher_.calls + server_->stats().coalesced, 2u);
}

TEST_F(ApiServerTest, OversizedLineIsAnsweredAndClosedWhileOthersAreServed) {
  ApiLimits limits;
  limits.max_line_bytes = 1024;
  StartServer(limits);
  auto bad = Client();
  auto good = Client();
  std::string error;
  ASSERT_TRUE(bad->SendRaw(std::string(5000, 'x'), &error));
  auto e = Line(*bad);
  EXPECT_EQ(e["error"]["code"], rpc::kInvalidRequest);
  EXPECT_NE(e["error"]["message"].get<std::string>().find("longer than 1024"), std::string::npos);
  EXPECT_FALSE(bad->ReadLine(2, &error));
  // Closed with unread input: an orderly close or a reset, never left open.
  EXPECT_TRUE(error == "irslamd closed the connection" ||
              error == "recv: Connection reset by peer")
      << error;
  EXPECT_TRUE(good->Call("status", nlohmann::json::object(), 5, &error)) << error;
  EXPECT_EQ(server_->stats().dropped_long_line, 1u);
}

TEST_F(ApiServerTest, HalfSentLineThenHangUpLeavesTheServerFine) {
  StartServer({});
  {
    auto c = Client();
    std::string error;
    ASSERT_TRUE(c->SendRaw("{\"jsonrpc\":\"2.0\",\"id\":1,\"meth", &error));
  }
  auto c = Client();
  std::string error;
  EXPECT_TRUE(c->Call("status", nlohmann::json::object(), 5, &error)) << error;
}

TEST_F(ApiServerTest, AFullServerEvictsTheClientIdleLongestInsteadOfRefusing) {
  // Before: two idle clients (one a subscriber at 0.001 Hz) locked everyone
  // else out ("too many clients") for as long as they stayed.
  ApiLimits limits;
  limits.max_clients = 2;
  StartServer(limits);
  std::string error;
  auto a = Client();
  ASSERT_TRUE(a->Call("subscribe", {{"rate", 0.001}}, 5, &error)) << error;
  std::this_thread::sleep_for(std::chrono::milliseconds(20));
  auto b = Client();
  ASSERT_TRUE(b->Call("status", nlohmann::json::object(), 5, &error)) << error;
  auto c = Client();
  ASSERT_TRUE(c->Call("status", nlohmann::json::object(), 5, &error)) << error;
  const auto e = Line(*a);  // the oldest idle one made room, and was told why
  EXPECT_EQ(e["error"]["code"], rpc::kRejected);
  EXPECT_NE(e.dump().find("idle longest"), std::string::npos) << e.dump();
  EXPECT_FALSE(a->ReadLine(2, &error));
  EXPECT_TRUE(b->Call("status", nlohmann::json::object(), 5, &error)) << error;
  EXPECT_EQ(server_->stats().evicted_idle, 1u);
  EXPECT_EQ(server_->stats().rejected_full, 0u);
  EXPECT_EQ(server_->client_count(), 2u);
}

TEST_F(ApiServerTest, StopGetsThroughTheReservedSlotWhenEveryClientIsBusy) {
  ApiLimits limits;
  limits.max_clients = 2;
  StartServer(limits);
  std::string error;
  auto a = Client(), b = Client();
  // Both have a request at the control loop: neither may be evicted.
  ASSERT_TRUE(a->SendRaw(R"({"jsonrpc":"2.0","id":1,"method":"hold"})" "\n", &error));
  ASSERT_TRUE(b->SendRaw(R"({"jsonrpc":"2.0","id":1,"method":"hold"})" "\n", &error));
  for (int i = 0; i < 200 && Held() < 2; ++i) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  ASSERT_EQ(Held(), 2u);
  // The reserved slot serves start/stop only, then closes.
  auto c = Client();
  EXPECT_FALSE(c->Call("status", nlohmann::json::object(), 5, &error));
  EXPECT_EQ(error, "too many clients: this connection may only start or stop the robot");
  EXPECT_FALSE(c->ReadLine(2, &error));
  auto d = Client();
  auto e = Client();  // the slot is taken by d: refused
  EXPECT_EQ(Line(*e)["error"]["message"], "too many clients");
  auto r = d->Call("stop", nlohmann::json::object(), 5, &error);
  ASSERT_TRUE(r) << error;
  EXPECT_EQ((*r)["state"], "idle");
  EXPECT_FALSE(d->ReadLine(2, &error));  // closed after its one reply
  EXPECT_EQ(server_->stats().control_slot, 2u);
  EXPECT_EQ(server_->stats().rejected_full, 1u);
  OnControl([&] {
    for (auto& reply : dispatcher_.held) reply(rpc::MakeResult(1, "released"));
    dispatcher_.held.clear();
  });
  EXPECT_EQ(Line(*a)["result"], "released");
  EXPECT_EQ(Line(*b)["result"], "released");
}

TEST_F(ApiServerTest, ASlowlorisIsDroppedWhenItsLineIsNotFinishedInTime) {
  // Before: a client sending one byte at a time held its slot for idle_timeout_s.
  ApiLimits limits;
  limits.line_timeout_s = 0.3;
  StartServer(limits);
  auto slow = Client();
  std::string error;
  const std::string line = R"({"jsonrpc":"2.0","id":1,"method":"status"})";
  bool cut = false;
  for (int i = 0; i < 100 && !cut; ++i) {
    cut = !slow->SendRaw(line.substr(i % line.size(), 1), &error);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    if (server_->stats().dropped_line_timeout > 0) break;
  }
  EXPECT_EQ(server_->stats().dropped_line_timeout, 1u);
  auto e = Line(*slow);
  EXPECT_NE(e.dump().find("not finished within"), std::string::npos) << e.dump();
  // The session closes once its error line is written (asynchronously, on the
  // control thread): read the count there, and give it up to 2 s (under
  // AddressSanitizer on a loaded host it was still 1 right after the line).
  size_t clients = 1;
  for (int i = 0; i < 200 && clients != 0; ++i) {
    OnControl([&] { clients = server_->client_count(); });
    if (clients != 0) std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(clients, 0u);
}

TEST_F(ApiServerTest, InvalidUtf8IsAnsweredInsteadOfEndingTheProcess) {
  // Before: the reply echoed the raw byte and dump() threw type_error 316: SIGABRT.
  StartServer({});
  auto c = Client();
  std::string error;
  ASSERT_TRUE(c->SendRaw("{\"jsonrpc\":\"2.0\",\"id\":1,\"method\":\"\xff\"}\n", &error));
  std::string error2;
  auto raw = c->ReadLine(5, &error2);
  ASSERT_TRUE(raw) << error2;
  EXPECT_EQ(raw->find('\xff'), std::string::npos);  // never echoed raw
  auto e = nlohmann::json::parse(*raw);
  EXPECT_EQ(e["error"]["code"], rpc::kParseError);
  EXPECT_NE(e["error"]["message"].get<std::string>().find("ill-formed UTF-8 byte; last read: '\"\xef\xbf\xbd'"),
            std::string::npos) << *raw;  // U+FFFD in its place
  ASSERT_TRUE(c->SendRaw("\xff\n", &error));
  EXPECT_EQ(Line(*c)["error"]["code"], rpc::kParseError);
  ASSERT_TRUE(c->SendRaw("\xff\xfe{\"\xc3\n", &error));
  EXPECT_EQ(Line(*c)["error"]["code"], rpc::kParseError);
  EXPECT_TRUE(c->Call("status", nlohmann::json::object(), 5, &error)) << error;
}

TEST_F(ApiServerTest, StatusIsBuiltOncePerPeriodHoweverManyAsk) {
  StartServer({});
  std::string error;
  std::vector<std::unique_ptr<RpcClient>> clients;
  for (int i = 0; i < 5; ++i) clients.push_back(Client());
  for (auto& c : clients) {
    for (int k = 0; k < 3; ++k) {
      auto r = c->Call("status", nlohmann::json::object(), 5, &error);
      ASSERT_TRUE(r) << error;
      EXPECT_EQ((*r)["state"], "idle");
    }
  }
  EXPECT_EQ(dispatcher_.status_builds, 1);
  EXPECT_EQ(server_->stats().coalesced, 14u);
  OnControl([&] { server_->NewPeriod(); });
  ASSERT_TRUE(clients[0]->Call("status", nlohmann::json::object(), 5, &error)) << error;
  EXPECT_EQ(dispatcher_.status_builds, 2);
  // A command may change what status says: the next one is built afresh.
  ASSERT_TRUE(clients[1]->Call("stop", nlohmann::json::object(), 5, &error)) << error;
  ASSERT_TRUE(clients[1]->Call("status", nlohmann::json::object(), 5, &error)) << error;
  EXPECT_EQ(dispatcher_.status_builds, 3);
}

TEST_F(ApiServerTest, APipeliningClientIsNotReadPastItsBudgetUntilAnswered) {
  ApiLimits limits;
  limits.max_inflight = 2;
  StartServer(limits);
  auto c = Client();
  std::string error;
  std::string batch;
  for (int i = 1; i <= 5; ++i) {
    batch += R"({"jsonrpc":"2.0","id":)" + std::to_string(i) + R"(,"method":"hold"})" "\n";
  }
  ASSERT_TRUE(c->SendRaw(batch, &error));
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  EXPECT_EQ(Held(), 2u);  // before: all 5 went to the control loop at once
  EXPECT_GE(server_->stats().paused, 1u);
  int answered = 0;
  for (int round = 0; round < 10 && answered < 5; ++round) {
    OnControl([&] {
      for (auto& reply : dispatcher_.held) reply(rpc::MakeResult(0, "done"));
      dispatcher_.held.clear();
    });
    while (c->ReadLine(0.2, &error)) ++answered;
  }
  EXPECT_EQ(answered, 5);
}

TEST_F(ApiServerTest, TheApiThreadKeepsToItsCpuShareAndStillServesEveryone) {
  ApiLimits limits;
  limits.cpu_share = 1e-6;  // 50 ns per 50 ms window: about one line per window
  limits.cpu_window_s = 0.05;
  limits.max_inflight = 64;
  StartServer(limits);
  auto c = Client();
  std::string error, batch;
  for (int i = 1; i <= 20; ++i) {
    batch += R"({"jsonrpc":"2.0","id":)" + std::to_string(i) + R"(,"method":"status"})" "\n";
  }
  ASSERT_TRUE(c->SendRaw(batch, &error));
  int answered = 0;
  while (answered < 20 && c->ReadLine(5, &error)) ++answered;
  EXPECT_EQ(answered, 20) << error;
  EXPECT_GE(server_->stats().cpu_pauses, 10u);
}

TEST_F(ApiServerTest, SubscribeRateMustBePositiveAndWithinTheLimitAndATinyOneDoesNotFlood) {
  StartServer({});
  std::string error;
  auto c = Client();
  EXPECT_FALSE(c->Call("subscribe", {{"rate", 1000}}, 5, &error));
  EXPECT_EQ(error, "invalid params: rate must be > 0 and <= 50 (Hz)");
  EXPECT_FALSE(c->Call("subscribe", {{"rate", "fast"}}, 5, &error));
  EXPECT_FALSE(c->Call("subscribe", {{"rate", 0}}, 5, &error));
  // Before: 1/1e-11 s overflowed the timer's duration: ~12,000 notifications/s.
  auto r = c->Call("subscribe", {{"rate", 1e-11}}, 5, &error);
  ASSERT_TRUE(r) << error;
  EXPECT_FALSE(c->NextNotification(0.5, &error));
  EXPECT_EQ(error, "timed out waiting for irslamd");
}

// Out of file descriptors. The UBSan runtime needs two free descriptors for its
// first vptr check of each (type, dynamic type) pair (a pipe(2) to probe that the
// vtable is readable: sanitizer_common's IsAccessibleMemoryRange); without them
// it reports "invalid vptr" for a valid object. Accept fails only when no
// descriptor at all is free, so the runtime cannot be left any: instead, what
// runs while the process is out of descriptors (a session, a request, a reply, a
// timer expiry) runs once before with descriptors, and the sanitizer's checks
// of those types are cached. The back-off itself allocates no new object.
class ApiServerFdTest : public ApiServerTest {
 protected:
  // Makes every descriptor the process may open taken, until Restore().
  void Exhaust() {
    ASSERT_EQ(::getrlimit(RLIMIT_NOFILE, &saved_), 0);
    exhausted_ = true;
    const int probe = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
    ASSERT_GE(probe, 0);
    ::close(probe);
    rlimit low = saved_;
    low.rlim_cur = static_cast<rlim_t>(probe + 8);
    ASSERT_EQ(::setrlimit(RLIMIT_NOFILE, &low), 0);
    for (int fd; (fd = ::open("/dev/null", O_RDONLY | O_CLOEXEC)) >= 0;) fill_.push_back(fd);
    ASSERT_EQ(errno, EMFILE);
  }
  void Restore() {
    if (!exhausted_) return;
    exhausted_ = false;
    for (int fd : fill_) ::close(fd);
    fill_.clear();
    ::setrlimit(RLIMIT_NOFILE, &saved_);
  }
  void TearDown() override {
    Restore();
    ApiServerTest::TearDown();
  }
  // A client, a request answered, a subscription's timer expiring: the code
  // paths (and types) used later while out of descriptors, run once with them.
  std::unique_ptr<RpcClient> WarmClient() {
    auto c = Client();
    std::string error;
    EXPECT_TRUE(c->Call("subscribe", {{"rate", 50}}, 5, &error)) << error;
    EXPECT_TRUE(c->NextNotification(5, &error)) << error;
    EXPECT_TRUE(c->Call("status", nlohmann::json::object(), 5, &error)) << error;
    return c;
  }
  // Connects a client that the server cannot accept (a descriptor is made first).
  int ConnectLater() {
    const int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
    EXPECT_GE(fd, 0);
    return fd;
  }
  void Connect(int fd) {
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::memcpy(addr.sun_path, path_.c_str(), path_.size() + 1);
    ASSERT_EQ(::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
  }
  // Bounded wait (5 s) for the API thread's first failed accept.
  bool FirstBackoff() {
    for (int i = 0; i < 500 && server_->stats().accept_backoffs == 0; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    return server_->stats().accept_backoffs > 0;
  }

  rlimit saved_{};
  bool exhausted_ = false;
  std::vector<int> fill_;
};

TEST_F(ApiServerFdTest, OutOfFileDescriptorsTheAcceptLoopBacksOffInsteadOfSpinning) {
  // Counted, not timed: with a back-off longer than the test, a failed accept is
  // not tried again, however much else the API thread does meanwhile. Before,
  // it was retried at once, over and over (a core spun).
  ApiLimits limits;
  limits.accept_backoff_s = 3600;
  StartServer(limits);
  auto warm = WarmClient();
  const int waiting = ConnectLater();
  Exhaust();
  Connect(waiting);
  const bool backed_off = FirstBackoff();
  // The API thread goes on serving the clients it has: a few rounds of its loop.
  std::string error;
  int answered = 0;
  for (int i = 0; i < 5; ++i) {
    if (warm->Call("status", nlohmann::json::object(), 5, &error)) ++answered;
  }
  const ApiStats stats = server_->stats();
  Restore();
  ::close(waiting);
  EXPECT_TRUE(backed_off);
  EXPECT_EQ(answered, 5) << error;
  EXPECT_EQ(stats.accept_backoffs, 1u);
  EXPECT_EQ(stats.accepted, 1u);  // the warm client only
}

TEST_F(ApiServerFdTest, OutOfFileDescriptorsAWaitingClientIsServedOnceThereAreSomeAgain) {
  ApiLimits limits;
  limits.accept_backoff_s = 0.01;
  StartServer(limits);
  auto warm = WarmClient();
  const int client = ConnectLater();
  Exhaust();
  Connect(client);
  const bool backed_off = FirstBackoff();
  Restore();
  EXPECT_TRUE(backed_off);
  // With descriptors back, the waiting client is served.
  const std::string req = R"({"jsonrpc":"2.0","id":1,"method":"status"})" "\n";
  ASSERT_EQ(::send(client, req.data(), req.size(), MSG_NOSIGNAL), static_cast<ssize_t>(req.size()));
  pollfd p{client, POLLIN, 0};
  ASSERT_EQ(::poll(&p, 1, 5000), 1);
  char buf[512];
  const ssize_t n = ::recv(client, buf, sizeof buf, 0);
  ::close(client);
  ASSERT_GT(n, 0);
  EXPECT_NE(std::string(buf, static_cast<size_t>(n)).find("idle"), std::string::npos);
  EXPECT_EQ(server_->stats().accepted, 2u);
}

TEST_F(ApiServerTest, GroupsComeFromTheKernelNotFromEtcGroup) {
  // Before: /etc/group's view of the user, so a process holding the control
  // group only as a supplementary group (setgroups, sg, SupplementaryGroups=) was refused.
  if (::getuid() != 0) GTEST_SKIP() << "needs root to act as another user";
  StartServer({});
  ::chmod(path_.c_str(), 0666);
  ::chmod(path_.substr(0, path_.rfind('/')).c_str(), 0755);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::memcpy(addr.sun_path, path_.c_str(), path_.size() + 1);
  const std::string req = R"({"jsonrpc":"2.0","id":1,"method":"status"})" "\n";
  const pid_t child = ::fork();
  if (child == 0) {  // only async-signal-safe calls here
    const gid_t extra[] = {4242};
    if (::setgroups(1, extra) != 0 || ::setgid(65534) != 0 || ::setuid(65534) != 0) ::_exit(2);
    const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
    if (::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) ::_exit(3);
    if (::write(fd, req.data(), req.size()) != static_cast<ssize_t>(req.size())) ::_exit(4);
    char buf[256];
    ::_exit(::read(fd, buf, sizeof buf) > 0 ? 0 : 5);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status;
  std::vector<gid_t> groups;
  OnControl([&] { groups = dispatcher_.last_groups; });
  EXPECT_EQ(dispatcher_.last_uid, 65534u);
  EXPECT_NE(std::find(groups.begin(), groups.end(), 4242u), groups.end());
  EXPECT_NE(std::find(groups.begin(), groups.end(), 65534u), groups.end());
  EXPECT_EQ(groups.size(), 2u);
}

TEST_F(ApiServerTest, RefusesToReplaceAFileThatIsNotASocket) {
  // Before: --socket PATH unlinked whatever file was at PATH.
  path_ = testing::MakeTempDir() + "/precious.txt";
  {
    FILE* f = std::fopen(path_.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fputs("keep me\n", f);
    std::fclose(f);
  }
  ApiServer server(io_, path_, {}, &dispatcher_);
  std::string error;
  EXPECT_FALSE(server.Listen(&error));
  EXPECT_EQ(error, "api: " + path_ + " exists and is not a socket: refusing to replace it");
  EXPECT_EQ(testing::ReadFile(path_), "keep me\n");
}

TEST_F(ApiServerTest, LimitsBeyondTheirBoundsAreAOneLineError) {
  path_ = testing::MakeTempDir() + "/api.sock";
  ApiLimits big_line;
  big_line.max_line_bytes = 16 << 20;
  std::string error;
  EXPECT_FALSE(ApiServer(io_, path_, big_line, &dispatcher_).Listen(&error));
  EXPECT_EQ(error, "api: max_line_bytes 16777216 is outside 1..1048576");
  ApiLimits many;
  many.max_clients = MaxClientsForFdLimit() + 1;
  EXPECT_FALSE(ApiServer(io_, path_, many, &dispatcher_).Listen(&error));
  EXPECT_NE(error.find("RLIMIT_NOFILE"), std::string::npos) << error;
}

TEST_F(ApiServerTest, AGroupTheSocketCannotBeGivenToIsAOneLineError) {
  if (::getuid() == 0) GTEST_SKIP() << "root may give the socket to any group";
  path_ = testing::MakeTempDir() + "/api.sock";
  ApiServer server(io_, path_, {}, &dispatcher_);
  std::string error;
  EXPECT_FALSE(server.Listen(&error, gid_t{0}));
  EXPECT_NE(error.find("cannot give"), std::string::npos) << error;
}

TEST(RpcClientTest, ConnectGivesUpOnADaemonThatNeverAccepts) {
  // Before: connect() blocked for good once the hung daemon's backlog was full.
  const std::string path = testing::MakeTempDir() + "/hung.sock";
  const int listener = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::memcpy(addr.sun_path, path.c_str(), path.size() + 1);
  ASSERT_EQ(::bind(listener, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
  ASSERT_EQ(::listen(listener, 0), 0);
  std::vector<int> queued;  // fill the backlog
  for (int i = 0; i < 16; ++i) {
    const int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
    if (::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
      ::close(fd);
      break;
    }
    queued.push_back(fd);
  }
  auto result = std::async(std::launch::async, [&] {
    RpcClient c;
    std::string error;
    const bool ok = c.Connect(path, &error, 0.3);
    return std::make_pair(ok, error);
  });
  const bool finished = result.wait_for(std::chrono::seconds(3)) == std::future_status::ready;
  ::close(listener);  // unblocks an old-style blocking connect
  for (int fd : queued) ::close(fd);
  ASSERT_TRUE(finished) << "Connect blocked";
  const auto r = result.get();
  EXPECT_FALSE(r.first);
  EXPECT_EQ(r.second, "cannot reach irslamd at " + path + ": timed out after 0.3 s (its backlog is full)");
}

TEST_F(ApiServerTest, SubscriberThatNeverReadsIsDroppedAndOthersKeepGoing) {
  ApiLimits limits;
  limits.max_pending_bytes = 64 * 1024;
  limits.max_rate_hz = 200;
  dispatcher_.blob = std::string(100 * 1024, 'b');
  StartServer(limits);
  auto slow = Client();
  std::string error;
  ASSERT_TRUE(slow->SendRaw(R"({"jsonrpc":"2.0","id":1,"method":"subscribe","params":{"rate":200}})" "\n", &error));
  auto other = Client();
  // The slow client's socket buffer fills, its queue passes the limit: dropped.
  for (int i = 0; i < 300 && server_->stats().dropped_slow == 0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(server_->stats().dropped_slow, 1u);
  EXPECT_TRUE(other->Call("status", nlohmann::json::object(), 5, &error)) << error;
}

TEST_F(ApiServerTest, SubscriptionDeliversNotificationsAtTheRate) {
  StartServer({});
  auto c = Client();
  std::string error;
  auto r = c->Call("subscribe", {{"rate", 20}}, 5, &error);
  ASSERT_TRUE(r) << error;
  EXPECT_EQ((*r)["rate"], 20);
  for (int i = 0; i < 3; ++i) {
    auto n = c->NextNotification(2, &error);
    ASSERT_TRUE(n) << error;
    EXPECT_EQ((*n)["state"], "idle");
  }
  EXPECT_FALSE(c->Call("subscribe", {{"rate", -1}}, 5, &error));
  EXPECT_NE(error.find("rate must be > 0"), std::string::npos);
  EXPECT_EQ(server_->stats().errors, 1u);
}

TEST_F(ApiServerTest, IdleClientsAreClosed) {
  ApiLimits limits;
  limits.idle_timeout_s = 0.2;
  StartServer(limits);
  auto c = Client();
  std::string error;
  EXPECT_FALSE(c->ReadLine(3, &error));
  EXPECT_EQ(error, "irslamd closed the connection");
}

TEST_F(ApiServerTest, RefusesToDisplaceALiveServer) {
  StartServer({});
  boost::asio::io_context io2;
  ApiServer second(io2, path_, {}, &dispatcher_);
  std::string error;
  EXPECT_FALSE(second.Listen(&error));
  EXPECT_NE(error.find("already listening"), std::string::npos);
}

}  // namespace
}  // namespace irslam
