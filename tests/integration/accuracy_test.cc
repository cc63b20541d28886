// The SLAM accuracy targets of the paper's scenarios, asserted (the numbers are
// tabulated in docs/accuracy.md by irslam-report).
#include <gtest/gtest.h>

#include "robot/robot_core.h"
#include "sim/sim_run.h"
#include "tests/testing/worlds.h"
#include "tests/tools/metrics.h"

namespace irslam {
namespace {

sim::World Load(const std::string& name) { return testing::LoadTestWorld(name); }

std::vector<TimedPose> Truth(const nlohmann::json& arr) {
  std::vector<TimedPose> out;
  for (const auto& p : arr) out.push_back({p[0], {p[1], p[2], p[3]}});
  return out;
}

class Fig14AccuracyTest : public ::testing::TestWithParam<uint64_t> {};

TEST_P(Fig14AccuracyTest, OneLoopMeetsThePoseAndWallTargets) {
  const sim::World world = Load("fig14");
  robot::CoreOptions o = robot::DefaultCoreOptions();
  o.mission.explore = false;  // judged after the wall-following loop
  sim::InProcessRun run = sim::RunInProcess(world, o, GetParam(), 400);
  ASSERT_EQ(run.core->state(), control::MissionState::kDone);
  const auto truth = run.sim->Truth();
  const auto est = metrics::ToWorld(run.core->slam().trajectory(), world.start);
  const auto e = metrics::ComparePoses(est, Truth(truth["trajectory"]));
  const auto odo = metrics::ComparePoses(Truth(truth["odometry"]), Truth(truth["trajectory"]));
  EXPECT_LE(e.final_position_m, 0.05);
  EXPECT_LE(e.final_heading_rad, 2 * M_PI / 180);
  EXPECT_LT(e.rms_position_m, odo.rms_position_m / 2);  // at least twice better than odometry
  // Map shape: after the best rigid alignment, every wall line within 3 cm and 1 deg.
  const auto& lines = run.core->slam().lines();
  const Pose2 fixed = metrics::CorrectStart(world.start, metrics::BestAlignment(lines, world.start, world));
  int unmatched = 0, walls = 0;
  for (const auto& l : metrics::CompareLines(lines, fixed, world, &unmatched)) {
    if (!l.wall) continue;
    ++walls;
    EXPECT_LE(l.distance_m, 0.03) << "line " << l.id;
    EXPECT_LE(l.angle_rad, 1 * M_PI / 180) << "line " << l.id;
  }
  EXPECT_GE(walls, 4);
  EXPECT_EQ(unmatched, 0);
}

INSTANTIATE_TEST_SUITE_P(Seeds, Fig14AccuracyTest, ::testing::Values(1, 2, 3, 4, 5));

TEST(FiveLoopsTest, CorrectedErrorDoesNotGrowWhileOdometryDrifts) {
  const sim::World world = Load("fig18");
  robot::CoreOptions o = robot::DefaultCoreOptions();
  o.mission.wall_follow_loops = 5;
  o.mission.explore = false;
  sim::InProcessRun run = sim::RunInProcess(world, o, 1, 1200);
  ASSERT_EQ(run.core->state(), control::MissionState::kDone);
  const auto& loops = run.core->loop_times();
  ASSERT_EQ(loops.size(), 5u);
  const auto truth = run.sim->Truth();
  const auto tr = Truth(truth["trajectory"]), od = Truth(truth["odometry"]);
  const auto est = metrics::ToWorld(run.core->slam().trajectory(), world.start);
  std::vector<double> se, oe;
  for (double t : loops) {
    se.push_back(metrics::PositionErrorAt(est, tr, t));
    oe.push_back(metrics::PositionErrorAt(od, tr, t));
  }
  for (size_t i = 1; i < loops.size(); ++i) {
    EXPECT_GT(oe[i], oe[i - 1]) << "odometry should keep drifting, loop " << i;
    EXPECT_LT(se[i], 0.06) << "loop " << i;
  }
  EXPECT_LT(se.back(), se.front() + 0.03);
  EXPECT_GT(oe.back(), 3 * oe.front());
}

TEST(ConstraintsTest, ConstrainedEkfBeatsThePlainOneAtTheCorner) {
  const sim::World world = Load("fig17");
  robot::CoreOptions on = robot::DefaultCoreOptions();
  on.mission.explore = false;
  robot::CoreOptions off = on;
  off.slam.association.use_constraints = false;
  double err_on = 0, err_off = 0;
  for (uint64_t seed = 1; seed <= 3; ++seed) {
    for (bool use : {true, false}) {
      sim::InProcessRun run = sim::RunInProcess(world, use ? on : off, seed, 400);
      const auto est = metrics::ToWorld(run.core->slam().trajectory(), world.start);
      const auto e = metrics::ComparePoses(est, Truth(run.sim->Truth()["trajectory"]));
      (use ? err_on : err_off) += e.rms_position_m;
    }
  }
  EXPECT_LT(err_on, 0.5 * err_off);
}

}  // namespace
}  // namespace irslam
