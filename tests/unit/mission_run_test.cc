// Wall following through the whole core, in process, on the simulator.
#include <gtest/gtest.h>

#include "robot/robot_core.h"
#include "sim/sim_run.h"

namespace irslam::sim {
namespace {

World LoadWorld(const std::string& name) {
  std::string error;
  auto w = LoadWorldFile(std::string(IRSLAM_SOURCE_DIR) + "/tests/worlds/" + name, &error);
  EXPECT_TRUE(w) << error;
  return *w;
}

// Which of the four walls of a w x h room the true trajectory came within `near` of.
struct Coverage {
  bool bottom = false, right = false, top = false, left = false;
};

class WallFollowRunTest : public ::testing::TestWithParam<uint64_t> {};

TEST_P(WallFollowRunTest, FollowsTheWholePerimeterWithoutTouchingAnything) {
  const World world = LoadWorld("wall_follow_fig14.json");
  robot::CoreOptions o = robot::DefaultCoreOptions();
  Coverage cov;
  std::optional<Pose2> follow_start;
  double closest_return = 1e9;
  double path_since_start = 0;
  Pose2 last{};
  bool have_last = false;
  const double near = 0.6;
  auto on_tick = [&](const InProcessRun& r) {
    const Pose2 p = r.sim->true_pose();
    if (have_last) path_since_start += std::hypot(p.x - last.x, p.y - last.y);
    last = p;
    have_last = true;
    if (!follow_start && r.core->Status(r.t).mission.behaviour == control::FollowMode::kFollow) {
      follow_start = p;
      path_since_start = 0;
    }
    if (!follow_start) return;
    cov.bottom |= p.y < near;
    cov.top |= p.y > 5.5 - near;
    cov.left |= p.x < near;
    cov.right |= p.x > 4.0 - near;
    if (cov.bottom && cov.top && cov.left && cov.right && path_since_start > 8) {
      closest_return = std::min(closest_return, std::hypot(p.x - follow_start->x, p.y - follow_start->y));
    }
  };
  InProcessRun run = RunInProcess(world, o, GetParam(), 300, on_tick);
  ASSERT_TRUE(run.error.empty()) << run.error;
  // One loop, detected by the mission itself, ends wall following.
  EXPECT_EQ(run.core->state(), control::MissionState::kDone);
  EXPECT_LT(run.t, 200);
  EXPECT_EQ(run.sim->collisions(), 0u);
  EXPECT_GT(run.sim->min_clearance(), o.slam.geometry.radius_m + 0.02);
  EXPECT_TRUE(cov.bottom && cov.right && cov.top && cov.left);
  // Back where following began (the perimeter of this room is ~17 m): the loop
  // closes within loop_close_radius_m of the estimated start.
  EXPECT_LT(closest_return, o.mission.loop.loop_close_radius_m + 0.05);
  EXPECT_GT(run.core->slam().distance_m(), 15.0);
}

INSTANTIATE_TEST_SUITE_P(Seeds, WallFollowRunTest, ::testing::Values(1, 2, 3, 4, 5));

}  // namespace
}  // namespace irslam::sim
