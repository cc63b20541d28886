// The daemon's logic without spawning it: a Daemon on a loopback bus in a temp
// directory, driven by Tick() under a fake clock; its notifier, method table,
// reload and the second-commander check.
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <boost/asio/io_context.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>
#include <type_traits>

#include "daemon/irslamd.h"
#include "proto/codec.h"
#include "tests/testing/process.h"

namespace irslam {
namespace {

using std::chrono::milliseconds;

// A bound datagram socket standing in for systemd's notify socket.
class NotifySink {
 public:
  explicit NotifySink(const std::string& path, bool abstract = false) {
    fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::memcpy(addr.sun_path, path.data(), path.size());
    if (abstract) addr.sun_path[0] = '\0';
    const auto len = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + path.size());
    EXPECT_EQ(::bind(fd_, reinterpret_cast<sockaddr*>(&addr), len), 0) << path;
  }
  ~NotifySink() { ::close(fd_); }
  std::vector<std::string> Drain() {
    std::vector<std::string> out;
    char buf[512];
    ssize_t n;
    while ((n = ::recv(fd_, buf, sizeof buf, 0)) > 0) out.emplace_back(buf, static_cast<size_t>(n));
    return out;
  }

 private:
  int fd_ = -1;
};

int OpenFds() {
  int n = 0;
  for ([[maybe_unused]] const auto& e : std::filesystem::directory_iterator("/proc/self/fd")) ++n;
  return n;
}

class DaemonTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing::MakeTempDir();
    options_.can_iface = "unix:" + dir_ + "/bus";
    options_.socket_path = dir_ + "/irslamd.sock";
    settings_.state_dir = dir_ + "/state";
  }
  void TearDown() override {
    daemon_.reset();
    std::filesystem::remove_all(dir_);
  }
  void Open() {
    daemon_ = std::make_unique<Daemon>(io_, options_, settings_, [this] { return now_; });
    std::string error;
    ASSERT_TRUE(daemon_->Open(&error)) << error;
  }
  // Advances the fake clock and runs one control period.
  void TickAfter(milliseconds dt) {
    now_ += dt;
    daemon_->Tick();
  }
  // Lets the io_context deliver what arrived (the loopback bus is a real socket).
  void Pump() {
    for (int i = 0; i < 20; ++i) {
      io_.poll();
      io_.restart();
      std::this_thread::sleep_for(milliseconds(5));
    }
  }
  nlohmann::json Call(const std::string& method, nlohmann::json params = nlohmann::json::object()) {
    rpc::Request r;
    r.id = 1;
    r.method = method;
    r.params = std::move(params);
    PeerCred self;
    self.uid = ::getuid();
    self.gid = ::getgid();
    self.groups = {::getgid()};
    nlohmann::json reply;
    daemon_->Handle(r, self, [&reply](nlohmann::json j) { reply = std::move(j); });
    // A stop's reply waits for the map writer thread's outcome, posted onto io_.
    // io_ has work only while the write is in flight (the bus is drained by
    // Tick, no period timer is armed here), so it may have stopped since, and a
    // stopped io_context runs nothing until restarted.
    while (reply.is_null()) {
      io_.restart();
      if (io_.run_one() == 0) {
        ADD_FAILURE() << "no reply, and nothing left on io_ that could give one";
        break;
      }
    }
    return reply;
  }

  std::string dir_;
  DaemonOptions options_;
  DaemonSettings settings_;  // built-in defaults
  WallTime now_ = WallTime(std::chrono::hours(100));
  boost::asio::io_context io_;
  std::unique_ptr<Daemon> daemon_;
};

TEST_F(DaemonTest, WatchdogPingsEveryHalfIntervalOfTheInjectedClock) {
  NotifySink sink(dir_ + "/notify");
  options_.notify_socket = dir_ + "/notify";
  options_.watchdog_usec = 200000;  // a ping due every 100 ms
  Open();
  // 40 periods of 30 ms: a ping at the first, then at the first period at least
  // 100 ms after the last one, i.e. every 4th (120 ms): 0.03, 0.15, ..., 1.11 s.
  int pings = 0;
  std::vector<int> at;
  for (int i = 1; i <= 40; ++i) {
    TickAfter(milliseconds(30));
    for (const auto& m : sink.Drain()) {
      if (m == "WATCHDOG=1") {
        ++pings;
        at.push_back(i);
      }
    }
  }
  EXPECT_EQ(pings, 10);
  ASSERT_FALSE(at.empty());
  EXPECT_EQ(at.front(), 1);
  for (size_t k = 1; k < at.size(); ++k) EXPECT_EQ(at[k] - at[k - 1], 4) << k;
  // A loop that does not tick sends nothing, however much time passes.
  now_ += std::chrono::seconds(10);
  EXPECT_TRUE(sink.Drain().empty());
  EXPECT_EQ(daemon_->StatusJson()["notify_dropped"], 0);
  EXPECT_EQ(daemon_->StatusJson()["period"]["ticks"], 40);
}

TEST_F(DaemonTest, NoWatchdogNoPings) {
  NotifySink sink(dir_ + "/notify");
  options_.notify_socket = dir_ + "/notify";
  Open();
  for (int i = 0; i < 50; ++i) TickAfter(milliseconds(20));
  EXPECT_TRUE(sink.Drain().empty());
}

TEST(SdNotifierTest, SendsToAbstractAddressesCountsDropsAndClosesItsSocket) {
  const std::string name = "@irslam-notify-test-" + std::to_string(::getpid());
  NotifySink sink(name, /*abstract=*/true);
  const int before = OpenFds();
  {
    SdNotifier n(name);
    EXPECT_TRUE(n.enabled());
    EXPECT_TRUE(n.Send("READY=1"));
    EXPECT_EQ(sink.Drain(), std::vector<std::string>{"READY=1"});
    EXPECT_EQ(OpenFds(), before + 1);
    SdNotifier moved(std::move(n));
    EXPECT_FALSE(n.enabled());  // NOLINT(bugprone-use-after-move): the moved-from one is off
    EXPECT_FALSE(n.Send("X=1"));
    EXPECT_TRUE(moved.Send("WATCHDOG=1"));
    EXPECT_EQ(OpenFds(), before + 1);  // the fd moved, not duplicated
  }
  EXPECT_EQ(OpenFds(), before);  // closed by the destructor
  SdNotifier nobody("@irslam-nobody-listens-" + std::to_string(::getpid()));
  EXPECT_FALSE(nobody.Send("WATCHDOG=1"));
  EXPECT_FALSE(nobody.Send("WATCHDOG=1"));
  EXPECT_EQ(nobody.dropped(), 2u);
  EXPECT_FALSE(SdNotifier("").enabled());
  EXPECT_FALSE(SdNotifier("relative/path").enabled());
  static_assert(!std::is_copy_constructible_v<SdNotifier> && std::is_move_constructible_v<SdNotifier>);
}

TEST_F(DaemonTest, MethodTableHoldsTheAccessRuleOfEveryMethod) {
  Open();
  std::map<std::string, Access> rules;
  for (const auto& m : daemon_->methods().methods()) rules[m.name] = m.access;
  const std::map<std::string, Access> expected = {{"status", Access::kRead},    {"map", Access::kRead},
                                                  {"subscribe", Access::kRead}, {"start", Access::kControl},
                                                  {"stop", Access::kControl},   {"clean", Access::kControl}};
  EXPECT_EQ(rules, expected);
  EXPECT_EQ(daemon_->methods().Needs("no-such-method"), Access::kRead);
  // A stranger (uid 4242, in group 777 = the read group only).
  AccessPolicy policy;
  policy.daemon_uid = 1000;
  policy.read_gid = 777;
  policy.control_gid = 778;
  PeerCred reader;
  reader.uid = 4242;
  reader.gid = 777;
  reader.groups = {777};
  const auto call = [&](const std::string& method, const PeerCred& peer) {
    rpc::Request r;
    r.id = 7;
    r.method = method;
    return daemon_->methods().Handle(r, peer, policy);
  };
  EXPECT_TRUE(call("status", reader).contains("result"));
  EXPECT_TRUE(call("map", reader).contains("result"));
  for (const char* m : {"start", "stop", "clean"}) {
    const auto reply = call(m, reader);
    ASSERT_TRUE(reply.contains("error")) << m;
    EXPECT_EQ(reply["error"]["code"], rpc::kAccessDenied);
    EXPECT_EQ(reply["error"]["message"], std::string("access denied: ") + m + " needs the control group");
  }
  PeerCred nobody;
  nobody.uid = 4243;
  nobody.gid = 999;
  nobody.groups = {999};
  EXPECT_EQ(call("status", nobody)["error"]["code"], rpc::kAccessDenied);
  EXPECT_EQ(call("no-such-method", nobody)["error"]["code"], rpc::kAccessDenied);
  EXPECT_EQ(call("no-such-method", reader)["error"]["code"], rpc::kMethodNotFound);
  EXPECT_EQ(call("subscribe", reader)["error"]["code"], rpc::kMethodNotFound);  // the server's own
  // A denied name is logged escaped: no forged line.
  ::testing::internal::CaptureStderr();
  call("x\n<0>irslamd: forged", nobody);
  const std::string log = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(std::count(log.begin(), log.end(), '\n'), 1) << log;
  EXPECT_NE(log.find("method=x\\x0a<0>irslamd: forged uid=4243"), std::string::npos) << log;
}

TEST_F(DaemonTest, StatusHasTheDaemonsPartsAndStopWithoutAMissionSavesNothing) {
  Open();
  for (int i = 0; i < 5; ++i) TickAfter(milliseconds(20));
  const auto s = daemon_->StatusJson();
  EXPECT_EQ(s["state"], "idle");
  EXPECT_DOUBLE_EQ(s["uptime"].get<double>(), 0.1);
  EXPECT_EQ(s["period"]["ticks"], 5);
  EXPECT_EQ(s["can"]["iface"], options_.can_iface);
  EXPECT_EQ(s["can"]["foreign_commander"], false);
  EXPECT_EQ(s["map_store"]["saved_map"], false);
  const auto stop = Call("stop");
  ASSERT_TRUE(stop.contains("result")) << stop;
  EXPECT_EQ(stop["result"]["state"], "idle");
  EXPECT_EQ(stop["result"]["map"], "nothing");
  EXPECT_FALSE(std::filesystem::exists(settings_.state_dir + "/map.json"));
}

// Issue 12: two daemons on one bus both commanded the wheels, unnoticed.
TEST_F(DaemonTest, ASecondCommanderOnTheBusFaultsTheMission) {
  Open();
  std::string error;
  boost::asio::io_context other_io;
  auto other = drivers::OpenCanBus(other_io, {options_.can_iface, {}}, &error);
  ASSERT_TRUE(other) << error;
  std::vector<can_frame> heard;
  other->Start([&](const can_frame& f, double) { heard.push_back(f); });
  // Our own commands and heartbeats reach the other node, never ourselves.
  for (int i = 0; i < 10; ++i) TickAfter(milliseconds(20));
  Pump();
  for (int i = 0; i < 20; ++i) {
    other_io.poll();
    other_io.restart();
  }
  EXPECT_GE(heard.size(), 10u);
  EXPECT_EQ(daemon_->StatusJson()["can"]["foreign_commander_frames"], 0);
  // Someone else's wheel command.
  proto::WheelCmd cmd;
  cmd.left_mps = cmd.right_mps = 0.2;
  cmd.enable = true;
  cmd.seq = 1;
  other->Send(proto::Encode(cmd));
  other_io.poll();
  other_io.restart();
  Pump();
  // The bus is drained at the start of each period: seen at the next tick.
  EXPECT_EQ(daemon_->StatusJson()["can"]["foreign_commander_frames"], 0);
  TickAfter(milliseconds(20));
  auto s = daemon_->StatusJson();
  EXPECT_EQ(s["can"]["foreign_commander"], true);
  EXPECT_EQ(s["can"]["foreign_commander_frames"], 1);
  EXPECT_DOUBLE_EQ(s["can"]["foreign_commander_last"].get<double>(), 0.22);
  EXPECT_EQ(s["state"], "fault");
  EXPECT_EQ(s["reason"], "another controller client on the bus");
  const auto start = Call("start");
  ASSERT_TRUE(start.contains("error")) << start;
  EXPECT_EQ(start["error"]["message"], "start rejected: another controller client on the bus");
  // A heartbeat of another daemon counts too; 2 s after the last one it is gone.
  other->Send(proto::Encode(proto::DaemonHeartbeat{2, 5}));
  other_io.poll();
  Pump();
  TickAfter(milliseconds(20));
  s = daemon_->StatusJson();
  EXPECT_EQ(s["can"]["foreign_commander_frames"], 2);
  now_ += std::chrono::milliseconds(2100);
  s = daemon_->StatusJson();
  EXPECT_EQ(s["can"]["foreign_commander"], false);
  EXPECT_EQ(s["state"], "fault");  // latched until start
  const auto again = Call("start");
  ASSERT_TRUE(again.contains("error"));
  EXPECT_EQ(again["error"]["message"].get<std::string>().rfind("start rejected: controller not reachable", 0), 0u)
      << again;
}

// Issue 13 (contracts §7): start's optional params are checked before anything else.
TEST_F(DaemonTest, StartRejectsABadModeOrUnknownParams) {
  Open();
  const auto bad_mode = Call("start", {{"mode", "mop"}});
  ASSERT_TRUE(bad_mode.contains("error")) << bad_mode;
  EXPECT_EQ(bad_mode["error"]["code"], rpc::kInvalidParams);
  const auto bad_fresh = Call("start", {{"fresh", "yes"}});
  ASSERT_TRUE(bad_fresh.contains("error")) << bad_fresh;
  EXPECT_EQ(bad_fresh["error"]["code"], rpc::kInvalidParams);
  const auto unknown = Call("start", {{"speed", 2}});
  ASSERT_TRUE(unknown.contains("error")) << unknown;
  EXPECT_EQ(unknown["error"]["code"], rpc::kInvalidParams);
  // Good params get as far as the controller check (none is on this bus).
  for (const char* m : {"start", "clean"}) {
    const auto r = Call(m, std::string(m) == "start" ? nlohmann::json{{"mode", "clean"}, {"fresh", true}}
                                                     : nlohmann::json::object());
    ASSERT_TRUE(r.contains("error")) << r;
    EXPECT_EQ(r["error"]["code"], rpc::kRejected) << r;
  }
}

// Issue 12 B5: a bad config on SIGHUP changes nothing and says so in one line.
TEST_F(DaemonTest, ABadReloadConfigLeavesTheRunningDaemonUntouched) {
  options_.config_path = dir_ + "/irslamd.conf";
  std::ofstream(options_.config_path) << R"({"control": {"period_s": 0.01}})";
  settings_.core.period_s = 0.01;
  Open();
  const auto check = [&](const std::string& what) {
    ::testing::internal::CaptureStderr();
    daemon_->Reload();
    const std::string log = ::testing::internal::GetCapturedStderr();
    EXPECT_EQ(std::count(log.begin(), log.end(), '\n'), 1) << what << ": " << log;
    EXPECT_EQ(log.rfind("<3>irslamd: reload failed, keeping the running config: ", 0), 0u) << what << ": " << log;
    const auto s = daemon_->StatusJson();
    EXPECT_DOUBLE_EQ(s["period"]["target"].get<double>(), 0.01) << what;
    EXPECT_EQ(s["config_pending"], false) << what;
  };
  std::ofstream(options_.config_path) << R"({"control": {"period_s": "fast"}})";
  check("wrong type");
  std::ofstream(options_.config_path) << std::string(200000, '[');
  check("nested 200000 deep");
  std::filesystem::remove(options_.config_path);
  ASSERT_EQ(::mkfifo(options_.config_path.c_str(), 0600), 0);
  check("a FIFO");
  std::filesystem::remove(options_.config_path);
  check("gone");
  // And a good one applies at once (idle, no mission's map to lose).
  std::ofstream(options_.config_path) << R"({"control": {"period_s": 0.02}})";
  daemon_->Reload();
  EXPECT_DOUBLE_EQ(daemon_->StatusJson()["period"]["target"].get<double>(), 0.02);
}

}  // namespace
}  // namespace irslam
