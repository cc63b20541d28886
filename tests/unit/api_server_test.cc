#include <gtest/gtest.h>

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
  nlohmann::json Handle(const rpc::Request& r, const PeerCred& peer) override {
    ++calls;
    last_uid = peer.uid;
    if (r.method == "status") return rpc::MakeResult(r.id, {{"state", "idle"}});
    return rpc::MakeError(r.id, rpc::kMethodNotFound, "method not found: " + r.method);
  }
  bool MaySubscribe(const PeerCred&) override { return true; }
  nlohmann::json StatusNotification() override { return {{"state", "idle"}, {"blob", blob}}; }
  std::atomic<int> calls{0};
  std::atomic<uid_t> last_uid{0};
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
  EXPECT_EQ(dispatcher_.calls, 2);
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

TEST_F(ApiServerTest, RefusesClientsBeyondTheLimit) {
  ApiLimits limits;
  limits.max_clients = 2;
  StartServer(limits);
  auto a = Client(), b = Client();
  std::string error;
  ASSERT_TRUE(a->Call("status", nlohmann::json::object(), 5, &error));
  ASSERT_TRUE(b->Call("status", nlohmann::json::object(), 5, &error));
  auto c = Client();
  auto e = Line(*c);
  EXPECT_EQ(e["error"]["message"], "too many clients");
  EXPECT_TRUE(a->Call("status", nlohmann::json::object(), 5, &error)) << error;
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
