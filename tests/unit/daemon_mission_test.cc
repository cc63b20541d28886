// The daemon with a mission: a Daemon and the simulated controller
// (sim/sim_controller.h) on one loopback bus in a temp directory, both driven by
// the same fake clock (20 ms per period), no processes. Issue 12's map-losing
// and save-failure defects, at the level of the daemon's own methods.
#include <unistd.h>

#include <gtest/gtest.h>

#include <boost/asio/io_context.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "daemon/core_json.h"
#include "daemon/irslamd.h"
#include "daemon/map_store.h"
#include "sim/sim_run.h"
#include "tests/testing/process.h"
#include "tests/testing/worlds.h"

namespace irslam {
namespace {

class DaemonMissionTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = testing::MakeTempDir();
    options_.can_iface = "unix:" + dir_ + "/bus";
    options_.socket_path = dir_ + "/irslamd.sock";
    options_.config_path = dir_ + "/irslamd.conf";
    std::ofstream(options_.config_path) << "{}";
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
    sim_ = std::make_unique<sim::SimController>(testing::LoadTestWorld("wall_follow_fig14"),
                                                sim::SimOptionsFrom(settings_.core), 1);
    controller_ = drivers::OpenCanBus(sim_io_, {options_.can_iface, {}}, &error);
    ASSERT_TRUE(controller_) << error;
    controller_->Start([this](const can_frame& f, double) { sim_->HandleFrame(f); });
  }
  // Delivers what is in flight both ways (datagrams arrive synchronously).
  void Pump() {
    for (int i = 0; i < 4; ++i) {
      io_.poll();
      io_.restart();
      sim_io_.poll();
      sim_io_.restart();
    }
  }
  // Runs the controller and the daemon for robot_s seconds of robot time.
  void Run(double robot_s) {
    const int periods = static_cast<int>(robot_s / 0.02 + 0.5);
    for (int i = 0; i < periods; ++i) {
      now_ += std::chrono::milliseconds(20);
      t_ += 0.02;
      std::vector<can_frame> out;
      sim_->AdvanceTo(t_, &out);
      for (const auto& f : out) controller_->Send(f);
      Pump();
      daemon_->Tick();
      Pump();
    }
  }
  // Hands a request to the daemon as this process; *reply is set when it answers
  // (a stop's answer waits for the map writer thread's outcome, posted onto io_).
  void Send(const std::string& method, int id, nlohmann::json* reply,
            nlohmann::json params = nlohmann::json::object()) {
    rpc::Request r;
    r.id = id;
    r.method = method;
    r.params = std::move(params);
    PeerCred self;
    self.uid = ::getuid();
    self.gid = ::getgid();
    self.groups = {::getgid()};
    daemon_->Handle(r, self, [reply](nlohmann::json j) { *reply = std::move(j); });
  }
  // Runs io_ until reply is set. io_ has work only while a write is in flight:
  // the daemon's bus is drained by Tick (polled) and no period timer is armed
  // here, so io_ runs out of work, and stops, when an outcome is delivered; a
  // stopped io_context runs nothing posted later until restarted (run_one
  // returns 0 at once: a spin, not a wait).
  void AwaitReply(const nlohmann::json& reply) {
    while (reply.is_null()) {
      io_.restart();
      ASSERT_NE(io_.run_one(), 0u) << "no reply, and nothing left on io_ that could give one";
    }
  }
  nlohmann::json Call(const std::string& method, nlohmann::json params = nlohmann::json::object()) {
    nlohmann::json reply;
    Send(method, 1, &reply, std::move(params));
    AwaitReply(reply);
    return reply;
  }
  size_t MapLines() { return Call("map")["result"]["lines"].size(); }

  std::string dir_;
  DaemonOptions options_;
  DaemonSettings settings_;  // built-in defaults
  WallTime now_ = WallTime(std::chrono::hours(100));
  double t_ = 0;
  boost::asio::io_context io_, sim_io_;
  std::unique_ptr<Daemon> daemon_;
  std::unique_ptr<sim::SimController> sim_;
  std::unique_ptr<drivers::CanBus> controller_;
};

// Issue 12 B1: SIGHUP after a mission replaced the core: `map` served an empty
// map, and the next stop or SIGTERM saved it over the mission's map.
TEST_F(DaemonMissionTest, AReloadAfterAMissionNeitherServesNorSavesAnEmptyMap) {
  Open();
  Run(1);
  ASSERT_EQ(daemon_->StatusJson()["controller"]["alive"], true);
  const auto started = Call("start");
  ASSERT_TRUE(started.contains("result")) << started;
  Run(15);
  const auto stop = Call("stop");
  ASSERT_TRUE(stop.contains("result")) << stop;
  EXPECT_EQ(stop["result"]["map"], "saved");
  const size_t lines = MapLines();
  ASSERT_GT(lines, 0u);
  std::ofstream(options_.config_path) << R"({"control": {"period_s": 0.01}})";
  daemon_->Reload();
  EXPECT_DOUBLE_EQ(daemon_->StatusJson()["period"]["target"].get<double>(), 0.01);  // idle: at once
  Run(1);
  EXPECT_EQ(MapLines(), lines);
  EXPECT_EQ(daemon_->StatusJson()["lines"], 0);  // the new core's own SLAM starts afresh
  EXPECT_EQ(Call("stop")["result"]["map"], "unchanged");
  EXPECT_EQ(daemon_->Shutdown(), 0);
  std::string error;
  auto saved = MapStore(settings_.state_dir).Load(&error);
  ASSERT_TRUE(saved) << error;
  EXPECT_EQ(saved->seq, 1u);
  EXPECT_EQ(saved->map["lines"].size(), lines);
}

// The odometry calibration a mission learnt is kept in the saved map, carried
// over a reload, and the next run of the daemon starts from it.
TEST_F(DaemonMissionTest, TheOdometryCalibrationIsSavedCarriedOverAndStartedFrom) {
  settings_.core.slam.calibration.enabled = true;
  std::ofstream(options_.config_path) << R"({"slam": {"calibration": {"enabled": true}}})";
  Open();
  Run(1);
  ASSERT_TRUE(Call("start").contains("result"));
  Run(15);
  ASSERT_EQ(Call("stop")["result"]["map"], "saved");
  const nlohmann::json learnt = daemon_->StatusJson()["slam"]["calibration"];
  EXPECT_EQ(learnt["enabled"], true);
  // It moved from the prior (1, 1, 1; sigma 0.01, 0.01, 0.03) while driving.
  EXPECT_LT(learnt["std"][0].get<double>(), 0.01);
  std::string error;
  auto saved = MapStore(settings_.state_dir).Load(&error);
  ASSERT_TRUE(saved) << error;
  ASSERT_TRUE(saved->map.contains("calibration"));
  EXPECT_EQ(saved->map["calibration"]["scale"], learnt["scale"]);
  // A reload: the new core starts from what the old one learnt.
  std::ofstream(options_.config_path)
      << R"({"control": {"period_s": 0.01}, "slam": {"calibration": {"enabled": true}}})";
  daemon_->Reload();
  const double resume = slam::CalibrationOptions{}.resume_sigma;
  nlohmann::json now = daemon_->StatusJson()["slam"]["calibration"];
  EXPECT_EQ(now["scale"], learnt["scale"]);
  EXPECT_NEAR(now["std"][0].get<double>(), std::hypot(learnt["std"][0].get<double>(), resume), 1e-12);
  EXPECT_EQ(daemon_->Shutdown(), 0);
  // The next run of the daemon: from the saved map's.
  daemon_.reset();
  Open();
  now = daemon_->StatusJson()["slam"]["calibration"];
  EXPECT_EQ(now["scale"], saved->map["calibration"]["scale"]);
  EXPECT_NEAR(now["std"][2].get<double>(),
              std::hypot(saved->map["calibration"]["std"][2].get<double>(), resume), 1e-12);
}

// A config that comes during a mission applies when it ends (the mission's map
// kept and served); the next start, on the new core, works at once.
TEST_F(DaemonMissionTest, AConfigDuringAMissionAppliesWhenItEndsAndTheMapIsKept) {
  Open();
  Run(1);
  ASSERT_TRUE(Call("start").contains("result"));
  Run(10);
  std::ofstream(options_.config_path) << R"({"control": {"period_s": 0.01}})";
  daemon_->Reload();
  EXPECT_EQ(daemon_->StatusJson()["config_pending"], true);
  EXPECT_DOUBLE_EQ(daemon_->StatusJson()["period"]["target"].get<double>(), 0.02);
  Run(2);
  const size_t lines = MapLines();
  ASSERT_GT(lines, 0u);
  ASSERT_TRUE(Call("stop").contains("result"));
  Run(1);
  EXPECT_EQ(daemon_->StatusJson()["config_pending"], false);
  EXPECT_DOUBLE_EQ(daemon_->StatusJson()["period"]["target"].get<double>(), 0.01);
  EXPECT_GE(MapLines(), lines);
  const auto start = Call("start");
  EXPECT_TRUE(start.contains("result")) << start;
  EXPECT_EQ(daemon_->StatusJson()["state"], "wall_follow");
}

// Issue 12 B2: a failed save still answered stop with success, and SIGTERM exited 0.
TEST_F(DaemonMissionTest, AFailedSaveMakesStopAnErrorAndShutdownNonZero) {
  std::ofstream(dir_ + "/plain-file") << "x";
  settings_.state_dir = dir_ + "/plain-file/state";  // cannot be created, even by root
  Open();
  Run(1);
  ASSERT_TRUE(Call("start").contains("result"));
  Run(5);
  ::testing::internal::CaptureStderr();
  const auto stop = Call("stop");
  ::testing::internal::GetCapturedStderr();
  ASSERT_TRUE(stop.contains("error")) << stop;
  EXPECT_EQ(stop["error"]["code"], rpc::kMapNotSaved);
  EXPECT_EQ(stop["error"]["message"].get<std::string>().rfind(
                "stopped, but the map was not saved: map: cannot create " + settings_.state_dir + ": ", 0),
            0u)
      << stop;
  const auto s = daemon_->StatusJson();
  EXPECT_EQ(s["state"], "idle");  // the wheels stopped all the same
  EXPECT_EQ(s["map_store"]["save_errors"], 1);
  EXPECT_NE(s["map_store"]["error"], "");
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(daemon_->Shutdown(), 1);
  const std::string log = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(log.find("the final map save failed: exit status 1"), std::string::npos) << log;
}

// Issue 15: the map is written on the writer thread. The stop's reply waits for
// the outcome, the control loop does not: Handle returns at once with the
// snapshot handed over, ticks go on, and the reply comes when the writer's
// outcome is delivered on the loop.
TEST_F(DaemonMissionTest, StopHandsTheMapToTheWriterAndRepliesWhenItIsWritten) {
  Open();
  Run(1);
  ASSERT_TRUE(Call("start").contains("result"));
  Run(15);
  nlohmann::json reply;
  Send("stop", 9, &reply);
  EXPECT_TRUE(reply.is_null());  // not answered yet: the file is being written
  EXPECT_TRUE(daemon_->maps().writing());
  auto s = daemon_->StatusJson()["map_store"];
  EXPECT_EQ(s["writing"], true);
  EXPECT_EQ(s["last_result"], "queued");
  EXPECT_EQ(s["saves"], 0);
  daemon_->Tick();  // the loop goes on meanwhile
  EXPECT_EQ(daemon_->StatusJson()["state"], "idle");
  AwaitReply(reply);
  ASSERT_TRUE(reply.contains("result")) << reply;
  EXPECT_EQ(reply["id"], 9);
  EXPECT_EQ(reply["result"]["map"], "saved");
  s = daemon_->StatusJson()["map_store"];
  EXPECT_EQ(s["writing"], false);
  EXPECT_EQ(s["saves"], 1);
  EXPECT_EQ(s["seq"], 1);
  EXPECT_EQ(s["last_result"], "saved");
  std::string error;
  auto saved = MapStore(settings_.state_dir).Load(&error);
  ASSERT_TRUE(saved) << error;
  EXPECT_EQ(saved->reason, "stop");
  EXPECT_EQ(saved->map["lines"].size(), MapLines());
  // A second stop with the same map: the writer finds it unchanged and writes nothing.
  EXPECT_EQ(Call("stop")["result"]["map"], "unchanged");
  EXPECT_EQ(daemon_->Shutdown(), 0);
}

// SIGTERM while a write is in flight: the shutdown waits for it (and answers the
// stop waiting for it), then writes the final map itself.
TEST_F(DaemonMissionTest, ShutdownWaitsForTheWriteInFlightAndAnswersTheWaitingStop) {
  Open();
  Run(1);
  ASSERT_TRUE(Call("start").contains("result"));
  Run(12);
  nlohmann::json reply;
  Send("stop", 3, &reply);
  ASSERT_TRUE(reply.is_null());
  EXPECT_EQ(daemon_->Shutdown(), 0);
  ASSERT_TRUE(reply.contains("result")) << reply;
  EXPECT_EQ(reply["result"]["map"], "saved");
  const auto s = daemon_->StatusJson()["map_store"];
  EXPECT_EQ(s["saves"], 1);  // the final save found the same map: unchanged
  EXPECT_EQ(s["writing"], false);
}

// Issue 15 (c): a 100 ms host stall tripped the 0.1 s encoder timeout. A loop
// that was itself stalled, with the controller's frames queued unread, must not
// blame the controller; 150 ms of true silence while the loop keeps its period
// must still fault.
TEST_F(DaemonMissionTest, ALoopStallWithFramesQueuedIsNoControllerLossButSilenceIs) {
  Open();
  Run(1);
  ASSERT_TRUE(Call("start").contains("result"));
  Run(2);
  ASSERT_EQ(daemon_->StatusJson()["state"], "wall_follow");
  // 150 ms in which the loop did not run; the controller went on sending.
  for (int i = 0; i < 75; ++i) {
    now_ += std::chrono::milliseconds(2);
    t_ += 0.002;
    std::vector<can_frame> out;
    sim_->AdvanceTo(t_, &out);
    for (const auto& f : out) controller_->Send(f);
  }
  sim_io_.poll();
  sim_io_.restart();
  daemon_->Tick();  // late, before the daemon has read what is queued
  auto s = daemon_->StatusJson();
  EXPECT_EQ(s["state"], "wall_follow") << s["reason"];
  EXPECT_EQ(s["period"]["loop_stalls"], 1);
  Run(0.2);
  s = daemon_->StatusJson();
  EXPECT_EQ(s["state"], "wall_follow") << s["reason"];
  EXPECT_EQ(s["controller"]["alive"], true);
  // 160 ms of silence, the loop on its period: the controller is lost.
  for (int i = 0; i < 8; ++i) {
    now_ += std::chrono::milliseconds(20);
    Pump();
    daemon_->Tick();
  }
  s = daemon_->StatusJson();
  EXPECT_EQ(s["state"], "fault");
  EXPECT_EQ(s["reason"], "controller lost: encoder frames timed out");
  EXPECT_EQ(s["period"]["loop_stalls"], 1);
}

// The stall grace is one tick: a loop that stays slow (every tick late) with a
// silent controller still faults, at the second late tick.
TEST_F(DaemonMissionTest, AStallGraceLastsOneTickSoASlowLoopStillFindsADeadController) {
  Open();
  Run(1);
  ASSERT_TRUE(Call("start").contains("result"));
  Run(2);
  ASSERT_EQ(daemon_->StatusJson()["state"], "wall_follow");
  now_ += std::chrono::milliseconds(150);  // no frames: the controller is silent
  Pump();
  daemon_->Tick();
  EXPECT_EQ(daemon_->StatusJson()["state"], "wall_follow");  // stalled: not judged
  now_ += std::chrono::milliseconds(150);
  Pump();
  daemon_->Tick();  // late again, but the grace was had
  const auto s = daemon_->StatusJson();
  EXPECT_EQ(s["state"], "fault");
  EXPECT_EQ(s["reason"], "controller lost: encoder frames timed out");
  EXPECT_EQ(s["period"]["loop_stalls"], 1);
}

// Issue 14: the map the next start relocalises in.
nlohmann::json GoldenMap() {
  std::ifstream in(std::string(IRSLAM_SOURCE_DIR) + "/tests/unit/testdata/core_map.golden.json");
  std::stringstream ss;
  ss << in.rdbuf();
  return nlohmann::json::parse(ss.str());
}

void WriteStateMap(const std::string& dir, const nlohmann::json& map) {
  std::string error;
  ASSERT_TRUE(MapStore(dir).Save({4, "stop", map}, &error)) << error;
}

// The saved map on disk goes to the core at start (and to the core a reload
// makes); start {"fresh": true} forgets it; a mission stopped before it modelled
// the room leaves its map saved but not one to relocalise in.
TEST_F(DaemonMissionTest, TheSavedMapGoesToTheCoreAndFreshForgetsIt) {
  const nlohmann::json golden = GoldenMap();
  WriteStateMap(settings_.state_dir, golden);
  Open();
  ASSERT_TRUE(daemon_->core().saved_map());
  EXPECT_EQ(ToJson(*daemon_->core().saved_map()), golden);  // all of it, exactly
  std::ofstream(options_.config_path) << R"({"control": {"period_s": 0.02}})";
  daemon_->Reload();
  ASSERT_TRUE(daemon_->core().saved_map());  // the new core has it too
  EXPECT_EQ(daemon_->core().saved_map()->lines.size(), golden["lines"].size());
  Run(1);
  // A start that is rejected forgets nothing.
  const auto bad = Call("start", {{"fresh", true}, {"mode", "mop"}});
  ASSERT_TRUE(bad.contains("error")) << bad;
  EXPECT_TRUE(daemon_->core().saved_map());
  const auto started = Call("start", {{"fresh", true}});
  ASSERT_TRUE(started.contains("result")) << started;
  EXPECT_FALSE(daemon_->core().saved_map());
  EXPECT_EQ(daemon_->core().last_start(), robot::RobotCore::StartKind::kNewMap);
  EXPECT_FALSE(daemon_->saved_map());
  Run(10);
  ASSERT_EQ(Call("stop")["result"]["map"], "saved");
  Run(0.1);
  // 10 s of wall following: saved (the file is replaced) but no room model.
  EXPECT_FALSE(daemon_->core().saved_map());
  std::string error;
  auto saved = MapStore(settings_.state_dir).Load(&error);
  ASSERT_TRUE(saved) << error;
  EXPECT_EQ(saved->seq, 5u);
  EXPECT_TRUE(saved->map["room"]["box"].is_null());
  EXPECT_EQ(daemon_->Shutdown(), 0);
  daemon_.reset();
  Open();
  EXPECT_FALSE(daemon_->core().saved_map());
  EXPECT_TRUE(daemon_->maps().stored());  // still served as the saved map
}

// A finished mission's map is the next start's saved map (no restart needed).
TEST_F(DaemonMissionTest, AFinishedMissionsMapIsTheNextStartsSavedMap) {
  Open();
  Run(1);
  ASSERT_TRUE(Call("start").contains("result"));
  EXPECT_EQ(daemon_->core().last_start(), robot::RobotCore::StartKind::kNewMap);
  for (int i = 0; i < 90 && daemon_->StatusJson()["state"] != "done"; ++i) Run(10);
  ASSERT_EQ(daemon_->StatusJson()["state"], "done");
  Run(0.1);
  ASSERT_TRUE(daemon_->core().saved_map());
  EXPECT_TRUE(daemon_->core().saved_map()->room.box);
  const nlohmann::json served = Call("map")["result"];
  EXPECT_EQ(ToJson(*daemon_->core().saved_map())["objects"], served["objects"]);
  EXPECT_EQ(daemon_->core().saved_map()->lines.size(), served["lines"].size());
  // The next start goes on in the live map (a saved map is there too, and the
  // log line once said "in the saved map" here).
  ASSERT_TRUE(Call("start").contains("result"));
  EXPECT_EQ(daemon_->core().last_start(), robot::RobotCore::StartKind::kLiveMap);
  EXPECT_EQ(daemon_->StatusJson()["state"], "model");
}

// A daemon started with a saved map relocalises in it at the first start.
TEST_F(DaemonMissionTest, TheFirstStartWithASavedMapRelocalisesInIt) {
  WriteStateMap(settings_.state_dir, GoldenMap());
  Open();
  Run(1);
  EXPECT_EQ(daemon_->core().last_start(), robot::RobotCore::StartKind::kNone);
  ASSERT_TRUE(Call("start").contains("result"));
  EXPECT_EQ(daemon_->core().last_start(), robot::RobotCore::StartKind::kSavedMap);
  EXPECT_EQ(daemon_->StatusJson()["state"], "relocalize");
}

// A map file that checks out (checksum, types) but does not make a map (two
// lines with one id) is set aside; the daemon starts without it.
TEST_F(DaemonMissionTest, ASavedMapThatDoesNotParseIsSetAsideAndTheDaemonStarts) {
  nlohmann::json bad = GoldenMap();
  bad["lines"][1]["id"] = bad["lines"][0]["id"];
  WriteStateMap(settings_.state_dir, bad);
  ::testing::internal::CaptureStderr();
  Open();
  const std::string log = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(log.find("<3>irslamd: map: " + settings_.state_dir + "/map.json: map.lines[1].id: line 1 is in the map "
                     "twice; kept aside as " + settings_.state_dir + "/map.json.bad, not used\n"),
            std::string::npos)
      << log;
  EXPECT_TRUE(std::filesystem::exists(settings_.state_dir + "/map.json.bad"));
  EXPECT_FALSE(std::filesystem::exists(settings_.state_dir + "/map.json"));
  EXPECT_FALSE(daemon_->core().saved_map());
  EXPECT_FALSE(daemon_->maps().stored());
  EXPECT_EQ(daemon_->StatusJson()["map_store"]["saved_map"], false);
  Run(1);
  ASSERT_TRUE(Call("start").contains("result"));
  Run(1);
  EXPECT_EQ(daemon_->StatusJson()["state"], "wall_follow");
}

}  // namespace
}  // namespace irslam
