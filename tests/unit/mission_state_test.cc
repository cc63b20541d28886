// Mission transitions that need no world: start, stop, fault, watchdogs.
#include <gtest/gtest.h>

#include "control/mission.h"
#include "robot/robot_core.h"

namespace irslam::control {
namespace {

struct Rig {
  robot::CoreOptions o = robot::DefaultCoreOptions();
  slam::Slam slam{o.slam};
  Mission Make() const { return Mission(o.mission, o.wall, o.explore, o.model, o.slam); }
};

TEST(MissionStateTest, StartStopAndFault) {
  Rig r;
  Mission m = r.Make();
  std::string why;
  EXPECT_EQ(m.state(), MissionState::kIdle);
  ASSERT_TRUE(m.Start(0, &why));
  EXPECT_EQ(m.state(), MissionState::kWallFollow);
  EXPECT_FALSE(m.Start(1, &why));
  EXPECT_EQ(why, "already running (wall_follow)");
  m.SetFault(2, "controller lost");
  EXPECT_EQ(m.state(), MissionState::kFault);
  EXPECT_FALSE(m.Step(2.1, r.slam, RangeScan{}, 0).enable);  // no driving in fault
  EXPECT_FALSE(m.Start(3, &why));
  EXPECT_EQ(why, "cannot start while in fault: controller lost");
  m.ClearFault(4);
  EXPECT_EQ(m.state(), MissionState::kWallFollow);
  EXPECT_EQ(m.reason(), "resumed after: controller lost");
  EXPECT_TRUE(m.Step(4.1, r.slam, RangeScan{}, 0).enable);
  m.Stop(5);
  EXPECT_EQ(m.state(), MissionState::kIdle);
  EXPECT_EQ(m.reason(), "stopped by request");
}

TEST(MissionStateTest, NoProgressEndsTheMission) {
  Rig r;  // the robot never moves: the odometric distance stays 0
  Mission m = r.Make();
  std::string why;
  ASSERT_TRUE(m.Start(0, &why));
  double ended = -1;
  for (double t = 0; t < 200 && ended < 0; t += 0.5) {
    m.Step(t, r.slam, RangeScan{}, 0);
    if (m.state() != MissionState::kWallFollow) ended = t;
  }
  EXPECT_DOUBLE_EQ(ended, 120.5);
  EXPECT_EQ(m.state(), MissionState::kIdle);
  EXPECT_EQ(m.reason(), "no progress for 120 s");
}

TEST(MissionStateTest, TimeLimitEndsTheMission) {
  Rig r;
  r.o.mission.max_time_s = 10;
  Mission m = r.Make();
  std::string why;
  ASSERT_TRUE(m.Start(100, &why));
  m.Step(110, r.slam, RangeScan{}, 0);
  EXPECT_EQ(m.state(), MissionState::kWallFollow);
  EXPECT_FALSE(m.Step(110.5, r.slam, RangeScan{}, 0).enable);
  EXPECT_EQ(m.state(), MissionState::kIdle);
  EXPECT_EQ(m.reason(), "mission time limit reached");
}

TEST(MissionStateTest, TheCommandIsAccelerationLimited) {
  Rig r;
  Mission m = r.Make();
  std::string why;
  ASSERT_TRUE(m.Start(0, &why));
  // Finding a wall: cruise straight ahead, reached at max_accel_mps2 (0.8) per
  // step of at most max_step_s (0.1 s): 0.08 m/s per wheel per step.
  const WheelCommand c1 = m.Step(1.0, r.slam, RangeScan{}, 0);
  EXPECT_NEAR(c1.left_mps, 0.08, 1e-12);
  EXPECT_NEAR(c1.right_mps, 0.08, 1e-12);
  const WheelCommand c2 = m.Step(1.05, r.slam, RangeScan{}, 0);
  EXPECT_NEAR(c2.left_mps, 0.12, 1e-12);
}

}  // namespace
}  // namespace irslam::control
