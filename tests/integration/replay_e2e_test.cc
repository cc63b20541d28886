// Record and replay with the real processes (docs/replay.md): a mission of irslam-sim
// serve + irslamd on the loopback bus, recorded twice at once (irslamd's own [record]
// and irslam-candump beside it), then replayed offline by irslam-replay: the replayed
// map must be the one `irslamctl map` gave at the end of the live run.
#include <signal.h>

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <thread>

#include "io/json_text.h"
#include "tests/testing/process.h"

namespace irslam {
namespace {

using testing::Process;
using testing::RunCommand;

const std::string kBin = IRSLAM_BINARY_DIR;
const std::string kSrc = IRSLAM_SOURCE_DIR;
const double kScale = [] {
  const char* e = std::getenv("IRSLAM_TEST_TIME_SCALE");
  return e && *e ? std::atof(e) : 10.0;
}();

nlohmann::json ReadJson(const std::string& path) {
  std::string error;
  auto j = ParseJsonText(testing::ReadFile(path), &error);
  EXPECT_TRUE(j) << path << ": " << error;
  return j.value_or(nlohmann::json::object());
}

// Equal JSON, numbers within tol.
void ExpectNear(const nlohmann::json& a, const nlohmann::json& b, double tol, const std::string& where) {
  if (a.is_number() && b.is_number()) {
    EXPECT_NEAR(a.get<double>(), b.get<double>(), tol) << where;
  } else if (a.is_array() && b.is_array() && a.size() == b.size()) {
    for (size_t i = 0; i < a.size(); ++i) ExpectNear(a[i], b[i], tol, where + "[" + std::to_string(i) + "]");
  } else if (a.is_object() && b.is_object() && a.size() == b.size()) {
    for (const auto& [k, v] : a.items()) {
      ASSERT_TRUE(b.contains(k)) << where << "." << k;
      ExpectNear(v, b[k], tol, where + "." + k);
    }
  } else {
    EXPECT_EQ(a, b) << where;
  }
}

class RecordReplayTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing::MakeTempDir();
    const char* env = std::getenv("IRSLAM_TEST_CAN");
    bus_ = env && *env ? env : "unix:" + dir_ + "/bus";
    socket_ = dir_ + "/irslamd.sock";
  }
  void TearDown() override {
    if (HasFailure()) {
      std::fprintf(stderr, "--- daemon log\n%s", testing::ReadFile(dir_ + "/daemon.log").c_str());
    }
    for (Process* p : {&daemon_, &sim_, &dump_}) p->Signal(SIGKILL);
    for (Process* p : {&daemon_, &sim_, &dump_}) p->Wait(5);
    std::filesystem::remove_all(dir_);
  }
  int Ctl(const std::vector<std::string>& args, std::string* out, double timeout_s = 30) {
    std::vector<std::string> argv = {kBin + "/daemon/irslamctl", "--socket", socket_};
    argv.insert(argv.end(), args.begin(), args.end());
    return RunCommand(argv, out, timeout_s);
  }
  int Replay(const std::vector<std::string>& args, std::string* out) {
    std::vector<std::string> argv = {kBin + "/daemon/irslam-replay"};
    argv.insert(argv.end(), args.begin(), args.end());
    return RunCommand(argv, out, 120);
  }

  std::string dir_, bus_, socket_;
  Process sim_, daemon_, dump_;
};

TEST_F(RecordReplayTest, AMissionRecordedOnTheBusReplaysOfflineToTheLiveMap) {
  const std::string config = dir_ + "/irslamd.conf";
  // The controller-silence limit: 0.5 s of wall time. A bystander's log has its own
  // receive times, not the daemon's: a stall of one process under load that the
  // other did not see would fault one mission and not the other (docs/replay.md).
  std::ofstream(config) << nlohmann::json{{"controller", {{"timeout_s", std::max(0.5, 0.5 * kScale)}}},
                                          {"state", {{"dir", dir_ + "/state"}}},
                                          {"record", {{"enabled", true}}}}
                               .dump(2);
  ASSERT_TRUE(sim_.Start({kBin + "/sim/irslam-sim", "serve", "--can", bus_, "--world",
                          kSrc + "/tests/worlds/wall_follow_fig14.json", "--time-scale", std::to_string(kScale),
                          "--realtime-priority", testing::kSimRealtimePriority},
                         dir_ + "/sim.log"));
  // irslam-candump beside the daemon: the log an engineer takes with a laptop on the bus.
  ASSERT_TRUE(dump_.Start({kBin + "/daemon/irslam-candump", bus_}, dir_ + "/candump.log"));
  ASSERT_TRUE(daemon_.Start({kBin + "/daemon/irslamd", "--can", bus_, "--socket", socket_, "--time-scale",
                             std::to_string(kScale), "--config", config},
                            dir_ + "/daemon.log"));
  std::string out;
  bool alive = false;
  for (int i = 0; i < 200 && !alive; ++i) {
    if (Ctl({"status", "--json"}, &out, 5) == 0) alive = nlohmann::json::parse(out)["controller"]["alive"] == true;
    if (!alive) std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  ASSERT_TRUE(alive) << out;
  ASSERT_EQ(Ctl({"start"}, &out), 0) << out;
  const double wait_s = 80.0 * 10.0 / kScale;
  ASSERT_EQ(Ctl({"wait", "--state", "done", "--timeout", std::to_string(wait_s)}, &out, wait_s + 10), 0) << out;
  ASSERT_EQ(Ctl({"map", "--out", dir_ + "/live.json"}, &out), 0) << out;
  ASSERT_EQ(Ctl({"status", "--json"}, &out), 0);
  const nlohmann::json status = nlohmann::json::parse(out);
  EXPECT_EQ(status["record"]["dropped"], 0) << status["record"].dump();
  // SIGTERM: the recorder writes what it buffered; candump stops.
  daemon_.Signal(SIGTERM);
  EXPECT_EQ(daemon_.Wait(10), 0);
  dump_.Signal(SIGTERM);
  dump_.Wait(5);
  const nlohmann::json live = ReadJson(dir_ + "/live.json");
  ASSERT_EQ(live["state"], "done");
  ASSERT_GE(live["lines"].size(), 4u);

  // 1. irslamd's own recording: the frames in the order the core saw them, stamped
  //    with the times it was given (to the microsecond).
  ASSERT_EQ(Replay({dir_ + "/state/bus.log", "--config", config, "--map-out", dir_ + "/replay.json", "--stats",
                    dir_ + "/stats.json", "--svg", dir_ + "/replay.svg", "--pgm", dir_ + "/replay.pgm"},
                   &out),
            0)
      << out;
  std::printf("%s", out.c_str());
  const nlohmann::json rec = ReadJson(dir_ + "/replay.json");
  const nlohmann::json stats = ReadJson(dir_ + "/stats.json");
  EXPECT_EQ(rec["state"], "done");
  EXPECT_EQ(stats["starts"], 1);
  EXPECT_EQ(stats["time_scale"], kScale);
  // Lines, the room, the objects and the final pose: the same numbers, bit for bit.
  EXPECT_EQ(rec["lines"], live["lines"]);
  EXPECT_EQ(rec["room"], live["room"]);
  EXPECT_EQ(rec["objects"], live["objects"]);
  EXPECT_EQ(rec["pose"], live["pose"]);
  // Every command the replayed core gave is the one the daemon sent, every state the
  // one it said (the start call is in the recording, at its exact time).
  const uint64_t matched = stats["commands_matched"], differed = stats["commands_differed"];
  EXPECT_GT(matched, 5000u);
  EXPECT_EQ(differed, 0u) << stats.dump();
  EXPECT_EQ(stats["states_differed"], 0);
  EXPECT_TRUE(std::filesystem::exists(dir_ + "/replay.yaml"));
  std::printf("replay of irslamd's recording: %.1f s of robot time at %.0fx real time (%.0fx on CPU time)\n",
              stats["robot_time_s"].get<double>(), stats["speed"].get<double>(), stats["speed_cpu"].get<double>());

  // 2. irslam-candump's log: the bus as a bystander saw it (no header, the origin
  //    is the first frame). The scale is told from the controller's ENCODER stamps
  //    against the log's. (The WHEEL_CMD spacing, used before, a loaded machine
  //    distorts: CI read 9 for 10, 5.7 for 5 in the sanitizer build, 13 for 10 beside
  //    a CI run.)
  ASSERT_EQ(Replay({dir_ + "/candump.log", "--config", config, "--map-out", dir_ + "/replay2.json", "--stats",
                    dir_ + "/stats2.json"},
                   &out),
            0)
      << out;
  std::printf("%s", out.c_str());
  EXPECT_NE(out.find("from the controller's ENCODER stamps"), std::string::npos) << out;
  const nlohmann::json dump = ReadJson(dir_ + "/replay2.json");
  const nlohmann::json stats2 = ReadJson(dir_ + "/stats2.json");
  EXPECT_EQ(stats2["time_scale"], kScale);
  EXPECT_NEAR(stats2["time_scale_measured"].get<double>(), kScale, 0.02 * kScale);
  EXPECT_EQ(dump["state"], "done");
  // It may lack the frames the daemon heard before the bystander started (it starts
  // later than the daemon here), and sees the ticks from outside: the floating-point
  // sums begin elsewhere (differences of 1e-12 seen), and a tick may fall on the
  // other side of a frame. The same model, numbers within a micrometre.
  ExpectNear(dump["lines"], live["lines"], 1e-6, "lines");
  ExpectNear(dump["room"], live["room"], 1e-6, "room");
  ExpectNear(dump["objects"], live["objects"], 1e-6, "objects");
  ExpectNear(dump["pose"], live["pose"], 1e-6, "pose");
  // The mission's states as the daemon's heartbeats said, within a period or so.
  EXPECT_LE(stats2["states_differed"].get<uint64_t>(), stats2["heartbeats"].get<uint64_t>() / 100) << stats2.dump();
}

TEST_F(RecordReplayTest, AMalformedOrTruncatedLogIsRefusedNamingTheLine) {
  std::ofstream(dir_ + "/bad.log") << "(1700000000.000000) vcan0 110#01020304050607\n"
                                   << "(1700000000.001000) vcan0 110#0102\n"
                                   << "(1700000000.002000) vcan0 11";
  std::string out;
  EXPECT_EQ(Replay({dir_ + "/bad.log", "--time-scale", "1"}, &out), 1);
  EXPECT_EQ(out, "irslam-replay: " + dir_ +
                     "/bad.log:3: bad frame (want ID#DATA in hex) (the last line: truncated log?)\n");
  std::ofstream(dir_ + "/back.log") << "(1700000001.000000) vcan0 110#01020304050607\n"
                                    << "(1700000000.000000) vcan0 110#01020304050607\n";
  EXPECT_EQ(Replay({dir_ + "/back.log", "--time-scale", "1"}, &out), 1);
  EXPECT_EQ(out, "irslam-replay: " + dir_ +
                     "/back.log:2: time stamp 1.000000 s before the previous line's (files out of order?)\n");
  EXPECT_EQ(Replay({dir_ + "/none.log"}, &out), 1);
  EXPECT_EQ(out, "irslam-replay: " + dir_ + "/none.log: cannot open\n");
}

}  // namespace
}  // namespace irslam
