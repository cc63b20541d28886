// The JSON views of RobotCore's status and map (daemon/core_json.h): the API's
// `status` and `map` and the map files (contracts §4, §6) must not change by a
// byte. The golden files were written by the JSON building that lived inside
// RobotCore before the typed structs; a mission with faults (so every counter
// moves) is replayed and its views compared with them.
//
// After a deliberate behaviour change, regenerate them with
//   IRSLAM_UPDATE_GOLDEN=1 build/tests/daemon_test --gtest_filter='CoreJson*'
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "daemon/core_json.h"
#include "daemon/map_store.h"
#include "daemon/map_validate.h"
#include "robot/robot_core.h"
#include "sim/sim_run.h"

namespace irslam {
namespace {

std::string StatusText(const robot::RobotCore& core, double t) { return ToJson(core.Status(t)).dump(1); }
std::string MapText(const robot::RobotCore& core) { return ToJson(core.Map()).dump(1); }

std::string GoldenPath(const std::string& name) {
  return std::string(IRSLAM_SOURCE_DIR) + "/tests/unit/testdata/" + name;
}

// Compares text with the golden file `name` (or rewrites it on request).
void ExpectGolden(const std::string& name, const std::string& text) {
  const std::string path = GoldenPath(name);
  if (std::getenv("IRSLAM_UPDATE_GOLDEN")) {
    std::ofstream(path) << text;
    return;
  }
  std::ifstream in(path);
  ASSERT_TRUE(in) << path;
  std::stringstream golden;
  golden << in.rdbuf();
  if (golden.str() != text) {
    const std::string actual = std::string(IRSLAM_BINARY_DIR) + "/" + name + ".actual";
    std::ofstream(actual) << text;
    ADD_FAILURE() << name << " differs from the golden file: diff " << path << " " << actual;
  }
}

TEST(CoreJsonTest, StatusAndMapOfAMissionWithFaultsMatchTheGoldenFiles) {
  std::string error;
  auto world = sim::LoadWorldFile(std::string(IRSLAM_SOURCE_DIR) + "/tests/worlds/fig14.json", &error);
  ASSERT_TRUE(world) << error;
  // Corrupted, duplicated and reordered frames and a stuck sensor: the frame,
  // IR-plausibility and bumper counters all move.
  auto faults = sim::ParseFaultSpec("corrupt:p=0.02,duplicate:p=0.01,reorder:p=0.01,stuck_ir:sensor=2:at=20:for=4",
                                    &error);
  ASSERT_TRUE(faults) << error;
  std::string statuses;
  int ticks = 0;
  const auto on_tick = [&](const sim::InProcessRun& r) {
    if (++ticks % 1500 == 0) statuses += StatusText(*r.core, r.t) + "\n";  // every 30 s
  };
  const sim::InProcessRun run =
      sim::RunInProcess(*world, robot::DefaultCoreOptions(), 3, 900, on_tick, &*faults);
  ASSERT_TRUE(run.error.empty()) << run.error;
  statuses += StatusText(*run.core, run.t + 0.01) + "\n";
  ExpectGolden("core_status.golden.json", statuses);
  ExpectGolden("core_map.golden.json", MapText(*run.core) + "\n");
}

TEST(CoreJsonTest, AStatusBeforeAnyFrameHasNullRangesAndNoController) {
  robot::CoreStatus s;
  s.robot_time = 1.5;
  s.safety.estop = true;
  s.safety.estop_latched = true;
  s.mission.reason = "emergency stop pressed";
  const nlohmann::json j = ToJson(s);
  EXPECT_EQ(j["state"], "idle");
  EXPECT_EQ(j["behaviour"], "find_wall");
  EXPECT_EQ(j["reason"], "emergency stop pressed");
  EXPECT_EQ(j["ir_ranges"].dump(), "[null,null,null,null,null,null,null]");
  EXPECT_EQ(j["ir_adc"].dump(), "[0,0,0,0,0,0,0]");
  EXPECT_EQ(j["controller"].dump(), R"({"alive":false,"battery":0.0,"bumpers":0,"faults":0,"state":-1})");
  EXPECT_EQ(j["safety"].dump(),
            R"({"bumper_left":false,"bumper_right":false,"estop":true,"estop_latched":true,"motor_enable":false})");
  EXPECT_EQ(j["robot_time"].dump(), "1.5");
  EXPECT_EQ(j["frames"].size(), 19u);
  s.controller = {true, proto::ControllerStatus{proto::ControllerState::kReady, 4, kBumperRight, 14.5, 0, 0}};
  s.ir.scan.range_m[2] = 0.25;
  EXPECT_EQ(ToJson(s)["controller"].dump(), R"({"alive":true,"battery":14.5,"bumpers":2,"faults":4,"state":1})");
  EXPECT_EQ(ToJson(s)["ir_ranges"].dump(), "[null,null,0.25,null,null,null,null]");
}

TEST(CoreJsonTest, AMapWithoutARoomBoxAndAnObjectWithANote) {
  robot::MapSnapshot m;
  m.state = control::MissionState::kDone;
  m.room.walls[3] = {7, 11};
  control::ObjectModel o;
  o.id = 2;
  o.kind = control::ObjectKind::kWallContact;
  o.lines = {8, 9, 10};
  o.box = {1, 2, 3, 4.5};
  o.note = "P1 unreachable";
  m.objects = {o, o};
  m.objects[1].note.clear();
  m.trajectory = {{0.5, {1, 2, 0.25}}};
  const nlohmann::json j = ToJson(m);
  EXPECT_EQ(j["frame"], "map");
  EXPECT_EQ(j["state"], "done");
  EXPECT_EQ(j["room"].dump(), R"({"box":null,"walls":{"bottom":[],"left":[7,11],"right":[],"top":[]}})");
  EXPECT_EQ(j["objects"][0].dump(),
            R"({"box":[1.0,2.0,3.0,4.5],"complete":false,"id":2,"kind":"wall_contact","lines":[8,9,10],)"
            R"("note":"P1 unreachable","open_ends":0})");
  EXPECT_FALSE(j["objects"][1].contains("note"));
  EXPECT_EQ(j["trajectory"].dump(), "[[0.5,1.0,2.0,0.25]]");
  EXPECT_EQ(j["pose_cov"].dump(), "[[0.0,0.0,0.0],[0.0,0.0,0.0],[0.0,0.0,0.0]]");
  EXPECT_TRUE(j["lines"].is_array());
  EXPECT_TRUE(j["lines"].empty());
}

// The odometry calibration goes into the map and comes back out of a saved
// map file (the next mission starts from it); maps without it still load.
TEST(CoreJsonTest, TheMapKeepsTheOdometryCalibrationThroughTheMapFile) {
  robot::MapSnapshot m;
  m.calibration = slam::CalibrationEstimate{{1.0043, 0.9941, 1.0178}, Eigen::Vector3d(4e-3, 4e-3, 2e-3), 3e-4};
  const nlohmann::json j = ToJson(m);
  EXPECT_EQ(j["calibration"]["scale"].dump(), "[1.0043,0.9941,1.0178]");
  EXPECT_EQ(j["calibration"]["std"].dump(), "[0.004,0.004,0.002]");
  EXPECT_EQ(j["calibration"]["ratio"].get<double>(), 0.9941 / 1.0043);
  EXPECT_EQ(j["calibration"]["ratio_std"].get<double>(), 3e-4);
  std::string error;
  EXPECT_TRUE(ValidateMapBody(j, &error)) << error;
  const std::string text = EncodeMapFile({3, "stop", j});
  const auto back = DecodeMapFile(text, &error);
  ASSERT_TRUE(back) << error;
  const auto c = CalibrationFromMap(back->map);
  ASSERT_TRUE(c);
  EXPECT_EQ(c->value.left, 1.0043);  // exactly: the numbers survive the file
  EXPECT_EQ(c->value.right, 0.9941);
  EXPECT_EQ(c->value.base, 1.0178);
  EXPECT_EQ(c->sigma, Eigen::Vector3d(4e-3, 4e-3, 2e-3));
  EXPECT_EQ(c->ratio_sigma, 3e-4);
  // A map without it (an older file, or calibration disabled): valid, none.
  m.calibration.reset();
  const nlohmann::json old = ToJson(m);
  EXPECT_FALSE(old.contains("calibration"));
  EXPECT_TRUE(ValidateMapBody(old, &error)) << error;
  EXPECT_FALSE(CalibrationFromMap(old));
  // Wrong types are a one-line error; values out of bounds are not used.
  nlohmann::json bad = j;
  bad["calibration"]["scale"] = {1.0, 1.0};
  EXPECT_FALSE(ValidateMapBody(bad, &error));
  EXPECT_EQ(error, "map.calibration.scale: not an array of 3 numbers");
  EXPECT_FALSE(CalibrationFromMap(bad));
  bad = j;
  bad["calibration"]["scale"][2] = 2.5;
  EXPECT_TRUE(ValidateMapBody(bad, &error)) << error;
  EXPECT_FALSE(CalibrationFromMap(bad));
}

// A live core: its map and status carry the calibration it estimates.
TEST(CoreJsonTest, StatusAndMapReportTheCalibration) {
  robot::CoreOptions o = robot::DefaultCoreOptions();
  o.slam.calibration.enabled = true;
  o.slam.initial_calibration = slam::CalibrationEstimate{{1.01, 0.99, 1.02}, Eigen::Vector3d(1e-3, 1e-3, 2e-3), 0};
  const robot::RobotCore core(o);
  const nlohmann::json status = ToJson(core.Status(0));
  EXPECT_EQ(status["slam"]["calibration"]["enabled"], true);
  EXPECT_EQ(status["slam"]["calibration"]["scale"].dump(), "[1.01,0.99,1.02]");
  EXPECT_NEAR(status["slam"]["calibration"]["ratio"].get<double>(), 0.99 / 1.01, 1e-15);
  const auto c = CalibrationFromMap(ToJson(core.Map()));
  ASSERT_TRUE(c);
  EXPECT_EQ(c->value.right, 0.99);
  o.slam.calibration.enabled = false;
  EXPECT_FALSE(ToJson(robot::RobotCore(o).Map()).contains("calibration"));
}

}  // namespace
}  // namespace irslam
