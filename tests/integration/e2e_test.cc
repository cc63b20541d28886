// Integration tests with the real processes: irslam-sim serve + irslamd + irslamctl
// over the loopback bus (vcan0 when IRSLAM_TEST_CAN=vcan0), time-scaled.
#include <sched.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <boost/crc.hpp>
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <thread>

#include "daemon/rpc_client.h"
#include "proto/codec.h"
#include "io/json_text.h"
#include "tests/testing/bus_tap.h"
#include "tests/testing/dbc.h"
#include "tests/testing/process.h"

namespace irslam {
namespace {

using testing::Process;
using testing::RunCommand;
using Clock = std::chrono::steady_clock;

const std::string kBin = IRSLAM_BINARY_DIR;
const std::string kSrc = IRSLAM_SOURCE_DIR;
const std::string kSim = kBin + "/sim/irslam-sim";
const std::string kDaemon = kBin + "/daemon/irslamd";
const std::string kCtl = kBin + "/daemon/irslamctl";
// Robot time runs this much faster than wall time (IRSLAM_TEST_TIME_SCALE: lower
// it on slow hosts, e.g. a software-emulated VM).
const double kScale = [] {
  const char* e = std::getenv("IRSLAM_TEST_TIME_SCALE");
  return e && *e ? std::atof(e) : 10.0;
}();

// A wall-time limit that was chosen for 10x: scaled to the time scale in use.
double WallS(double seconds_at_10x) { return seconds_at_10x * 10.0 / kScale; }

void Sleep(double s) { std::this_thread::sleep_for(std::chrono::duration<double>(s)); }

// How a test starts the processes: the world, config keys over the test defaults,
// extra environment for the daemon, and whether to wait until it hears the controller.
struct StartOptions {
  std::string world = "wall_follow_fig14.json";
  nlohmann::json config = nlohmann::json::object();
  std::vector<std::string> daemon_env;
  std::vector<std::string> sim_args;  // e.g. {"--faults", "..."}
  std::vector<std::string> daemon_args;
  bool wait_for_controller = true;
};

class E2eTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing::MakeTempDir();
    const char* env = std::getenv("IRSLAM_TEST_CAN");
    bus_ = env && *env ? env : "unix:" + dir_ + "/bus";
    socket_ = dir_ + "/irslamd.sock";
  }
  void TearDown() override {
    if (HasFailure()) {
      std::fprintf(stderr, "--- sim log\n%s--- daemon log\n%s", testing::ReadFile(dir_ + "/sim.log").c_str(),
                   testing::ReadFile(dir_ + "/daemon.log").c_str());
    }
    daemon_.Signal(SIGKILL);
    sim_.Signal(SIGKILL);
    daemon_.Wait(5);
    sim_.Wait(5);
    std::filesystem::remove_all(dir_);
  }

  // The loopback bus (this host), not SocketCAN (a vcan interface in the VM).
  bool IsLoopback() const { return bus_.rfind("unix:", 0) == 0; }

  // A stand-in for systemd's notify socket at dir_/notify.sock: its path, and
  // the bound datagram socket (receives time out after timeout_s; 0: block).
  std::string BindNotifySocket(double timeout_s, int* fd) const {
    const std::string path = dir_ + "/notify.sock";
    *fd = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    std::snprintf(addr.sun_path, sizeof addr.sun_path, "%s", path.c_str());
    EXPECT_EQ(::bind(*fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0) << path;
    const long us = static_cast<long>(timeout_s * 1e6);
    timeval tv{us / 1000000, us % 1000000};
    if (us > 0) ::setsockopt(*fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
    return path;
  }

  // The daemon's config file in the test directory (tests may rewrite it for SIGHUP).
  std::string ConfigPath() const { return dir_ + "/irslamd.conf"; }
  // Where the daemon saves its map.
  std::string StateDir() const { return dir_ + "/state"; }

  // The test rig's config: the defaults, except that the controller-silence limit is
  // 300 ms of *wall* time (not robot time) at any time scale, so a loaded host (ASan,
  // ctest -j2) or the VM suite's software emulation does not see the simulator's
  // scheduling stalls as a lost controller (it was 100 ms until 2026-12-03: the VM
  // suite in CI and locally faulted "encoder frames timed out" on a 202 ms wall stall
  // of irslam-sim, 1 run in 5). The silence fault test silences it for 6 s.
  nlohmann::json TestConfig(const nlohmann::json& over) const {
    nlohmann::json c = {{"controller", {{"timeout_s", std::max(0.3, 0.3 * kScale)}}},
                        {"state", {{"dir", StateDir()}}}};
    c.merge_patch(over);
    return c;
  }

  void StartAll(const StartOptions& o = StartOptions()) {
    std::ofstream(ConfigPath()) << TestConfig(o.config).dump(2) << "\n";
    std::vector<std::string> sim = {kSim, "serve", "--can", bus_, "--world", kSrc + "/tests/worlds/" + o.world,
                                    "--time-scale", std::to_string(kScale), "--truth-out", dir_ + "/truth.json",
                                    "--realtime-priority", testing::kSimRealtimePriority};
    sim.insert(sim.end(), o.sim_args.begin(), o.sim_args.end());
    ASSERT_TRUE(sim_.Start(sim, dir_ + "/sim.log"));
    StartDaemon(o);
  }

  // (Re)starts the daemon alone, with the config StartAll wrote.
  void StartDaemon(const StartOptions& o = StartOptions()) {
    std::vector<std::string> args = {kDaemon, "--can", bus_, "--socket", socket_, "--time-scale",
                                     std::to_string(kScale), "--config", ConfigPath()};
    args.insert(args.end(), o.daemon_args.begin(), o.daemon_args.end());
    ASSERT_TRUE(daemon_.Start(args, dir_ + "/daemon.log", o.daemon_env));
    for (int i = 0; i < 400; ++i) {
      auto s = Status();
      // Ready when the daemon answers (and, if asked, hears the controller).
      if (s && (!o.wait_for_controller || (*s)["controller"]["alive"] == true)) return;
      Sleep(0.05);
    }
    FAIL() << "daemon never answered or never saw the controller";
  }

  std::optional<nlohmann::json> Status() {
    RpcClient c;
    std::string error;
    if (!c.Connect(socket_, &error)) return std::nullopt;
    return c.Call("status", nlohmann::json::object(), 5, &error);
  }

  int Ctl(const std::vector<std::string>& args, std::string* out = nullptr, double timeout_s = 30) {
    std::vector<std::string> argv = {kCtl, "--socket", socket_};
    argv.insert(argv.end(), args.begin(), args.end());
    std::string o;
    const int rc = RunCommand(argv, &o, timeout_s);
    if (out) *out = o;
    return rc;
  }

  // Waits (wall time) until the daemon's robot time passes t.
  nlohmann::json WaitRobotTime(double t, double wall_limit_s = 60) {
    const auto end = Clock::now() + std::chrono::duration<double>(WallS(wall_limit_s));
    nlohmann::json last;
    while (Clock::now() < end) {
      auto s = Status();
      if (s) {
        last = *s;
        if ((*s)["robot_time"].get<double>() >= t) return *s;
      }
      Sleep(0.1);
    }
    ADD_FAILURE() << "robot time never reached " << t;
    return last;
  }

  nlohmann::json StopSimAndReadTruth() {
    sim_.Signal(SIGTERM);
    EXPECT_EQ(sim_.Wait(10), 0);
    std::string error;
    auto j = ParseJsonText(testing::ReadFile(dir_ + "/truth.json"), &error);
    EXPECT_TRUE(j) << error;
    return j.value_or(nlohmann::json::object());
  }

  std::string dir_, bus_, socket_;
  Process sim_, daemon_;
};

TEST_F(E2eTest, FollowsTheWholePerimeterOverTheBusAndReturnsToItsStart) {
  StartAll();
  std::string out;
  ASSERT_EQ(Ctl({"start"}, &out), 0) << out;
  EXPECT_EQ(out, "state: wall_follow\n");
  // Poll status: it advances, and tells when wall following proper began.
  double follow_t = -1, last_t = -1, last_dist = -1;
  uint64_t last_enc = 0;
  int advances = 0;
  const auto end = Clock::now() + std::chrono::duration<double>(WallS(80));
  while (Clock::now() < end) {
    auto s = Status();
    ASSERT_TRUE(s);
    const double t = (*s)["robot_time"];
    if (follow_t < 0 && (*s)["behaviour"] == "follow") follow_t = t;
    if (t > last_t && (*s)["distance"].get<double>() > last_dist &&
        (*s)["frames"]["encoder"].get<uint64_t>() > last_enc) {
      ++advances;
    }
    last_t = t;
    last_dist = (*s)["distance"];
    last_enc = (*s)["frames"]["encoder"];
    if ((*s)["state"] == "done") break;
    EXPECT_NE((*s)["state"], "fault") << s->dump();
    EXPECT_NE((*s)["state"], "idle") << s->dump();
    // Finely until wall following begins (its start point is judged from it), then coarsely.
    Sleep(follow_t < 0 ? 0.02 : 0.25);
  }
  auto final_status = Status();
  EXPECT_EQ((*final_status)["state"], "done") << "the loop was not closed";
  EXPECT_GT(last_t, 60);
  EXPECT_GT(advances, 30);
  ASSERT_GT(follow_t, 0);
  ASSERT_EQ(Ctl({"stop"}), 0);
  const nlohmann::json truth = StopSimAndReadTruth();
  EXPECT_EQ(truth["collisions"], 0) << "contacts [t, x, y]: " << truth["collision_points"].dump();
  EXPECT_GT(truth["min_clearance"].get<double>(), 0.19);
  // Coverage of the four walls, and the return to where following began.
  const auto& tr = truth["trajectory"];
  double sx = 0, sy = 0;
  for (const auto& p : tr) {
    if (p[0].get<double>() >= follow_t) {
      sx = p[1];
      sy = p[2];
      break;
    }
  }
  bool bottom = false, right = false, top = false, left = false;
  double best = 1e9, path = 0, px = sx, py = sy;
  for (const auto& p : tr) {
    if (p[0].get<double>() < follow_t) continue;
    const double x = p[1], y = p[2];
    path += std::hypot(x - px, y - py);
    px = x;
    py = y;
    bottom |= y < 0.6;
    top |= y > 4.9;
    left |= x < 0.6;
    right |= x > 3.4;
    if (bottom && top && left && right && path > 8) best = std::min(best, std::hypot(x - sx, y - sy));
  }
  EXPECT_TRUE(bottom && right && top && left);
  EXPECT_LT(best, 0.30) << "did not return to the point where wall following began";
}

TEST_F(E2eTest, StopHaltsTheWheelsWithinOnePeriod) {
  StartAll();
  testing::BusTap tap(bus_);
  ASSERT_TRUE(tap.ok()) << tap.error();
  ASSERT_EQ(Ctl({"start"}), 0);
  WaitRobotTime(Status().value()["robot_time"].get<double>() + 5);
  RpcClient c;
  std::string error;
  ASSERT_TRUE(c.Connect(socket_, &error));
  ASSERT_TRUE(c.Call("stop", nlohmann::json::object(), 5, &error)) << error;
  const auto replied = Clock::now();
  Sleep(0.3);
  // The command stream around the request, in bus order: the first disabled
  // command must directly follow the last enabled one (consecutive sequence
  // numbers: no control period passed in between) and nothing enabled may follow.
  std::vector<std::pair<proto::WheelCmd, Clock::time_point>> cmds;
  int status_ready = 0;
  for (const auto& s : tap.Frames()) {
    const auto d = proto::Decode(s.frame);
    if (!d.ok()) continue;
    if (const auto* cmd = std::get_if<proto::WheelCmd>(&d.message)) cmds.emplace_back(*cmd, s.at);
    if (const auto* st = std::get_if<proto::ControllerStatus>(&d.message)) {
      status_ready += st->state == proto::ControllerState::kReady && s.at > replied;
    }
  }
  // The stop is the last switch from enabled to disabled commands (a loaded host
  // may also have shown a short controller-loss fault earlier, with its own zeros).
  size_t first_off = cmds.size();
  for (size_t i = cmds.size(); i-- > 0;) {
    if (cmds[i].first.enable) {
      first_off = i + 1;
      break;
    }
  }
  ASSERT_LT(first_off, cmds.size()) << "no stop command on the bus";
  ASSERT_GT(first_off, 0u) << "the robot was not driving before the stop";
  EXPECT_EQ(static_cast<uint8_t>(cmds[first_off - 1].first.seq + 1), cmds[first_off].first.seq);
  EXPECT_EQ(cmds[first_off].first.left_mps, 0.0);
  EXPECT_EQ(cmds[first_off].first.right_mps, 0.0);
  EXPECT_LE(cmds[first_off].second, replied + std::chrono::milliseconds(50));
  // And it was the stop: the last enabled command came before the request was
  // answered (give the tap's thread a moment of delivery latency).
  EXPECT_LE(cmds[first_off - 1].second, replied + std::chrono::milliseconds(50));
  EXPECT_GT(status_ready, 0) << "the controller never reported the wheels stopped";
  auto s = Status();
  EXPECT_EQ((*s)["state"], "idle");
  EXPECT_EQ((*s)["reason"], "stopped by request");
  EXPECT_EQ((*s)["command"][0], 0.0);
}

TEST_F(E2eTest, BadFramesAreCountedAndDroppedWhileTheRobotKeepsGoing) {
  StartAll();
  testing::BusTap tap(bus_);
  ASSERT_TRUE(tap.ok()) << tap.error();
  ASSERT_EQ(Ctl({"start"}), 0);
  WaitRobotTime(3);
  const auto before = Status().value();
  can_frame f{};
  for (int i = 0; i < 50; ++i) {  // unknown ids
    f.can_id = 0x555;
    f.can_dlc = 8;
    tap.Send(f);
  }
  for (int i = 0; i < 10; ++i) {  // extended id that aliases ours
    f.can_id = proto::kEncoderId | CAN_EFF_FLAG;
    tap.Send(f);
  }
  for (int i = 0; i < 20; ++i) {  // our id, wrong DLC
    f = proto::Encode(proto::EncoderCounts{});
    f.can_dlc = 3;
    tap.Send(f);
  }
  Sleep(0.5);
  const auto after = WaitRobotTime(before["robot_time"].get<double>() + 8);
  if (IsLoopback()) {
    // Loopback bus: filtered in user space, and counted.
    EXPECT_EQ(after["can"]["filtered"].get<uint64_t>() - before["can"]["filtered"].get<uint64_t>(), 60u);
  } else {
    // SocketCAN: the kernel's CAN_RAW_FILTER keeps foreign ids out of user space.
    EXPECT_EQ(after["can"]["filtered"], before["can"]["filtered"]);
    EXPECT_EQ(after["frames"]["unknown_id"], before["frames"]["unknown_id"]);
  }
  EXPECT_EQ(after["frames"]["wrong_dlc"].get<uint64_t>() - before["frames"]["wrong_dlc"].get<uint64_t>(), 20u);
  EXPECT_EQ(after["state"], "wall_follow");
  EXPECT_GT(after["frames"]["encoder"].get<uint64_t>(), before["frames"]["encoder"].get<uint64_t>() + 200);
  EXPECT_GT(after["distance"].get<double>(), before["distance"].get<double>() + 0.3);
}

TEST_F(E2eTest, BadApiInputNeverWedgesTheDaemon) {
  StartAll();
  RpcClient good;
  std::string error;
  ASSERT_TRUE(good.Connect(socket_, &error));
  {
    RpcClient garbage;
    ASSERT_TRUE(garbage.Connect(socket_, &error));
    ASSERT_TRUE(garbage.SendRaw("\x01\x02 not json at all\n", &error));
    auto l = garbage.ReadLine(5, &error);
    ASSERT_TRUE(l) << error;
    EXPECT_EQ(nlohmann::json::parse(*l)["error"]["code"], -32700);
  }
  {
    RpcClient big;
    ASSERT_TRUE(big.Connect(socket_, &error));
    big.SendRaw(std::string(100 * 1024, '{'), &error);
    auto l = big.ReadLine(5, &error);
    ASSERT_TRUE(l) << error;
    EXPECT_EQ(nlohmann::json::parse(*l)["error"]["code"], -32600);
    EXPECT_FALSE(big.ReadLine(5, &error));
  }
  {
    RpcClient half;
    ASSERT_TRUE(half.Connect(socket_, &error));
    half.SendRaw(R"({"jsonrpc":"2.0","id":1,"method":"sta)", &error);
  }
  {
    RpcClient unknown;
    ASSERT_TRUE(unknown.Connect(socket_, &error));
    EXPECT_FALSE(unknown.Call("self_destruct", nlohmann::json::object(), 5, &error));
    EXPECT_EQ(error, "method not found: self_destruct");
  }
  auto s = good.Call("status", nlohmann::json::object(), 5, &error);
  ASSERT_TRUE(s) << error;
  EXPECT_GE((*s)["api"]["dropped_long_line"].get<int>(), 1);
  EXPECT_TRUE(daemon_.running());
}

TEST_F(E2eTest, SigtermStopsTheWheelsAndExitsCleanly) {
  StartAll();
  testing::BusTap tap(bus_);
  ASSERT_EQ(Ctl({"start"}), 0);
  WaitRobotTime(Status().value()["robot_time"].get<double>() + 2);
  daemon_.Signal(SIGTERM);
  EXPECT_EQ(daemon_.Wait(5), 0);
  Sleep(0.1);
  std::optional<proto::WheelCmd> last;
  for (const auto& s : tap.Frames()) {
    const auto d = proto::Decode(s.frame);
    if (d.ok() && std::holds_alternative<proto::WheelCmd>(d.message)) {
      last = std::get<proto::WheelCmd>(d.message);
    }
  }
  ASSERT_TRUE(last);
  EXPECT_FALSE(last->enable);
  EXPECT_FALSE(std::filesystem::exists(socket_));
  std::string out;
  EXPECT_NE(Ctl({"status"}, &out), 0);
  EXPECT_NE(out.find("cannot reach irslamd"), std::string::npos) << out;
}

TEST_F(E2eTest, CtlWaitAndMapWork) {
  StartAll();
  std::string out;
  EXPECT_EQ(Ctl({"wait", "--state", "idle", "--timeout", "5"}, &out), 0) << out;
  EXPECT_EQ(Ctl({"wait", "--state", "done", "--timeout", "0.5"}, &out), 1);
  EXPECT_EQ(out, "irslamctl: timed out waiting for state done\n");
  ASSERT_EQ(Ctl({"map", "--out", dir_ + "/map.json", "--svg", dir_ + "/map.svg"}, &out), 0) << out;
  std::string error;
  auto m = ParseJsonText(testing::ReadFile(dir_ + "/map.json"), &error);
  ASSERT_TRUE(m) << error;
  EXPECT_EQ((*m)["frame"], "map");
  EXPECT_EQ((*m)["pose"].size(), 3u);
  EXPECT_EQ((*m)["pose_cov"].size(), 3u);
  EXPECT_NE(testing::ReadFile(dir_ + "/map.svg").find("<svg"), std::string::npos);
  EXPECT_EQ(Ctl({"status", "--json"}, &out), 0);
  EXPECT_EQ(nlohmann::json::parse(out)["state"], "idle");
}

// A task's scheduling policy and real-time priority (/proc/PID/task/TID/stat fields 41, 40).
std::pair<int, int> TaskPolicy(pid_t pid, const std::string& tid) {
  const std::string stat = testing::ReadFile("/proc/" + std::to_string(pid) + "/task/" + tid + "/stat");
  std::istringstream rest(stat.substr(stat.rfind(')') + 2));  // after "pid (comm) "
  std::string field, rt_priority;
  for (int i = 3; i <= 41 && rest >> field; ++i) {
    if (i == 40) rt_priority = field;
  }
  return {std::stoi(field), std::stoi(rt_priority)};
}

TEST_F(E2eTest, TheLoopAndApiThreadsRunRealTimeTheWritersDoNotAndStatusSaysSo) {
  StartAll();
  std::string out;
  ASSERT_EQ(Ctl({"status", "--json"}, &out), 0) << out;
  const auto period = nlohmann::json::parse(out)["period"];
  const std::string sched = period["scheduling"], api_sched = period["api_scheduling"];
  const pid_t pid = daemon_.pid();
  std::multiset<std::pair<int, int>> others;  // every thread but the loop's
  int tasks = 0;
  for (const auto& e : std::filesystem::directory_iterator("/proc/" + std::to_string(pid) + "/task")) {
    const std::string tid = e.path().filename();
    const auto [policy, priority] = TaskPolicy(pid, tid);
    ++tasks;
    if (tid == std::to_string(pid)) {
      EXPECT_EQ(policy == SCHED_FIFO && priority == 10, sched == "fifo 10") << sched;
    } else {
      others.insert({policy, priority});
    }
  }
  EXPECT_GE(tasks, 3);  // the loop, the API thread, the map writer
  if (sched == "fifo 10") {
    EXPECT_EQ(api_sched, "fifo 9");
    EXPECT_EQ(others.count({SCHED_FIFO, 9}), 1u);  // the API thread
    EXPECT_EQ(others.count({SCHED_OTHER, 0}), others.size() - 1);  // the writers
  } else {  // refused on this host: normal, and the reason given
    EXPECT_EQ(sched.rfind("normal (SCHED_FIFO 10 refused: ", 0), 0u) << sched;
    EXPECT_EQ(others.count({SCHED_OTHER, 0}), others.size());
    EXPECT_NE(testing::ReadFile(dir_ + "/daemon.log").find("keeps normal scheduling"), std::string::npos);
  }
}

TEST_F(E2eTest, WholeMissionOverTheBusEndsDoneWithTheRoomModelled) {
#if defined(__SANITIZE_ADDRESS__)
  // Instrumented processes run several times slower: short controller-loss
  // faults change the robot's path, so exploration quality is judged in the
  // normal build (this suite still checks the whole mission for memory errors
  // in process: mission_test).
  GTEST_SKIP() << "exploration quality is judged in the uninstrumented build";
#endif
  StartOptions o;
  o.world = "fig14.json";
  StartAll(o);
  std::string out;
  ASSERT_EQ(Ctl({"start"}, &out), 0) << out;
  // ~290 s of robot time at 10x (docs/accuracy.md); generous for a loaded machine.
  EXPECT_EQ(Ctl({"wait", "--state", "done", "--timeout", std::to_string(WallS(120))}, &out, WallS(120) + 10),
            0)
      << out;
  ASSERT_EQ(Ctl({"map", "--out", dir_ + "/map.json", "--svg", dir_ + "/map.svg"}, &out), 0) << out;
  std::string error;
  auto m = ParseJsonText(testing::ReadFile(dir_ + "/map.json"), &error);
  ASSERT_TRUE(m) << error;
  EXPECT_EQ((*m)["state"], "done");
  ASSERT_TRUE((*m)["room"]["box"].is_array());
  for (const char* wall : {"bottom", "right", "top", "left"}) EXPECT_FALSE((*m)["room"]["walls"][wall].empty()) << wall;
  int wall_contact = 0, free_objects = 0, complete = 0;
  for (const auto& obj : (*m)["objects"]) {
    (obj["kind"] == "free" ? free_objects : wall_contact)++;
    complete += obj["complete"].get<bool>();
  }
  EXPECT_EQ(wall_contact, 1);
  EXPECT_EQ(free_objects, 2);
  // In process every seed but one in 20 completes all three (docs/accuracy.md);
  // over a real bus the timing differs from run to run: at least two of three.
  EXPECT_GE(complete, 2) << (*m)["objects"].dump();
  std::printf("whole mission over the bus: %d of 3 objects complete\n", complete);
  // Nothing mapped or seen is touched; a box corner that sits between the beams
  // may be found by the bumper once on the way to P1 (timing differs from run to
  // run over a real bus: seen in about one run in six under a loaded host), and
  // is then remembered and never hit again.
  const nlohmann::json truth = StopSimAndReadTruth();
  EXPECT_LE(truth["collisions"].get<int>(), 1) << "contacts [t, x, y]: " << truth["collision_points"].dump();
}

// Issue 14 through the real processes: the map an earlier run left in the state
// directory (made here by irslam-sim run, stored as irslamd stores it) is loaded
// at start; `start` relocalises in it and the mission goes on in its frame with
// its ids; `start --fresh` explores from nothing instead.
TEST_F(E2eTest, ARestartedDaemonRelocalisesInTheSavedMap) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "relocalisation quality is judged in the uninstrumented build";
#endif
  std::string out;
  ASSERT_EQ(RunCommand({kSim, "run", "--world", kSrc + "/tests/worlds/fig14.json", "--map-out", dir_ + "/day1.json"},
                       &out, 120),
            0)
      << out;
  std::string error;
  const auto day1 = ParseJsonText(testing::ReadFile(dir_ + "/day1.json"), &error);
  ASSERT_TRUE(day1) << error;
  {
    // daemon/map_store.h's file: the map with its CRC-32.
    boost::crc_32_type crc;
    const std::string body = day1->dump();
    crc.process_bytes(body.data(), body.size());
    char hex[9];
    std::snprintf(hex, sizeof hex, "%08x", crc.checksum());
    std::filesystem::create_directories(StateDir());
    std::ofstream(StateDir() + "/map.json")
        << nlohmann::json{{"format", "irslam-map"}, {"version", 1}, {"seq", 7}, {"reason", "stop"},
                          {"map", *day1}, {"crc32", hex}}.dump() << "\n";
  }
  StartOptions o;
  o.world = "fig14.json";
  StartAll(o);
  EXPECT_EQ(Status().value()["map_store"]["seq"], 7);
  EXPECT_NE(testing::ReadFile(dir_ + "/daemon.log").find("the next start relocalises in the saved map"),
            std::string::npos);
  ASSERT_EQ(Ctl({"start"}, &out), 0) << out;
  bool relocalising = false, committed = false;
  const auto end = Clock::now() + std::chrono::duration<double>(WallS(60));
  while (Clock::now() < end && !committed) {
    const auto s = Status().value();
    relocalising |= s["state"] == "relocalize";
    committed = s.contains("relocalize") && s["relocalize"]["committed"] == true;
    Sleep(0.05);
  }
  EXPECT_TRUE(relocalising);
  ASSERT_TRUE(committed) << Status().value().dump();
  WaitRobotTime(Status().value()["robot_time"].get<double>() + 5);
  ASSERT_EQ(Ctl({"map", "--out", dir_ + "/day2.json"}, &out), 0) << out;
  const auto day2 = ParseJsonText(testing::ReadFile(dir_ + "/day2.json"), &error);
  ASSERT_TRUE(day2) << error;
  EXPECT_TRUE((*day2)["relocalized"].is_object()) << (*day2).dump().substr(0, 400);
  std::set<int> ids;
  for (const auto& l : (*day2)["lines"]) ids.insert(l["id"].get<int>());
  size_t kept = 0;
  for (const auto& l : (*day1)["lines"]) kept += ids.count(l["id"].get<int>());
  EXPECT_GE(kept, (*day1)["lines"].size() * 3 / 4) << "the saved map's line ids";
  ASSERT_EQ(Ctl({"stop"}, &out), 0) << out;
  // Fresh: explores from nothing.
  ASSERT_EQ(Ctl({"start", "--fresh"}, &out), 0) << out;
  WaitRobotTime(Status().value()["robot_time"].get<double>() + 1);
  const auto s = Status().value();
  EXPECT_EQ(s["state"], "wall_follow") << s.dump().substr(0, 400);
  ASSERT_EQ(Ctl({"stop"}, &out), 0) << out;
}

TEST_F(E2eTest, SighupReloadsAGoodConfigAndKeepsTheOldOneOnABadOne) {
  StartOptions o;
  o.world = "fig14.json";
  o.config = {{"control", {{"period_s", 0.02}}}};
  StartAll(o);
  const std::string conf = ConfigPath();
  auto s = Status();
  ASSERT_TRUE(s);
  EXPECT_DOUBLE_EQ((*s)["period"]["target"].get<double>(), 0.02);
  std::ofstream(conf) << R"({"control": {"period_s": "fast"}})";
  daemon_.Signal(SIGHUP);
  Sleep(0.3);
  s = Status();
  ASSERT_TRUE(s) << "the daemon died on a bad reload";
  EXPECT_DOUBLE_EQ((*s)["period"]["target"].get<double>(), 0.02);
  EXPECT_NE(testing::ReadFile(dir_ + "/daemon.log").find("reload failed, keeping the running config"),
            std::string::npos);
  std::ofstream(conf) << R"({"control": {"period_s": 0.01}})";
  daemon_.Signal(SIGHUP);
  Sleep(0.3);
  s = Status();
  ASSERT_TRUE(s);
  EXPECT_DOUBLE_EQ((*s)["period"]["target"].get<double>(), 0.01);  // idle: applied at once
}

TEST_F(E2eTest, TellsSystemdReadyStatusAndFeedsTheWatchdog) {
  int fd;
  const std::string notify = BindNotifySocket(0.2, &fd);
  StartOptions o;
  o.world = "fig14.json";
  o.daemon_env = {"NOTIFY_SOCKET=" + notify, "WATCHDOG_USEC=200000"};
  o.wait_for_controller = false;
  StartAll(o);
  std::string all;
  const auto end = Clock::now() + std::chrono::seconds(5);
  int watchdogs = 0;
  while (Clock::now() < end && watchdogs < 3) {
    char buf[512];
    const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
    if (n <= 0) continue;
    const std::string msg(buf, static_cast<size_t>(n));
    all += msg + "\n";
    if (msg.find("WATCHDOG=1") != std::string::npos) ++watchdogs;
  }
  ::close(fd);
  EXPECT_NE(all.find("READY=1"), std::string::npos) << all;
  EXPECT_NE(all.find("STATUS=state=idle"), std::string::npos) << all;
  EXPECT_GE(watchdogs, 3) << all;
  daemon_.Signal(SIGTERM);
  EXPECT_EQ(daemon_.Wait(5), 0);
}

// A stand-in for systemd's watchdog: a loop that hangs stops the WATCHDOG=1 pings
// (they are sent from the loop itself), the supervisor notices within
// WATCHDOG_USEC, kills the daemon with SIGABRT as systemd does and starts it
// again (Restart=on-failure); the new one is READY and has the saved map.
TEST_F(E2eTest, AHungLoopStopsTheWatchdogPingsAndARestartFindsTheMap) {
  int fd;
  const std::string notify = BindNotifySocket(0.02, &fd);
  const double watchdog_s = 1.0;  // pings every 0.5 s; a loaded host stays well inside
  StartOptions o;
  o.daemon_env = {"NOTIFY_SOCKET=" + notify, "WATCHDOG_USEC=" + std::to_string(static_cast<int>(watchdog_s * 1e6))};
  // The hang comes after 2.5 s of wall time at 10x; slower (software-emulated)
  // hosts get proportionally more wall time to start, save and start again first.
  const double hang_at = 25 * std::max(1.0, 10.0 / kScale);
  o.daemon_args = {"--test-hang-at", std::to_string(hang_at)};
  StartAll(o);
  ASSERT_EQ(Ctl({"start"}), 0);
  WaitRobotTime(10);
  ASSERT_EQ(Ctl({"stop"}), 0);  // saves the map (save 1)
  ASSERT_EQ(Status().value()["map_store"]["seq"], 1);
  ASSERT_EQ(Ctl({"start"}), 0);
  // Supervise: note every ping; a silence longer than WATCHDOG_USEC is a stall.
  auto last_ping = Clock::now();
  bool stalled = false;
  int pings = 0;
  const auto end = Clock::now() + std::chrono::duration<double>(WallS(40) + hang_at / kScale);
  while (Clock::now() < end && !stalled) {
    char buf[512];
    const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
    if (n > 0 && std::string(buf, static_cast<size_t>(n)).find("WATCHDOG=1") != std::string::npos) {
      last_ping = Clock::now();
      ++pings;
    }
    stalled = std::chrono::duration<double>(Clock::now() - last_ping).count() > watchdog_s;
  }
  ASSERT_TRUE(stalled) << "the watchdog never saw a stall";
  EXPECT_GE(pings, 2);  // the loop was feeding it until it hung
  EXPECT_NE(testing::ReadFile(dir_ + "/daemon.log").find("the control loop hangs now"), std::string::npos);
  EXPECT_TRUE(daemon_.running()) << "hung, not dead: only the watchdog can tell";
  RpcClient c;
  std::string error;
  if (c.Connect(socket_, &error)) {
    EXPECT_FALSE(c.Call("status", nlohmann::json::object(), 0.5, &error)) << "a hung loop answered";
  }
  daemon_.Signal(SIGABRT);  // systemd's WatchdogSignal
  daemon_.Wait(5);
  EXPECT_FALSE(daemon_.running());
  StartOptions again;
  again.daemon_env = {"NOTIFY_SOCKET=" + notify};
  StartDaemon(again);
  bool ready = false;
  for (int i = 0; i < 100 && !ready; ++i) {
    char buf[512];
    const ssize_t n = ::recv(fd, buf, sizeof buf, 0);
    ready = n > 0 && std::string(buf, static_cast<size_t>(n)).find("READY=1") != std::string::npos;
  }
  ::close(fd);
  EXPECT_TRUE(ready);
  const auto s = Status().value();
  EXPECT_EQ(s["map_store"]["seq"], 1);
  EXPECT_TRUE(s["map_store"]["saved_map"].get<bool>());
  EXPECT_EQ(s["state"], "idle");
}

// A notify socket nobody reads (its queue full after net.unix.max_dgram_qlen
// messages) must not stall the control loop: notifications that do not fit are
// dropped and counted.
TEST_F(E2eTest, AnUndrainedNotifySocketDoesNotStallTheLoop) {
  int fd;
  const std::string notify = BindNotifySocket(0, &fd);
  StartOptions o;
  o.daemon_env = {"NOTIFY_SOCKET=" + notify, "WATCHDOG_USEC=100000"};  // a ping every 50 ms
  StartAll(o);
  Sleep(2);  // ~40 pings, never read
  const auto s = Status();
  ASSERT_TRUE(s) << "the daemon stalled on its notify socket";
  EXPECT_GT((*s)["notify_dropped"].get<int>(), 0);
  EXPECT_GT((*s)["period"]["ticks"].get<int>(), 50);
  ::close(fd);
}

TEST_F(E2eTest, CandumpLogOfTheBusDecodesWithTheDbc) {
  StartAll();
  ASSERT_EQ(Ctl({"start"}), 0);
  std::string out;
  // can-utils' own candump on SocketCAN when it is there; ours on the loopback bus.
  std::vector<std::string> dump = {kBin + "/daemon/irslam-candump", bus_, "-n", "400"};
  if (bus_.rfind("unix:", 0) != 0 && ::access("/usr/bin/candump", X_OK) == 0) {
    dump = {"/usr/bin/candump", "-L", "-n", "400", bus_};
  }
  ASSERT_EQ(RunCommand(dump, &out, WallS(30)), 0) << out;
  const auto dbc = testing::ParseDbc(kSrc + "/proto/irslam.dbc");
  std::istringstream lines(out);
  std::string line;
  int n = 0;
  std::map<std::string, int> by_name;
  while (std::getline(lines, line)) {
    // "(1700000000.123456) loopback 110#3412CDAB01007F"
    std::istringstream ls(line);
    std::string stamp, iface, text;
    ls >> stamp >> iface >> text;
    can_frame f;
    ASSERT_TRUE(proto::ParseCandumpString(text, &f)) << line;
    bool known = false;
    for (const auto& [name, m] : dbc) {
      if (m.id != f.can_id) continue;
      known = true;
      EXPECT_EQ(m.dlc, f.can_dlc) << line;
      for (const auto& [sig, spec] : m.signals) {
        const double v = testing::DbcDecode(f, spec);
        EXPECT_GE(v, spec.min - 1e-9) << line << " " << sig;
        EXPECT_LE(v, spec.max + 1e-9) << line << " " << sig;
      }
      ++by_name[name];
    }
    EXPECT_TRUE(known) << line;
    ++n;
  }
  EXPECT_EQ(n, 400);
  for (const char* name : {"WHEEL_CMD", "CTRL_STATUS", "ENCODER", "IR_A", "IR_B"}) EXPECT_GT(by_name[name], 0) << name;
}

// Issue 16: a candump -L log of a mission plays into a live irslamd with
// can-utils' canplayer (SocketCAN only: the VM suite). The controller's frames
// of the log (irslamd's own are left out: played back they would be a second
// commander on the bus) reach the daemon and are taken as from a controller.
TEST_F(E2eTest, CanplayerPlaysARecordedLogIntoALiveDaemon) {
  const bool socketcan = bus_.rfind("unix:", 0) != 0 && ::access("/usr/bin/canplayer", X_OK) == 0 &&
                         ::access("/usr/bin/candump", X_OK) == 0;
  if (!socketcan) GTEST_SKIP() << "needs SocketCAN and can-utils (vcan-scripts/vm-test.sh)";
  StartAll();
  ASSERT_EQ(Ctl({"start"}), 0);
  std::string log;
  ASSERT_EQ(RunCommand({"/usr/bin/candump", "-L", "-n", "1500", bus_}, &log, WallS(60)), 0) << log;
  daemon_.Signal(SIGTERM);
  daemon_.Wait(5);
  sim_.Signal(SIGTERM);
  sim_.Wait(5);
  // The controller's frames only, by the DBC's transmitter.
  const auto dbc = testing::ParseDbc(kSrc + "/proto/irslam.dbc");
  std::istringstream lines(log);
  std::ofstream played(dir_ + "/controller.log");
  std::string line;
  int kept = 0;
  while (std::getline(lines, line)) {
    std::istringstream ls(line);
    std::string stamp, iface, text;
    ls >> stamp >> iface >> text;
    can_frame f;
    if (!proto::ParseCandumpString(text, &f)) continue;
    for (const auto& [name, m] : dbc) {
      if (m.id == f.can_id && (name == "CTRL_STATUS" || name == "ENCODER" || name == "IR_A" || name == "IR_B")) {
        played << line << "\n";
        ++kept;
      }
    }
  }
  played.close();
  ASSERT_GT(kept, 500);
  StartOptions o;
  o.wait_for_controller = false;
  StartDaemon(o);
  const auto before = Status().value();
  std::string out;
  ASSERT_EQ(RunCommand({"/usr/bin/canplayer", "-I", dir_ + "/controller.log"}, &out, WallS(60)), 0) << out;
  Sleep(0.3);
  const auto after = Status().value();
  const auto grew = [&](const char* key) {
    return after["frames"][key].get<uint64_t>() - before["frames"][key].get<uint64_t>();
  };
  EXPECT_GT(grew("encoder"), 100u) << after["frames"].dump();
  EXPECT_GT(grew("status"), 10u) << after["frames"].dump();
  EXPECT_GT(grew("ir"), 100u) << after["frames"].dump();
  EXPECT_EQ(after["frames"]["unknown_id"], before["frames"]["unknown_id"]);
  EXPECT_NE(after["state"], "fault") << after.dump().substr(0, 300);
}

TEST_F(E2eTest, FrameSentWithCansendInDbcLayoutIsDecoded) {
  StartAll();
  const auto before = Status().value();
  // ENCODER, DBC layout: Timestamp, LeftCount, RightCount, Seq (here: bad DLC 3 and
  // a well-formed one from a second "controller": both must be seen and counted).
  std::string out;
  const bool socketcan = bus_.rfind("unix:", 0) != 0 && ::access("/usr/bin/cansend", X_OK) == 0;
  if (socketcan) {
    ASSERT_EQ(RunCommand({"/usr/bin/cansend", bus_, "110#010203"}, &out), 0) << out;
  } else {
    testing::BusTap tap(bus_);
    can_frame f;
    ASSERT_TRUE(proto::ParseCandumpString("110#010203", &f));
    tap.Send(f);
    Sleep(0.2);
  }
  Sleep(0.3);
  const auto after = Status().value();
  EXPECT_EQ(after["frames"]["wrong_dlc"].get<uint64_t>(), before["frames"]["wrong_dlc"].get<uint64_t>() + 1);
  // Receive timestamps: the kernel's on both buses (SocketCAN: SO_TIMESTAMP, the
  // loopback bus: SO_TIMESTAMPNS): recent wall-clock time.
  const double rx = after["can"]["last_rx_time"];
  EXPECT_NEAR(rx, static_cast<double>(::time(nullptr)), 5.0);
  EXPECT_TRUE(after["can"]["kernel_timestamps"].get<bool>());
}

TEST_F(E2eTest, InterfaceDownAndUpIsSurvivedWithoutRestart) {
  if (IsLoopback()) {
    GTEST_SKIP() << "needs a SocketCAN interface: runs in the VM suite (vcan-scripts/vm-test.sh)";
  }
  StartAll();
  ASSERT_EQ(Ctl({"start"}), 0);
  WaitRobotTime(Status().value()["robot_time"].get<double>() + 3);
  std::string out;
  ASSERT_EQ(RunCommand({"/sbin/ip", "link", "set", bus_, "down"}, &out), 0) << out;
  // The daemon notices (sends fail with ENETDOWN, frames stop): fault, wheels zero.
  bool faulted = false;
  for (int i = 0; i < 100 && !faulted; ++i) {
    auto s = Status();
    faulted = s && (*s)["state"] == "fault" && (*s)["can"]["link_up"] == false &&
              (*s)["command"][0] == 0.0 && (*s)["command"][1] == 0.0;
    Sleep(0.05);
  }
  EXPECT_TRUE(faulted);
  ASSERT_EQ(RunCommand({"/sbin/ip", "link", "set", bus_, "up"}, &out), 0) << out;
  bool resumed = false;
  for (int i = 0; i < 200 && !resumed; ++i) {
    auto s = Status();
    resumed = s && (*s)["state"] == "wall_follow" && (*s)["can"]["link_up"] == true;
    Sleep(0.05);
  }
  EXPECT_TRUE(resumed) << "no recovery without a restart";
  EXPECT_TRUE(daemon_.running());
  const auto s = Status().value();
  EXPECT_GE(s["can"]["link_down_events"].get<int>(), 1);
  EXPECT_NE(s["reason"].get<std::string>().find("resumed after: controller lost"), std::string::npos) << s["reason"];
}

TEST_F(E2eTest, ErrorFramesAndKernelDropsAreCounted) {
  if (IsLoopback() || ::access("/usr/bin/cansend", X_OK) != 0) {
    GTEST_SKIP() << "needs SocketCAN and can-utils: runs in the VM suite (vcan-scripts/vm-test.sh)";
  }
  StartAll();
  const auto before = Status().value();
  std::string out;
  // A bus-off error frame (CAN_ERR_FLAG | CAN_ERR_BUSOFF), as a controller would report it.
  ASSERT_EQ(RunCommand({"/usr/bin/cansend", bus_, "20000040#0000000000000000"}, &out), 0) << out;
  Sleep(0.3);
  auto s = Status().value();
  EXPECT_EQ(s["can"]["error_frames"].get<uint64_t>(), before["can"]["error_frames"].get<uint64_t>() + 1);
  EXPECT_EQ(s["can"]["bus_off"].get<uint64_t>(), before["can"]["bus_off"].get<uint64_t>() + 1);
  EXPECT_EQ(s["can"]["last_error"], "bus-off");
  // A reader that falls behind: the daemon is stopped while 3000 frames of one of
  // its ids arrive; the kernel's drop counter (SO_RXQ_OVFL) then shows up in
  // status, and the daemon carries on.
  daemon_.Signal(SIGSTOP);
  RunCommand({"/usr/bin/cangen", bus_, "-g", "0", "-I", "121", "-L", "7", "-n", "3000"}, &out, WallS(60));
  daemon_.Signal(SIGCONT);
  Sleep(0.5);
  s = Status().value();
  EXPECT_GT(s["can"]["rx_dropped"].get<uint64_t>(), 0u);
  EXPECT_TRUE(daemon_.running());
}

TEST_F(E2eTest, ControlNeedsTheControlGroupReadingTheReadGroup) {
  if (::getuid() != 0 || ::access("/usr/bin/setpriv", X_OK) != 0) {
    GTEST_SKIP() << "needs root and setpriv to act as another user";
  }
  // The socket is given to group nogroup; nogroup may read, only root's group control.
  ::chmod(dir_.c_str(), 0755);
  StartOptions o;
  o.world = "fig14.json";
  o.config = {{"api", {{"socket_group", "nogroup"}, {"read_group", "nogroup"}, {"control_group", "root"}}}};
  StartAll(o);
  struct stat st{};
  ASSERT_EQ(::stat(socket_.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0660u);
  EXPECT_EQ(st.st_gid, 65534u);
  const std::vector<std::string> as_nobody = {"/usr/bin/setpriv", "--reuid=nobody", "--regid=nogroup",
                                              "--clear-groups", kCtl, "--socket", socket_};
  std::string out;
  auto cmd = as_nobody;
  cmd.push_back("status");
  EXPECT_EQ(RunCommand(cmd, &out), 0) << out;
  cmd = as_nobody;
  cmd.push_back("start");
  EXPECT_EQ(RunCommand(cmd, &out), 1);
  EXPECT_EQ(out, "irslamctl: access denied: start needs the control group\n");
  EXPECT_NE(testing::ReadFile(dir_ + "/daemon.log").find("api: denied method=start uid=65534"),
            std::string::npos);
  EXPECT_EQ(Status().value()["state"], "idle");
  EXPECT_EQ(Ctl({"start"}), 0);  // root may
}

TEST(CommandLineTest, BadConfigAndWorldFilesGiveOneLineAndStatus2) {
  const std::string dir = testing::MakeTempDir();
  {
    std::ofstream(dir + "/bad.conf") << R"({"wall_follow": {"speed": 1}})";
    std::ofstream(dir + "/broken.conf") << R"({"control": )";
    std::ofstream(dir + "/bad_world.json") << R"({"room": [4, 4], "start": [1, 1]})";
  }
  const struct {
    std::vector<std::string> argv;
    std::string want;
  } cases[] = {
      {{kDaemon, "--can", "unix:" + dir + "/bus", "--config", dir + "/bad.conf"},
       "irslamd: " + dir + "/bad.conf: config: wall_follow.speed is not a known key\n"},
      {{kDaemon, "--can", "unix:" + dir + "/bus", "--config", dir + "/broken.conf"},
       "irslamd: " + dir + "/broken.conf: config: not valid JSON"},
      {{kDaemon, "--can", "unix:" + dir + "/bus", "--config", dir + "/missing.conf"},
       "irslamd: config: cannot read " + dir + "/missing.conf: No such file or directory\n"},
      {{kSim, "run", "--world", dir + "/bad_world.json"},
       "irslam-sim: " + dir + "/bad_world.json: world: \"start\" must be [x, y, theta]\n"},
      {{kSim, "run", "--world", dir + "/missing.json"},
       "irslam-sim: world: cannot read " + dir + "/missing.json: No such file or directory\n"},
  };
  for (const auto& c : cases) {
    std::string out;
    EXPECT_EQ(RunCommand(c.argv, &out), 2) << c.argv.back();
    EXPECT_EQ(out.rfind(c.want, 0), 0u) << out;
    EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
  }
  std::filesystem::remove_all(dir);
}

// Issue 14: irslam-sim run --map-in, --start and the kidnap fault's target are
// checked before the run, each in one line with status 2; good ones run.
TEST(CommandLineTest, SimRunMapInStartAndKidnapAreCheckedInOneLine) {
  const std::string dir = testing::MakeTempDir();
  const std::string world = std::string(IRSLAM_SOURCE_DIR) + "/tests/worlds/fig14.json";
  const std::string golden = std::string(IRSLAM_SOURCE_DIR) + "/tests/unit/testdata/core_map.golden.json";
  {
    std::ofstream(dir + "/bad_map.json") << R"({"frame": "map", "state": "done", "lines": [{"id": 1}], "objects": []})";
    std::ofstream(dir + "/not_json.json") << R"({"frame": )";
  }
  const auto run = [&](std::vector<std::string> extra) {
    std::vector<std::string> argv = {kSim, "run", "--world", world, "--max-time", "2"};
    argv.insert(argv.end(), extra.begin(), extra.end());
    return argv;
  };
  const struct {
    std::vector<std::string> argv;
    std::string want;
  } cases[] = {
      {run({"--start", "1,2"}),
       "irslam-sim: --start 1,2: expected X,Y,THETA (three numbers: metres, metres, radians), got '1,2'\n"},
      {run({"--start", "9,1,0"}), "irslam-sim: --start 9,1,0: (9.00, 1.00) lies outside the room\n"},
      {run({"--start", "0.3,2.5,0"}),
       "irslam-sim: --start 0.3,2.5,0: (0.30, 2.50) lies inside object 1 [0.00, 2.00, 0.60, 3.20]\n"},
      {run({"--start", "3.95,1,0"}), "irslam-sim: --start 3.95,1,0: (3.95, 1.00) is 0.05 m from a wall or object side"},
      {run({"--faults", "kidnap:at=5:x=1.8:y=1.5"}),
       "irslam-sim: --faults: kidnap at 5 s: (1.80, 1.50) lies inside object 2 [1.40, 1.20, 2.20, 1.80]\n"},
      {run({"--map-in", dir + "/missing.json"}),
       "irslam-sim: --map-in " + dir + "/missing.json: cannot read " + dir + "/missing.json"},
      {run({"--map-in", dir + "/not_json.json"}), "irslam-sim: --map-in " + dir + "/not_json.json: not valid JSON"},
      {run({"--map-in", dir + "/bad_map.json"}),
       "irslam-sim: --map-in " + dir + "/bad_map.json: map.lines[0].rho: missing\n"},
  };
  for (const auto& c : cases) {
    std::string out;
    EXPECT_EQ(RunCommand(c.argv, &out), 2) << c.want;
    EXPECT_EQ(out.rfind(c.want, 0), 0u) << out;
    EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
  }
  // Good ones: the run goes ahead (2 s: not done, status 1, a map written).
  std::string out;
  EXPECT_EQ(RunCommand(run({"--map-in", golden, "--start", "3,0.8,1.5", "--faults", "kidnap:at=1:x=3:y=4.8",
                            "--map-out", dir + "/out.json"}),
                       &out),
            1)
      << out;
  EXPECT_NE(out.find("--max-time reached"), std::string::npos) << out;
  EXPECT_NE(out.find("\"kidnapped\":1"), std::string::npos) << out;
  EXPECT_TRUE(std::filesystem::exists(dir + "/out.json"));
  std::filesystem::remove_all(dir);
}

// The map survives kill -9 at any moment: every restart finds the previous or the
// new map intact, never a torn one (daemon/map_store.h: temp file, fsync, rename).
TEST_F(E2eTest, KillNineAtRandomMomentsNeverLosesOrTearsTheMap) {
  StartAll();
  std::mt19937 rng(20261122);
  std::uniform_real_distribution<double> drive(0.1, 0.8), after_stop(0, 0.004);
  uint64_t last_seq = 0;
  int rounds_with_new_map = 0;
  for (int round = 0; round < 20; ++round) {
    const auto s = Status().value();
    const auto& store = s["map_store"];
    const uint64_t seq = store["seq"];
    // The previous map (the save was not reached) or the new one (it was); nothing else.
    EXPECT_TRUE(seq == last_seq || seq == last_seq + 1) << "round " << round << ": " << store;
    // A save that was answered before the kill is there.
    if (round > 0 && (round - 1) % 2 == 0) {
      EXPECT_EQ(seq, last_seq + 1) << "round " << round;
    }
    EXPECT_EQ(store["error"], "") << "round " << round;
    rounds_with_new_map += seq == last_seq + 1;
    if (seq > 0) {
      // What the restarted daemon serves before a new mission is the saved map.
      std::string out;
      ASSERT_EQ(Ctl({"map", "--out", dir_ + "/saved.json"}, &out), 0) << out;
      const std::string text = testing::ReadFile(dir_ + "/saved.json");
      EXPECT_NE(text.find("\"saved\""), std::string::npos);
      EXPECT_NE(text.find("\"trajectory\""), std::string::npos);
    }
    last_seq = seq;
    ASSERT_EQ(Ctl({"start"}), 0);
    Sleep(drive(rng));
    // stop (which saves the map) and kill -9: in odd rounds 0-4 ms after the
    // request (before, during or after the save), in even rounds right after the
    // reply (the save is done: the restart must find the new map).
    RpcClient c;
    std::string error;
    ASSERT_TRUE(c.Connect(socket_, &error)) << error;
    if (round % 2 == 0) {
      ASSERT_TRUE(c.Call("stop", nlohmann::json::object(), 5, &error)) << error;
    } else {
      c.SendRaw(R"({"jsonrpc":"2.0","id":1,"method":"stop"})" "\n", &error);
      Sleep(after_stop(rng));
    }
    daemon_.Signal(SIGKILL);
    daemon_.Wait(5);
    StartDaemon();
  }
  std::printf("kill -9: %d of 20 restarts found the new map, the others the previous one\n", rounds_with_new_map);
  EXPECT_GE(rounds_with_new_map, 10) << "a save that was answered was not found after the restart";
  int aside = 0, temporary = 0;
  for (const auto& e : std::filesystem::directory_iterator(StateDir())) {
    const std::string name = e.path().filename().string();
    aside += name.rfind("map.json.corrupt", 0) == 0;
    temporary += name.rfind("map.json.tmp", 0) == 0;
  }
  EXPECT_EQ(aside, 0) << "a torn map was found";
  EXPECT_EQ(temporary, 0);
}

// Faults injected by the simulator (irslam-sim --faults; docs/reliability.md),
// through the real processes.

TEST_F(E2eTest, ControllerSilenceAndResetFaultThenResumeKeepingTheMap) {
  StartOptions o;
  // Silent for 6 s from 12 s of robot time, and restarted meanwhile (its clock,
  // counts and sequence numbers start again from zero).
  o.sim_args = {"--faults", "silence:at=12:for=6:reset=1"};
  StartAll(o);
  ASSERT_EQ(Ctl({"start"}), 0);
  const auto before = WaitRobotTime(11);
  const int lines_before = before["lines"];
  const int merges_before = before["slam"]["merges"];
  ASSERT_EQ(before["state"], "wall_follow");
  bool faulted = false;
  nlohmann::json s;
  for (int i = 0; i < 400 && !faulted; ++i) {
    s = Status().value();
    faulted = s["state"] == "fault";
    if (!faulted) Sleep(0.02);
  }
  ASSERT_TRUE(faulted) << s.dump();
  EXPECT_EQ(s["reason"].get<std::string>().rfind("controller lost: ", 0), 0u) << s["reason"];
  EXPECT_FALSE(s["controller"]["alive"].get<bool>());
  Sleep(WallS(0.1));
  s = Status().value();
  EXPECT_EQ(s["state"], "fault");
  EXPECT_EQ(s["command"][0], 0.0);
  EXPECT_EQ(s["command"][1], 0.0);
  // Frames come back from a restarted controller: the mission carries on from
  // where it was, with its map.
  s = WaitRobotTime(24);
  EXPECT_EQ(s["state"], "wall_follow") << s.dump();
  EXPECT_EQ(s["reason"].get<std::string>().rfind("resumed after: controller lost", 0), 0u) << s["reason"];
  // The map was kept: no line lost (lines merged into one at a loop closure
  // count as kept).
  EXPECT_GE(s["lines"].get<int>() + s["slam"]["merges"].get<int>() - merges_before, lines_before) << s["slam"];
  EXPECT_GE(s["frames"]["controller_resets"].get<int>() + s["frames"]["clock_jumps"].get<int>(), 1) << s["frames"];
  const double d = s["distance"];
  s = WaitRobotTime(28);
  EXPECT_GT(s["distance"].get<double>(), d + 0.3) << "not moving again";
  EXPECT_EQ(StopSimAndReadTruth()["collisions"], 0);
}

TEST_F(E2eTest, CorruptAndImplausibleFramesAreCountedByReasonWhileTheRobotKeepsGoing) {
  StartOptions o;
  o.sim_args = {"--faults",
                "corrupt:p=0.02,duplicate:p=0.05,reorder:p=0.05,delay:p=0.02:max=0.03,"
                "encoder_glitch:at=6:counts=3000,stuck_ir:sensor=6:at=3"};
  StartAll(o);
  ASSERT_EQ(Ctl({"start"}), 0);
  const auto s = WaitRobotTime(25);
  const auto& f = s["frames"];
  EXPECT_EQ(s["state"], "wall_follow") << s.dump();
  EXPECT_GT(f["duplicate"].get<int>(), 50) << f;
  EXPECT_GT(f["stale"].get<int>(), 50) << f;
  EXPECT_GE(f["implausible_counts"].get<int>(), 3) << f;  // the glitch that stays, at least
  EXPECT_GT(f["ir_stuck"].get<int>(), 100) << f;
  EXPECT_GT(s["distance"].get<double>(), 2.0);
  // The glitch did not reach odometry: 3000 counts are 32 cm of one wheel, a
  // turn of ~75 degrees; SLAM's pose stays close to the truth.
  const nlohmann::json truth = StopSimAndReadTruth();
  EXPECT_EQ(truth["collisions"], 0) << "contacts [t, x, y]: " << truth["collision_points"].dump();
  EXPECT_GT(truth["faults"]["glitched"].get<int>(), 0);
}

TEST_F(E2eTest, AFloodOfForeignFramesNeitherOverrunsTheLoopNorStarvesTheApi) {
  StartOptions o;
  // From 10 s of robot time on: 8000 foreign frames per wall second (a 1 Mbit/s
  // bus at full load) for 20 s of robot time.
  o.sim_args = {"--faults", "flood:at=10:for=20:rate=8000"};
  StartAll(o);
  ASSERT_EQ(Ctl({"start"}), 0);
  const auto quiet = WaitRobotTime(9.5);  // fault-free so far
  WaitRobotTime(12);
  double worst_call = 0;
  nlohmann::json flooded;
  while (true) {
    const auto t0 = Clock::now();
    auto s = Status();
    worst_call = std::max(worst_call, std::chrono::duration<double>(Clock::now() - t0).count());
    ASSERT_TRUE(s);
    flooded = *s;
    if (flooded["robot_time"].get<double>() >= 28) break;
    Sleep(0.05);
  }
  const auto& pq = quiet["period"];
  const auto& pf = flooded["period"];
  const double ticks_q = pq["ticks"], ticks_f = pf["ticks"];
  const double mean_q = pq["jitter_mean"], mean_f = pf["jitter_mean"];
  const double mean_during = (mean_f * ticks_f - mean_q * ticks_q) / (ticks_f - ticks_q);
  std::printf("flood: %llu frames filtered; jitter mean %.3f ms before, %.3f ms during; overruns %d -> %d; "
              "slowest status call %.1f ms\n",
              static_cast<unsigned long long>(flooded["can"]["filtered"].get<uint64_t>()), mean_q * 1e3,
              mean_during * 1e3, pq["overruns"].get<int>(), pf["overruns"].get<int>(), worst_call * 1e3);
  // 8000 frames per wall second for (28 - 10) s of robot time.
  const double expected = 8000 * (flooded["robot_time"].get<double>() - 10) / kScale;
  if (IsLoopback()) {
    EXPECT_GT(flooded["can"]["filtered"].get<double>(), 0.7 * expected) << "the flood did not arrive";
  } else {
    // SocketCAN: the kernel's id filter keeps the flood out of user space.
    EXPECT_EQ(flooded["can"]["filtered"], 0);
    EXPECT_EQ(flooded["frames"]["unknown_id"], 0);
  }
  EXPECT_LT(mean_during, 2 * mean_q + 0.001);
  EXPECT_LT(worst_call, 0.25);
  EXPECT_EQ(flooded["state"], "wall_follow");
  EXPECT_GT(flooded["distance"].get<double>(), quiet["distance"].get<double>() + 2.0);
}

// The gpio-sim chip of the VM harness (vcan-scripts/run-in-vm.sh, label
// gpio-sim-robot, lines named by vm-test.sh): its sysfs directory, where a test
// pulls an input line (sim_gpioN/pull) and reads an output line (sim_gpioN/value).
std::string GpioSimDir() {
  const std::string cfg = "/sys/kernel/config/gpio-sim/sim0";
  std::string dev = testing::ReadFile(cfg + "/dev_name"), chip = testing::ReadFile(cfg + "/bank0/chip_name");
  if (dev.empty() || chip.empty()) return "";
  while (!dev.empty() && dev.back() == '\n') dev.pop_back();
  while (!chip.empty() && chip.back() == '\n') chip.pop_back();
  return "/sys/devices/platform/" + dev + "/" + chip;
}

void Pull(const std::string& sim, int offset, bool up) {
  std::ofstream(sim + "/sim_gpio" + std::to_string(offset) + "/pull") << (up ? "pull-up" : "pull-down");
}

int OutputLevel(const std::string& sim, int offset) {
  const std::string v = testing::ReadFile(sim + "/sim_gpio" + std::to_string(offset) + "/value");
  return v.empty() ? -1 : v[0] - '0';
}

TEST_F(E2eTest, GpioEstopBumperMotorEnableAndLedOnGpioSim) {
  const std::string sim = GpioSimDir();
  if (sim.empty()) GTEST_SKIP() << "needs a gpio-sim chip: runs in the VM suite (vcan-scripts/vm-test.sh)";
  // Lines 0..4 of chip gpio-sim-robot; the e-stop is active-low (a normally-closed
  // button pulled up: released = high), the others active-high. Some by offset,
  // some by name, as a robot's config may do either.
  Pull(sim, 0, true);
  Pull(sim, 1, false);
  Pull(sim, 2, false);
  StartOptions o;
  o.config = {{"gpio",
               {{"estop", {{"chip", "gpio-sim-robot"}, {"line", 0}, {"active_low", true}}},
                {"bumper_left", {{"chip", "gpio-sim-robot"}, {"line", "bumper-left"}}},
                {"bumper_right", {{"chip", "gpio-sim-robot"}, {"line", "bumper-right"}}},
                {"motor_enable", {{"chip", "gpio-sim-robot"}, {"line", 3}}},
                {"status_led", {{"chip", "gpio-sim-robot"}, {"line", "status-led"}}}}}};
  StartAll(o);
  auto s = Status().value();
  const auto& lines = s["gpio"]["lines"];
  ASSERT_EQ(lines.size(), 5u) << s["gpio"].dump();
  EXPECT_EQ(lines["estop"]["label"], "gpio-sim-robot");
  EXPECT_EQ(lines["estop"]["offset"], 0);
  EXPECT_EQ(lines["bumper_right"]["offset"], 2);
  EXPECT_EQ(lines["status_led"]["offset"], 4);
  EXPECT_EQ(s["state"], "idle");
  EXPECT_FALSE(s["safety"]["estop"].get<bool>());
  EXPECT_EQ(OutputLevel(sim, 3), 0) << "motor driver enabled while idle";
  EXPECT_EQ(OutputLevel(sim, 4), 1) << "idle: LED steady on";

  // Driving: the driver is enabled; the LED blinks at 1 Hz of robot time.
  ASSERT_EQ(Ctl({"start"}), 0);
  WaitRobotTime(Status().value()["robot_time"].get<double>() + 2);
  EXPECT_EQ(OutputLevel(sim, 3), 1) << "motor driver not enabled while driving";
  std::set<int> led;
  for (int i = 0; i < 40; ++i) {
    led.insert(OutputLevel(sim, 4));
    Sleep(WallS(0.05));
  }
  EXPECT_EQ(led, (std::set<int>{0, 1})) << "the LED does not blink while driving";

  // A bumper line held: seen in status and acted on (the robot backs off).
  Pull(sim, 1, true);
  bool seen = false, backed_off = false;
  for (int i = 0; i < 100 && !(seen && backed_off); ++i) {
    const auto st = Status().value();
    seen |= st["safety"]["bumper_left"] == true;
    backed_off |= st["behaviour"] == "backoff";
    Sleep(0.02);
  }
  Pull(sim, 1, false);
  EXPECT_TRUE(seen);
  EXPECT_TRUE(backed_off);

  // E-stop pressed (the line goes low): fault, wheels zero, driver disabled at once.
  testing::BusTap tap(bus_);
  ASSERT_TRUE(tap.ok()) << tap.error();
  Sleep(0.2);
  const auto pressed_at = Clock::now();
  Pull(sim, 0, false);
  while (OutputLevel(sim, 3) != 0 && Clock::now() - pressed_at < std::chrono::seconds(5)) {
  }
  const auto dropped_at = Clock::now();  // first seen low (an upper bound)
  EXPECT_EQ(OutputLevel(sim, 3), 0);
  const double latency = std::chrono::duration<double>(dropped_at - pressed_at).count();
  std::printf("e-stop to motor enable dropped: %.1f ms wall\n", latency * 1e3);
  // Within one control period of robot time (software emulation adds its own delay).
  EXPECT_LT(latency, 0.02 / kScale + 0.1);
  Sleep(0.3);
  s = Status().value();
  EXPECT_EQ(s["state"], "fault");
  EXPECT_EQ(s["reason"], "emergency stop pressed");
  EXPECT_EQ(s["command"][0], 0.0);
  EXPECT_EQ(s["command"][1], 0.0);
  // Every wheel command from shortly after the press on is zero and disabled.
  int after = 0;
  for (const auto& f : tap.Frames()) {
    const auto d = proto::Decode(f.frame);
    const auto* cmd = d.ok() ? std::get_if<proto::WheelCmd>(&d.message) : nullptr;
    if (cmd == nullptr || f.at < pressed_at + std::chrono::milliseconds(100)) continue;
    ++after;
    EXPECT_FALSE(cmd->enable);
    EXPECT_EQ(cmd->left_mps, 0.0);
  }
  EXPECT_GT(after, 3);
  std::string out;
  EXPECT_EQ(Ctl({"start"}, &out), 1);
  EXPECT_NE(out.find("emergency stop is pressed"), std::string::npos) << out;

  // Released: still fault until start is called again; then it carries on.
  Pull(sim, 0, true);
  Sleep(0.3);
  s = Status().value();
  EXPECT_EQ(s["state"], "fault");
  EXPECT_EQ(s["reason"], "emergency stop released: start to resume");
  EXPECT_EQ(OutputLevel(sim, 3), 0);
  ASSERT_EQ(Ctl({"start"}, &out), 0) << out;
  WaitRobotTime(Status().value()["robot_time"].get<double>() + 1);
  s = Status().value();
  EXPECT_EQ(s["state"], "wall_follow");
  EXPECT_EQ(OutputLevel(sim, 3), 1);
  ASSERT_EQ(Ctl({"stop"}), 0);
  Sleep(0.2);
  EXPECT_EQ(OutputLevel(sim, 3), 0);
  EXPECT_EQ(OutputLevel(sim, 4), 1);
  EXPECT_GE(Status().value()["gpio"]["events"].get<int>(), 4);
  // On exit the lines are let go with the driver disabled.
  daemon_.Signal(SIGTERM);
  EXPECT_EQ(daemon_.Wait(5), 0);
  EXPECT_EQ(OutputLevel(sim, 3), 0);
}

TEST(CommandLineTest, UnusableCanInterfaceIsExplained) {
  std::string out;
  const std::string dir = testing::MakeTempDir();
  EXPECT_EQ(RunCommand({kDaemon, "--can", "nocan7", "--socket", dir + "/s.sock"}, &out), 1);
  EXPECT_TRUE(out.find("no CAN support") != std::string::npos ||
              out.find("no such interface 'nocan7'") != std::string::npos)
      << out;
  std::filesystem::remove_all(dir);
}

TEST(CommandLineTest, AConfiguredGpioLineThatIsNotThereIsAnError) {
  // A safety line in the config must not be silently ignored when it is missing.
  std::string out;
  const std::string dir = testing::MakeTempDir();
  std::ofstream(dir + "/gpio.conf") << R"({"gpio": {"estop": {"chip": "no-such-chip", "line": 0}}})";
  EXPECT_EQ(RunCommand({kDaemon, "--can", "unix:" + dir + "/bus", "--socket", dir + "/s.sock", "--config",
                        dir + "/gpio.conf"},
                       &out),
            1);
  EXPECT_EQ(out.rfind("irslamd: gpio: estop (chip 'no-such-chip' line '0'): no such chip", 0), 0u) << out;
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace irslam
