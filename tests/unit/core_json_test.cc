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

#include "robot/robot_core.h"
#include "sim/sim_run.h"

namespace irslam {
namespace {

std::string StatusText(const robot::RobotCore& core, double t) { return core.Status(t).dump(1); }
std::string MapText(const robot::RobotCore& core) { return core.Map().dump(1); }

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

}  // namespace
}  // namespace irslam
