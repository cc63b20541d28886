#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <boost/asio/io_context.hpp>
#include <ctime>
#include <filesystem>
#include <thread>

#include "drivers/can_bus.h"
#include "proto/codec.h"
#include "tests/testing/process.h"

namespace irslam::drivers {
namespace {

struct Node {
  std::unique_ptr<CanBus> bus;
  std::vector<can_frame> got;
};

class LoopbackBusTest : public ::testing::Test {
 protected:
  void SetUp() override { dir_ = testing::MakeTempDir() + "/bus"; }
  void TearDown() override { std::filesystem::remove_all(std::filesystem::path(dir_).parent_path()); }

  std::unique_ptr<Node> Join(std::vector<uint32_t> ids = {}) {
    auto n = std::make_unique<Node>();
    std::string error;
    n->bus = OpenCanBus(io_, {"unix:" + dir_, std::move(ids)}, &error);
    EXPECT_NE(n->bus, nullptr) << error;
    Node* raw = n.get();
    n->bus->Start([raw](const can_frame& f, double) { raw->got.push_back(f); });
    return n;
  }
  void Pump() {
    io_.restart();
    io_.run_for(std::chrono::milliseconds(50));
  }
  static can_frame Frame(uint32_t id, uint8_t b) {
    can_frame f{};
    f.can_id = id;
    f.can_dlc = 1;
    f.data[0] = b;
    return f;
  }

  boost::asio::io_context io_;
  std::string dir_;
};

// A polled node (the daemon drains the bus once per period): nothing is
// delivered until Poll(), which hands over every frame received so far, in
// order, each with its kernel receive time (not the time of the poll).
TEST_F(LoopbackBusTest, APolledNodeGetsEverythingAtPollWithEachFramesReceiveTime) {
  auto a = Join();
  std::string error;
  auto polled = OpenCanBus(io_, {"unix:" + dir_, {}}, &error);
  ASSERT_NE(polled, nullptr) << error;
  std::vector<std::pair<can_frame, double>> got;
  polled->StartPolled([&](const can_frame& f, double rx) { got.push_back({f, rx}); });
  const auto realtime = [] {
    timespec ts;
    ::clock_gettime(CLOCK_REALTIME, &ts);
    return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
  };
  const double t0 = realtime();
  ASSERT_TRUE(a->bus->Send(Frame(0x100, 1)));
  Pump();  // a's flush runs on the io_context; the polled node does not read
  std::this_thread::sleep_for(std::chrono::milliseconds(30));
  const double t1 = realtime();
  ASSERT_TRUE(a->bus->Send(Frame(0x101, 2)));
  Pump();
  EXPECT_TRUE(got.empty());
  std::this_thread::sleep_for(std::chrono::milliseconds(30));
  const double t_poll = realtime();
  polled->Poll();
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].first.data[0], 1);
  EXPECT_EQ(got[1].first.data[0], 2);
  // Received when sent, not when polled: the first ~60 ms before the poll.
  EXPECT_GE(got[0].second, t0);
  EXPECT_LT(got[0].second, t1);
  EXPECT_GE(got[1].second, t1);
  EXPECT_LT(got[1].second, t_poll - 0.02);
  EXPECT_TRUE(polled->stats().kernel_timestamps);
  polled->Poll();  // nothing new
  EXPECT_EQ(got.size(), 2u);
}

// A polled node drains in bursts of 8 datagrams (recvmmsg): 10 datagrams (the
// kernel's default net.unix.max_dgram_qlen), waiting since the last period, all
// come at one Poll, in order.
// SendNow sends at once, behind what Send queued earlier in the same turn.
TEST_F(LoopbackBusTest, APollDrainsMoreDatagramsThanOneBurstAndSendNowKeepsTheOrder) {
  auto a = Join();
  std::string error;
  auto polled = OpenCanBus(io_, {"unix:" + dir_, {}}, &error);
  ASSERT_NE(polled, nullptr) << error;
  std::vector<can_frame> got;
  polled->StartPolled([&](const can_frame& f, double) { got.push_back(f); });
  for (uint8_t i = 0; i < 10; ++i) {
    ASSERT_TRUE(a->bus->Send(Frame(0x100, i)));
    Pump();  // each turn's frames: one datagram
  }
  polled->Poll();
  ASSERT_EQ(got.size(), 10u);
  for (uint8_t i = 0; i < 10; ++i) EXPECT_EQ(got[i].data[0], i);
  got.clear();
  ASSERT_TRUE(a->bus->Send(Frame(0x100, 40)));  // queued for the turn's flush
  ASSERT_TRUE(a->bus->SendNow({Frame(0x101, 41), Frame(0x102, 42)}));
  polled->Poll();  // already there: SendNow did not wait for a turn of the loop
  ASSERT_EQ(got.size(), 3u);
  EXPECT_EQ(got[0].data[0], 40);
  EXPECT_EQ(got[1].data[0], 41);
  EXPECT_EQ(got[2].data[0], 42);
  Pump();  // the posted flush finds nothing left to send
  polled->Poll();
  EXPECT_EQ(got.size(), 3u);
  EXPECT_EQ(a->bus->stats().tx_frames, 13u);
}

TEST_F(LoopbackBusTest, EveryFrameReachesEveryOtherNodeOfThree) {
  auto a = Join(), b = Join(), c = Join();
  ASSERT_TRUE(a->bus->Send(Frame(0x100, 1)));
  ASSERT_TRUE(b->bus->Send(Frame(0x101, 2)));
  ASSERT_TRUE(c->bus->Send(Frame(0x102, 3)));
  Pump();
  ASSERT_EQ(a->got.size(), 2u);
  ASSERT_EQ(b->got.size(), 2u);
  ASSERT_EQ(c->got.size(), 2u);
  // A node never hears itself (vcan without CAN_RAW_RECV_OWN_MSGS).
  for (const auto& f : a->got) EXPECT_NE(f.can_id, 0x100u);
  for (const auto& f : b->got) EXPECT_NE(f.can_id, 0x101u);
  EXPECT_EQ(c->got[0].can_id, 0x100u);
  EXPECT_EQ(c->got[1].data[0], 2);
  EXPECT_EQ(a->bus->stats().tx_frames, 1u);
  EXPECT_EQ(c->bus->stats().rx_frames, 2u);
}

TEST_F(LoopbackBusTest, ASlowNodeGetsEveryFrameInOrderWhenItCatchesUp) {
  // The receiver runs on its own io_context that is not run for a while: its
  // socket queue (net.unix.max_dgram_qlen datagrams) fills; the sender holds the
  // rest, like a vcan socket's receive buffer, and delivers it in order later.
  boost::asio::io_context slow_io;
  std::string error;
  auto slow = OpenCanBus(slow_io, {"unix:" + dir_, {}}, &error);
  ASSERT_NE(slow, nullptr) << error;
  std::vector<can_frame> got;
  slow->Start([&](const can_frame& f, double) { got.push_back(f); });
  auto fast = Join();
  for (int i = 0; i < 60; ++i) {  // 60 loop turns: 60 datagrams
    fast->bus->Send(Frame(0x100, static_cast<uint8_t>(i)));
    io_.restart();
    io_.poll();
  }
  EXPECT_EQ(got.size(), 0u);
  for (int i = 0; i < 50 && got.size() < 60; ++i) {
    slow_io.restart();
    slow_io.run_for(std::chrono::milliseconds(5));
    io_.restart();
    io_.run_for(std::chrono::milliseconds(5));
  }
  ASSERT_EQ(got.size(), 60u);
  for (int i = 0; i < 60; ++i) EXPECT_EQ(got[static_cast<size_t>(i)].data[0], i);
  EXPECT_EQ(fast->bus->stats().tx_dropped, 0u);
}

TEST_F(LoopbackBusTest, NodesJoinAndLeaveAtAnyTime) {
  auto a = Join(), b = Join();
  a->bus->Send(Frame(0x100, 1));
  Pump();
  auto late = Join();  // joins after the first frame: hears the next one at once
  a->bus->Send(Frame(0x100, 2));
  Pump();
  EXPECT_EQ(b->got.size(), 2u);
  ASSERT_EQ(late->got.size(), 1u);
  EXPECT_EQ(late->got[0].data[0], 2);
  b->bus->Close();  // leaves
  EXPECT_TRUE(a->bus->Send(Frame(0x100, 3)));
  Pump();
  EXPECT_EQ(late->got.size(), 2u);
  EXPECT_EQ(b->got.size(), 2u);
}

TEST_F(LoopbackBusTest, StaleSocketOfADeadNodeIsRemoved) {
  auto a = Join(), b = Join();
  // A node that died without cleaning up: its socket file stays, nobody listens.
  const std::string stale = dir_ + "/node-999999-3";
  const int fd = ::socket(AF_UNIX, SOCK_DGRAM, 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::snprintf(addr.sun_path, sizeof addr.sun_path, "%s", stale.c_str());
  ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
  ::close(fd);
  ASSERT_TRUE(std::filesystem::exists(stale));
  EXPECT_TRUE(a->bus->Send(Frame(0x100, 1)));
  Pump();
  EXPECT_FALSE(std::filesystem::exists(stale));
  EXPECT_EQ(b->got.size(), 1u);
}

TEST_F(LoopbackBusTest, IdFilterDropsForeignIds) {
  auto a = Join(), b = Join({proto::kEncoderId});
  a->bus->Send(Frame(proto::kEncoderId, 1));
  a->bus->Send(Frame(0x555, 2));
  a->bus->Send(Frame(proto::kEncoderId | CAN_EFF_FLAG, 3));
  Pump();
  ASSERT_EQ(b->got.size(), 1u);
  EXPECT_EQ(b->got[0].data[0], 1);
  EXPECT_EQ(b->bus->stats().filtered, 2u);
}

TEST_F(LoopbackBusTest, DatagramsThatAreNotFramesAreCountedAndDropped) {
  auto a = Join(), b = Join();
  const int fd = ::socket(AF_UNIX, SOCK_DGRAM, 0);
  for (const auto& e : std::filesystem::directory_iterator(dir_)) {
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::snprintf(addr.sun_path, sizeof addr.sun_path, "%s", e.path().c_str());
    ::sendto(fd, "garbage", 7, 0, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
  }
  ::close(fd);
  Pump();
  EXPECT_TRUE(a->got.empty());
  EXPECT_TRUE(b->got.empty());
  EXPECT_EQ(a->bus->stats().rx_dropped, 1u);
  EXPECT_EQ(b->bus->stats().rx_dropped, 1u);
}

TEST(SocketCanBusTest, ExplainsWhyItCannotOpen) {
  boost::asio::io_context io;
  std::string error;
  auto bus = OpenCanBus(io, {"irslamnope0", {}}, &error);
  ASSERT_EQ(bus, nullptr);
  // On a kernel without CAN: a clear word about it; with CAN: the missing interface.
  const bool no_can = error.find("no CAN support") != std::string::npos;
  const bool no_iface = error.find("no such interface 'irslamnope0'") != std::string::npos;
  EXPECT_TRUE(no_can || no_iface) << error;
  error.clear();
  EXPECT_EQ(OpenCanBus(io, {"a_name_longer_than_ifnamsiz", {}}, &error), nullptr);
  EXPECT_NE(error.find("longer than 15"), std::string::npos) << error;
}

}  // namespace
}  // namespace irslam::drivers
