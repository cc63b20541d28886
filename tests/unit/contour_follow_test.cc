// ContourFollow: which object next, where following it starts, when it ends.
#include "control/contour_follow.h"

#include <gtest/gtest.h>

#include "robot/robot_core.h"
#include "tests/testing/lines.h"

namespace irslam::control {
namespace {

using testing::Line;

TEST(ContourFollowTest, NearestPendingObject) {
  EnvironmentModel m;
  ObjectModel a, b, c;
  a.id = 1;
  a.box = {0, 0, 1, 1};  // centre (0.5, 0.5)
  b.id = 2;
  b.box = {2, 2, 3, 3};
  c.id = 3;
  c.box = {0, 0, 0.2, 0.2};
  c.complete = true;  // nearest, but complete
  m.objects = {a, b, c};
  EXPECT_EQ(NearestPending(m, {0, 0, 0})->id, 1);
  EXPECT_EQ(NearestPending(m, {3, 3, 0})->id, 2);
  m.objects[0].given_up = true;
  EXPECT_EQ(NearestPending(m, {0, 0, 0})->id, 2);
  m.objects[1].complete = true;
  EXPECT_EQ(NearestPending(m, {0, 0, 0}), nullptr);
}

TEST(ContourFollowTest, StartsOnTheSeenSideHeadingWithTheObjectOnTheRight) {
  ObjectModel box;
  box.lines = {7, 8};
  // Bottom side y = 1 seen from below; left side x = 1 seen from the left.
  const std::vector<slam::LineFeature> lines = {Line(7, {1, 1}, {2, 1}), Line(8, {1, 1}, {1, 2}),
                                                Line(9, {5, 5}, {6, 5})};
  const std::vector<TimedPose> traj = {{0, {1.5, 0.5, 0}}, {1, {0.5, 1.5, 0}}};
  const auto starts = ContourStarts(box, lines, traj, {1.5, 0, 0}, 0.4);
  ASSERT_EQ(starts.size(), 2u);  // line 9 is another object's; a free object: centres only
  // The bottom side is nearer the robot: start 0.4 m below its middle, heading -x.
  EXPECT_NEAR(starts[0].p.x(), 1.5, 1e-12);
  EXPECT_NEAR(starts[0].p.y(), 0.6, 1e-12);
  EXPECT_NEAR(std::abs(starts[0].heading), M_PI, 1e-12);
  // Then the left side: 0.4 m left of its middle, heading +y.
  EXPECT_NEAR(starts[1].p.x(), 0.6, 1e-12);
  EXPECT_NEAR(starts[1].p.y(), 1.5, 1e-12);
  EXPECT_NEAR(starts[1].heading, M_PI / 2, 1e-12);
}

// The end of a piece of furniture against a wall, seen alone: its centre is
// 0.25 m from the wall, too near for the robot; beside its free end is not.
TEST(ContourFollowTest, AShortSideAtAWallCanStartBesideItsFreeEnd) {
  ObjectModel box;
  box.lines = {5};
  box.kind = ObjectKind::kWallContact;
  const std::vector<slam::LineFeature> lines = {Line(5, {2, 3.5}, {2, 4})};  // wall at y = 4
  const std::vector<TimedPose> traj = {{0, {2.5, 3, 0}}};                  // seen from the right
  const auto starts = ContourStarts(box, lines, traj, {3, 2, 0}, 0.3);
  ASSERT_EQ(starts.size(), 3u);
  EXPECT_NEAR(starts[0].p.x(), 2.3, 1e-12);
  EXPECT_NEAR(starts[0].p.y(), 3.75, 1e-12);
  // Heading -y (the object on the right): the free end is the one ahead.
  EXPECT_NEAR(starts[1].p.x(), 2.3, 1e-12);
  EXPECT_NEAR(starts[1].p.y(), 3.5, 1e-12);
  EXPECT_NEAR(starts[1].heading, -M_PI / 2, 1e-12);
  EXPECT_NEAR(starts[2].p.y(), 4.0, 1e-12);
  // A free object's sides are followed from their centres only.
  box.kind = ObjectKind::kFree;
  EXPECT_EQ(ContourStarts(box, lines, traj, {3, 2, 0}, 0.3).size(), 1u);
}

TEST(ContourFollowTest, TimesOut) {
  const robot::CoreOptions o = robot::DefaultCoreOptions();
  slam::Slam slam(o.slam);
  WallFollower follower(o.wall, o.slam.mounts, o.slam.geometry.radius_m);
  Modeler modeler(o.model);
  ContourOptions co;
  co.contour_timeout_s = 20;
  ContourFollow c(co, o.wall.follow_distance_m);
  c.SetTarget(1, true);  // at a wall, but not in the model: never "left"
  c.Start(10, 0, 0);
  double ended = -1;
  for (double t = 10; t < 100 && ended < 0; t += 0.5) {
    const auto r = c.Step(t, slam, RangeScan{}, false, &follower, &modeler);
    if (r.status != ContourFollow::Status::kFollowing) {
      EXPECT_EQ(r.status, ContourFollow::Status::kTimedOut);
      ended = t;
    } else {
      EXPECT_GT(r.twist.v, 0);  // the follower looks for the side
    }
  }
  EXPECT_DOUBLE_EQ(ended, 30.5);
}

}  // namespace
}  // namespace irslam::control
