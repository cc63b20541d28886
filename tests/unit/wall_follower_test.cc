#include <gtest/gtest.h>

#include "robot/robot_core.h"
#include "control/wall_follower.h"

namespace irslam::control {
namespace {

// Ranges the default sensor ring would read with a wall parallel to the heading at
// distance d on the right (from the robot centre), rotated by `angle` (wall turns left).
RangeScan WallOnRight(double d, double angle) {
  const auto mounts = robot::DefaultCoreOptions().slam.mounts;
  RangeScan s;
  for (int i = 0; i < kNumIrSensors; ++i) {
    const auto& m = mounts[i];
    // Wall: points q with n.q = -d, normal n = (sin a, -cos a) pointing away (right).
    const double nx = std::sin(angle), ny = -std::cos(angle);
    const double dir = nx * std::cos(m.theta) + ny * std::sin(m.theta);
    if (dir <= 1e-6) continue;
    const double r = (d - (nx * m.x + ny * m.y)) / dir;
    if (r >= 0.2 && r <= 1.2) s.range_m[i] = r;
  }
  return s;
}

TEST(WallFollowerTest, EstimatesTheRightWall) {
  const auto o = robot::DefaultCoreOptions();
  WallFollower f(o.wall, o.slam.mounts, 0.17);
  auto w = f.RightWall(WallOnRight(0.40, 0.0));
  ASSERT_TRUE(w);
  EXPECT_NEAR(w->distance_m, 0.40, 1e-9);
  EXPECT_NEAR(w->angle_rad, 0.0, 1e-9);
  w = f.RightWall(WallOnRight(0.45, 0.2));
  ASSERT_TRUE(w);
  EXPECT_NEAR(w->distance_m, 0.45, 1e-9);
  EXPECT_NEAR(w->angle_rad, 0.2, 1e-9);
  EXPECT_FALSE(f.RightWall(WallOnRight(1.0, 0.0)));  // farther than follow + margin
}

TEST(WallFollowerTest, SteersBackTowardsTheFollowDistance) {
  const auto o = robot::DefaultCoreOptions();
  WallFollower f(o.wall, o.slam.mounts, 0.17);
  // Find the wall first (it is right there), then follow.
  RangeScan near = WallOnRight(0.40, 0.0);
  f.Step(0.00, near, false);
  f.Step(0.02, near, false);
  ASSERT_EQ(f.mode(), FollowMode::kFollow);
  const Twist too_far = f.Step(0.04, WallOnRight(0.55, 0.0), false);
  EXPECT_LT(too_far.omega, 0);  // turn right, towards the wall
  EXPECT_NEAR(too_far.omega, -o.wall.k_distance * 0.15, 1e-9);
  const Twist too_close = f.Step(0.06, WallOnRight(0.30, 0.0), false);
  EXPECT_GT(too_close.omega, 0);
  EXPECT_GT(too_close.v, 0);
}

TEST(WallFollowerTest, GoesRoundACornerSeenByTheSideSensorAloneWhenContourFollowing) {
  const auto o = robot::DefaultCoreOptions();
  // Only the side sensor sees something: the corner of a small box being passed.
  const auto corner = [](double range) {
    RangeScan s;
    s.range_m[0] = range;
    return s;
  };
  const double r_far = 0.50, d_far = r_far + 0.05;  // (the sensor sits 5 cm right of the centre)
  for (bool orbit : {false, true}) {
    WallFollower f(o.wall, o.slam.mounts, 0.17);
    f.SetOrbitCorners(orbit);
    f.StartFollowing(0.0);
    const auto w = f.RightWall(corner(r_far));
    ASSERT_TRUE(w);
    EXPECT_EQ(w->corner, true);
    const Twist t = f.Step(0.02, corner(r_far), false);
    if (orbit) {
      // The curvature of the circle at the follow distance, plus the correction.
      EXPECT_NEAR(t.v, o.wall.outer_arc_speed_mps, 1e-9);
      EXPECT_NEAR(t.omega,
                  -o.wall.outer_arc_speed_mps / o.wall.follow_distance_m -
                      o.wall.k_distance * (d_far - o.wall.follow_distance_m),
                  1e-9);
    } else {
      // Following the room: taken as a wall alongside (P on the distance only).
      EXPECT_NEAR(t.omega, -o.wall.k_distance * (d_far - o.wall.follow_distance_m), 1e-9);
    }
  }
  // Closer than the follow distance: never turned towards it (the side sensor may
  // still see the side's end, short of the corner).
  WallFollower f(o.wall, o.slam.mounts, 0.17);
  f.SetOrbitCorners(true);
  f.StartFollowing(0.0);
  EXPECT_GT(f.Step(0.02, corner(0.30), false).omega, 0);
  // With the diagonal sensor seeing the side too, it is a wall alongside.
  EXPECT_FALSE(f.RightWall(WallOnRight(0.40, 0.0))->corner);
}

TEST(WallFollowerTest, TurnsLeftAtAnInnerCorner) {
  const auto o = robot::DefaultCoreOptions();
  WallFollower f(o.wall, o.slam.mounts, 0.17);
  RangeScan s = WallOnRight(0.40, 0.0);
  f.Step(0.00, s, false);
  f.Step(0.02, s, false);
  s.range_m[3] = 0.35;  // a wall straight ahead, 40 cm from the centre
  const Twist t = f.Step(0.04, s, false);
  EXPECT_EQ(f.mode(), FollowMode::kInnerCorner);
  EXPECT_DOUBLE_EQ(t.v, 0);
  EXPECT_DOUBLE_EQ(t.omega, o.wall.turn_rate_rad_s);
}

TEST(WallFollowerTest, ArcsRightAtAnOuterCorner) {
  const auto o = robot::DefaultCoreOptions();
  WallFollower f(o.wall, o.slam.mounts, 0.17);
  RangeScan s = WallOnRight(0.40, 0.0);
  f.Step(0.00, s, false);
  f.Step(0.02, s, false);
  f.Step(0.04, RangeScan{}, false);  // the wall ends
  const Twist t = f.Step(0.06, RangeScan{}, false);
  EXPECT_EQ(f.mode(), FollowMode::kOuterCorner);
  EXPECT_GT(t.v, 0);
  EXPECT_NEAR(t.omega, -o.wall.outer_arc_speed_mps / o.wall.follow_distance_m, 1e-12);
}

TEST(WallFollowerTest, BacksOffWhenBumped) {
  const auto o = robot::DefaultCoreOptions();
  WallFollower f(o.wall, o.slam.mounts, 0.17);
  const Twist t = f.Step(0.0, RangeScan{}, true);
  EXPECT_EQ(f.mode(), FollowMode::kBackoff);
  EXPECT_LT(t.v, 0);
}

// Still in contact after backing off and turning (set down against a wall
// behind it: backing off cannot move it, and the simulator's bumper ring reads
// a contact at any bearing): the follower backed off again the other way. It
// used to wait for the bumper to release with the wheels at zero, for ever
// (a kidnapped robot put down against a wall stood still until the mission's
// no-progress limit).
TEST(WallFollowerTest, StillInContactAfterBackingOffBacksOffTheOtherWay) {
  const auto o = robot::DefaultCoreOptions();
  WallFollower f(o.wall, o.slam.mounts, 0.17);
  double t = 0;
  const double dt = 0.02;
  // Reverse for backoff_time_s, then turn backoff_turn_rad, the bumper pressed throughout.
  Twist tw = f.Step(t, RangeScan{}, true);
  EXPECT_LT(tw.v, 0);
  bool forward = false;
  for (int i = 0; i < 1000 && !forward; ++i) {
    t += dt;
    tw = f.Step(t, RangeScan{}, true);
    EXPECT_EQ(f.mode(), FollowMode::kBackoff);
    EXPECT_FALSE(tw.v == 0 && tw.omega == 0) << "held still at t=" << t;
    forward = tw.v > 0;
  }
  ASSERT_TRUE(forward);
  // The cycle took the reverse and the turn, then the other way round.
  EXPECT_GT(t, o.wall.backoff_time_s + o.wall.backoff_turn_rad / o.wall.turn_rate_rad_s - 2 * dt);
  EXPECT_DOUBLE_EQ(tw.v, o.wall.backoff_speed_mps);
  // Released: back to finding a wall.
  for (int i = 0; i < 500 && f.mode() == FollowMode::kBackoff; ++i) {
    t += dt;
    f.Step(t, RangeScan{}, false);
  }
  EXPECT_EQ(f.mode(), FollowMode::kFind);
}

// Boxed in all round: legs nearer ahead than the inner corner's clear distance
// (front_stop_m + 0.15) at every heading. The follower turned on the spot until
// the mission's time limit (generated room 1070, wedged under a chair). After a
// whole turn it turns on to the most open heading of that turn and drives out
// that way, slowly, squeeze_distance_m at most; then it follows again.
TEST(WallFollowerTest, BoxedInAllRoundDrivesOutTheMostOpenWay) {
  const auto o = robot::DefaultCoreOptions();
  WallFollower f(o.wall, o.slam.mounts, 0.17);
  const double front_x = o.slam.mounts[3].x;  // the front sensor's reading is from here
  const double open_heading = 2.0;            // rad: the way out
  // The front sensor's reading at a heading: 0.35 m from the centre, 0.55 m
  // within 0.2 rad of the way out (both short of clear: 0.60 m).
  const auto scan_at = [&](double heading, double extra) {
    RangeScan s;
    const double d = std::abs(NormalizeAngle(heading - open_heading)) < 0.2 ? 0.55 : 0.35;
    s.range_m[3] = d + extra - front_x;
    return s;
  };
  double t = 0, th = 0;
  const double dt = 0.02;
  f.Step(t, WallOnRight(0.40, 0.0), false);
  f.Step(t += dt, WallOnRight(0.40, 0.0), false);
  ASSERT_EQ(f.mode(), FollowMode::kFollow);
  Twist tw = f.Step(t += dt, scan_at(th, 0), false);
  ASSERT_EQ(f.mode(), FollowMode::kInnerCorner);
  double turned = 0;
  for (int i = 0; i < 2000 && f.mode() == FollowMode::kInnerCorner; ++i) {
    th += tw.omega * dt;
    turned += tw.omega * dt;
    tw = f.Step(t += dt, scan_at(th, 0), false);
  }
  ASSERT_EQ(f.mode(), FollowMode::kSqueeze);
  EXPECT_GT(turned, 2 * M_PI);
  EXPECT_LT(turned, 4 * M_PI);
  EXPECT_LT(std::abs(NormalizeAngle(th - open_heading)), 0.25);
  EXPECT_DOUBLE_EQ(tw.v, o.wall.squeeze_speed_mps);
  EXPECT_DOUBLE_EQ(tw.omega, 0);
  // Drives squeeze_distance_m (the way ahead stays open), then follows again.
  double driven = 0;
  for (int i = 0; i < 2000 && f.mode() == FollowMode::kSqueeze; ++i) {
    driven += tw.v * dt;
    tw = f.Step(t += dt, scan_at(th, 0), false);
  }
  EXPECT_NEAR(driven, o.wall.squeeze_distance_m, 2 * o.wall.squeeze_speed_mps * dt);
  EXPECT_NE(f.mode(), FollowMode::kSqueeze);
}

// Driving out goes by the sensors' own readings: a remembered contact (added
// to the scan the follower steers by) does not stop it, a reading closer than
// squeeze_stop_m in the body's path does.
TEST(WallFollowerTest, DrivingOutStopsForWhatTheSensorsSeeNotForRememberedContacts) {
  const auto o = robot::DefaultCoreOptions();
  const double front_x = o.slam.mounts[3].x;
  const auto front = [&](double d) {
    RangeScan s;
    s.range_m[3] = d - front_x;
    return s;
  };
  const auto boxed_in = [&](WallFollower* f, double* t) {
    f->Step(*t, WallOnRight(0.40, 0.0), false);
    f->Step(*t += 0.02, WallOnRight(0.40, 0.0), false);
    for (int i = 0; i < 2000 && f->mode() != FollowMode::kSqueeze; ++i) f->Step(*t += 0.02, front(0.35), false);
    ASSERT_EQ(f->mode(), FollowMode::kSqueeze);
  };
  WallFollower a(o.wall, o.slam.mounts, 0.17);
  double t = 0;
  boxed_in(&a, &t);
  const RangeScan sensors = front(0.35);
  Twist tw = a.Step(t += 0.02, front(0.20), false, &sensors);  // a remembered contact 20 cm ahead
  EXPECT_EQ(a.mode(), FollowMode::kSqueeze);
  EXPECT_DOUBLE_EQ(tw.v, o.wall.squeeze_speed_mps);
  const RangeScan near = front(o.wall.squeeze_stop_m - 0.01);
  a.Step(t += 0.02, near, false, &near);
  EXPECT_NE(a.mode(), FollowMode::kSqueeze);
}

}  // namespace
}  // namespace irslam::control
