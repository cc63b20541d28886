// Wall following through the whole core, in process, on the simulator.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <optional>

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

// Seeds 1-10. Every run follows the whole perimeter once without touching
// anything and closes its loop where following began; the mission (one wall
// box, modelled after the loop) is done within 200 s in most.
TEST(WallFollowRunTest, FollowsTheWholePerimeterWithoutTouchingAnything) {
  const World world = LoadWorld("wall_follow_fig14.json");
  const robot::CoreOptions o = robot::DefaultCoreOptions();
  int done_in_time = 0;
  for (uint64_t seed = 1; seed <= 10; ++seed) {
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
    InProcessRun run = RunInProcess(world, o, seed, 300, on_tick);
    ASSERT_TRUE(run.error.empty()) << run.error;
    const bool done = run.core->state() == control::MissionState::kDone && run.t < 200;
    std::printf("seed %llu: %s at %.1f s, min clearance %.4f m\n", static_cast<unsigned long long>(seed),
                done ? "done" : control::ToString(run.core->state()), run.t, run.sim->min_clearance());
    done_in_time += done;
    EXPECT_EQ(run.sim->collisions(), 0u) << seed;
    EXPECT_GT(run.sim->min_clearance(), o.slam.geometry.radius_m + 0.015) << seed;
    EXPECT_TRUE(cov.bottom && cov.right && cov.top && cov.left) << seed;
    // Back where following began (the perimeter of this room is ~17 m): the loop
    // closes within loop_close_radius_m of the estimated start.
    EXPECT_LT(closest_return, o.mission.loop.loop_close_radius_m + 0.05) << seed;
    EXPECT_GT(run.core->slam().distance_m(), 15.0) << seed;
  }
  // One loop, detected by the mission itself, ends wall following; then the
  // box is modelled. Measured: 10 of 10 before 2026-12-07; since the SLAM
  // trusts the odometry more, 8 (seed 2 maps half of the box's face, leaves it
  // two wall-contact pieces and contour-follows one round the room until its
  // 170 s limit, 1.5 mm nearer a wall than r + 2 cm; seed 6 is done at 207 s;
  // seeds 1-30: 28, 30 before; over 200 generated nominal rooms done 98.0 ->
  // 97.0 %, complete 71.5 -> 74.2 %: docs/robustness.md).
  EXPECT_GE(done_in_time, 8);
}

}  // namespace
}  // namespace irslam::sim
