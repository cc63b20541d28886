// GoTo: planning, pure pursuit, escape from contacts and giving the goal up,
// with a robot that does not move (the SLAM state stays at the origin).
#include "control/go_to.h"

#include <gtest/gtest.h>

#include "robot/robot_core.h"

namespace irslam::control {
namespace {

struct Rig {
  robot::CoreOptions o = robot::DefaultCoreOptions();
  slam::Slam slam{o.slam};
  BumpMemory bumps{{}, o.slam.mounts, o.slam.geometry.radius_m};
  WallFollower follower{o.wall, o.slam.mounts, o.slam.geometry.radius_m};
};

TEST(GoToTest, PlansAndDrivesStraightAtAGoalAhead) {
  Rig r;
  GoTo g({}, r.o.slam.geometry, r.o.slam.mounts);
  ASSERT_TRUE(g.TryGoal({2, 0}, 0, true, r.slam, r.bumps));
  ASSERT_FALSE(g.path().empty());
  EXPECT_NEAR((g.path().back() - Eigen::Vector2d(2, 0)).norm(), 0, 1e-9);
  g.Begin(0);
  const GoTo::Result res = g.Step(0, r.slam, RangeScan{}, 0, r.bumps, r.follower);
  EXPECT_EQ(res.status, GoTo::Status::kDriving);
  EXPECT_DOUBLE_EQ(res.twist.v, 0.18);  // cruise speed, on course
  EXPECT_DOUBLE_EQ(res.twist.omega, 0);
}

TEST(GoToTest, GivesUpAfterTheStuckTime) {
  for (double stuck : {25.0, 10.0}) {
    Rig r;
    GoToOptions o;
    o.go_to_stuck_s = stuck;
    GoTo g(o, r.o.slam.geometry, r.o.slam.mounts);
    ASSERT_TRUE(g.TryGoal({2, 0}, 0, true, r.slam, r.bumps));
    g.Begin(0);
    double gave_up = -1;
    std::string why;
    for (double t = 0; t < 100 && gave_up < 0; t += 0.5) {
      const GoTo::Result res = g.Step(t, r.slam, RangeScan{}, 0, r.bumps, r.follower);
      if (res.status == GoTo::Status::kGiveUp) {
        gave_up = t;
        why = res.why;
      }
    }
    EXPECT_DOUBLE_EQ(gave_up, stuck + 0.5) << stuck;  // the first step after go_to_stuck_s
    EXPECT_EQ(why, "no way found");
  }
}

TEST(GoToTest, TimesOutEvenWhileMoving) {
  Rig r;
  GoToOptions o;
  o.go_to_timeout_s = 5;
  GoTo g(o, r.o.slam.geometry, r.o.slam.mounts);
  ASSERT_TRUE(g.TryGoal({2, 0}, 0, true, r.slam, r.bumps));
  g.Begin(10);
  EXPECT_EQ(g.Step(15, r.slam, RangeScan{}, 0, r.bumps, r.follower).status, GoTo::Status::kDriving);
  const GoTo::Result res = g.Step(15.5, r.slam, RangeScan{}, 0, r.bumps, r.follower);
  EXPECT_EQ(res.status, GoTo::Status::kGiveUp);
  EXPECT_EQ(res.why, "not reached in time");
}

TEST(GoToTest, EscapesAContactThenGivesUpWhenItKeepsHittingIt) {
  Rig r;
  GoToOptions o;
  o.go_to_stuck_s = 1000;
  GoTo g(o, r.o.slam.geometry, r.o.slam.mounts);
  ASSERT_TRUE(g.TryGoal({2, 0}, 0, true, r.slam, r.bumps));
  g.Begin(0);
  // Left bumper: turn to face away from the contact (heading 0.6 + pi), at the
  // escape turn-rate limit.
  GoTo::Result res = g.Step(0, r.slam, RangeScan{}, 1, r.bumps, r.follower);
  EXPECT_EQ(res.status, GoTo::Status::kDriving);
  EXPECT_DOUBLE_EQ(res.twist.v, 0);
  EXPECT_DOUBLE_EQ(res.twist.omega, -0.9);
  // Still pressed at the same place: every escape_max_s (6 s) a new escape of the
  // same contact; the fifth counts as a second contact, and the goal is given up.
  double gave_up = -1;
  for (double t = 0.5; t < 60 && gave_up < 0; t += 0.5) {
    res = g.Step(t, r.slam, RangeScan{}, 1, r.bumps, r.follower);
    if (res.status == GoTo::Status::kGiveUp) gave_up = t;
  }
  EXPECT_DOUBLE_EQ(gave_up, 30);
  EXPECT_EQ(res.why, "the way is blocked by obstacles the sensors miss");
}

TEST(GoToTest, AGoalWithoutHeadingStaysReached) {
  Rig r;
  GoTo g({}, r.o.slam.geometry, r.o.slam.mounts);
  ASSERT_TRUE(g.TryGoal({0.05, 0}, 0, false, r.slam, r.bumps));  // within goal_tolerance_m
  g.Begin(0);
  EXPECT_EQ(g.Step(0, r.slam, RangeScan{}, 0, r.bumps, r.follower).status, GoTo::Status::kArrived);
  // With a heading to turn to (pi/2 away): turn at the align limit first.
  ASSERT_TRUE(g.TryGoal({0.05, 0}, M_PI / 2, true, r.slam, r.bumps));
  g.Begin(1);
  const GoTo::Result res = g.Step(1, r.slam, RangeScan{}, 0, r.bumps, r.follower);
  EXPECT_EQ(res.status, GoTo::Status::kDriving);
  EXPECT_DOUBLE_EQ(res.twist.omega, 0.8);
}

}  // namespace
}  // namespace irslam::control
