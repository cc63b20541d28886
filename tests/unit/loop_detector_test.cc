// LoopDetector on a circular wall-following path of radius 1 m at 0.2 m/s, and
// its orbit check on heading sequences.
#include "control/loop_detector.h"

#include <gtest/gtest.h>

#include <cmath>

namespace irslam::control {
namespace {

// Steps the detector along the circle (ccw: +1, cw: -1) every 0.1 s; returns
// the time of the first event and the event, or -1 if none within t_max.
std::pair<double, LoopEvent> RunCircle(LoopDetector* d, int dir, double t_max) {
  for (int k = 0; k * 0.1 <= t_max; ++k) {
    const double t = k * 0.1;
    const double a = dir * 0.2 * t;  // angle on the circle
    const Pose2 p{std::cos(a), std::sin(a), NormalizeAngle(a + dir * M_PI / 2)};
    const LoopEvent e = d->Update(t, true, p, 0.2 * t);
    if (e != LoopEvent::kNone) return {t, e};
  }
  return {-1, LoopEvent::kNone};
}

TEST(LoopDetectorTest, ClosesBackAtTheAnchorAfterTheMinimumDistance) {
  LoopDetector d({});
  const auto [t, e] = RunCircle(&d, +1, 100);
  EXPECT_EQ(e, LoopEvent::kRoom);
  // Anchor after 1.5 s steady (angle 0.3); back within 0.25 m of it at t = 31.7
  // (chord 0.223 m; at 31.6 it is 0.262 m).
  EXPECT_NEAR(t, 31.7, 1e-9);
  EXPECT_NEAR(d.anchor().x, std::cos(0.3), 1e-9);
  EXPECT_NEAR(d.turned(), 0.2 * (31.7 - 1.5), 1e-9);  // 6.04 rad: counter-clockwise
}

TEST(LoopDetectorTest, NoLoopBeforeTheMinimumDistance) {
  LoopOptions o;
  o.loop_min_distance_m = 10;  // more than one circumference (6.28 m)
  LoopDetector d(o);
  const auto [t, e] = RunCircle(&d, +1, 100);
  EXPECT_EQ(e, LoopEvent::kRoom);
  EXPECT_NEAR(t, 63.1, 1e-9);  // the second time round
}

TEST(LoopDetectorTest, AClockwiseLoopIsAFreeObject) {
  LoopDetector d({});
  const auto [t, e] = RunCircle(&d, -1, 100);
  EXPECT_EQ(e, LoopEvent::kFreeObject);
  EXPECT_NEAR(t, 31.7, 1e-9);
  EXPECT_FALSE(d.has_anchor());  // dropped: the next loop starts from a new anchor
}

TEST(LoopDetectorTest, NoAnchorUntilSteadyLongEnough) {
  LoopDetector d({});
  const Pose2 p{0, 0, 0};
  EXPECT_EQ(d.Update(0.0, true, p, 0), LoopEvent::kNone);
  EXPECT_EQ(d.Update(1.0, false, p, 0), LoopEvent::kNone);  // not steady: starts over
  EXPECT_EQ(d.Update(1.2, true, p, 0), LoopEvent::kNone);
  EXPECT_FALSE(d.has_anchor());
  d.Update(2.6, true, p, 0);
  EXPECT_FALSE(d.has_anchor());  // 1.4 s
  d.Update(2.75, true, p, 0);
  EXPECT_TRUE(d.has_anchor());  // 1.55 s
}

// Generated room 1169: the first wall followed steadily was a piece of
// furniture's side; at its end the robot went on along the room's wall and
// round the room for ever, never on that side again. Here: 2 m along a line
// (y = -2, heading 0) that the loop does not pass, then round the unit circle
// counter-clockwise from (1, 0). With one anchor (on the line) no loop closed.
TEST(LoopDetectorTest, ALoopClosesAtAnAnchorTakenAfterTheFirstWallWasLeft) {
  LoopDetector d({});
  double t = 0, dist = 0;
  for (; dist < 2.0 - 1e-9; t += 0.1, dist += 0.02)
    ASSERT_EQ(d.Update(t, true, {-3.0 + dist, -2.0, 0.0}, dist), LoopEvent::kNone);
  // Searching for the next wall (not steady) on the way to the circle.
  for (int i = 0; i < 20; ++i, t += 0.1) ASSERT_EQ(d.Update(t, false, {1.0, 0.0, M_PI / 2}, dist), LoopEvent::kNone);
  const size_t on_the_line = d.anchors();
  EXPECT_EQ(on_the_line, 2U);  // at 1.5 s (0.3 m) and 1.0 m on
  LoopEvent e = LoopEvent::kNone;
  const double circle_from = dist;
  for (double a = 0; a < 4 * M_PI && e == LoopEvent::kNone; a += 0.01, t += 0.05, dist += 0.01)
    e = d.Update(t, true, {std::cos(a), std::sin(a), NormalizeAngle(a + M_PI / 2)}, dist);
  ASSERT_EQ(e, LoopEvent::kRoom);
  // The anchor it closed at: the first on the circle (1.5 s, 0.3 m along it),
  // once round (2 pi) and back within 0.25 m.
  EXPECT_NEAR(d.anchor().x, std::cos(0.3), 0.02);
  EXPECT_NEAR(d.turned(), 2 * M_PI - 0.25, 0.03);
  EXPECT_NEAR(dist - circle_from, 0.3 + 2 * M_PI - 0.25, 0.03);
}

TEST(LoopDetectorTest, AnchorsAreBoundedAndRearmKeepsOne) {
  LoopOptions o;
  o.loop_min_distance_m = 1000;  // never closes
  LoopDetector d(o);
  double t = 0;
  for (double dist = 0; dist < 400; dist += 0.05, t += 0.25)
    d.Update(t, true, {dist, 0, 0}, dist);
  EXPECT_EQ(d.anchors(), LoopDetector::kMaxAnchors);
  d.Rearm({1, 2, 0}, 400);
  EXPECT_EQ(d.anchors(), 1U);
  EXPECT_NEAR(d.anchor().y, 2, 1e-12);
}

// The orbit check: round a small box without ever following it steadily (no
// anchor), as the follower does round boxes whose sides are shorter than it
// needs to settle.
TEST(LoopDetectorTest, CirclingClockwiseWithoutEverBeingSteadyIsAFreeObject) {
  LoopDetector d({});
  LoopEvent e = LoopEvent::kNone;
  double t_event = -1;
  for (int k = 0; k * 0.1 <= 100 && e == LoopEvent::kNone; ++k) {
    const double t = k * 0.1, a = -0.2 * t;
    e = d.Update(t, false, {std::cos(a), std::sin(a), NormalizeAngle(a - M_PI / 2)}, 0.2 * t);
    if (e != LoopEvent::kNone) t_event = t;
  }
  EXPECT_FALSE(d.has_anchor());
  ASSERT_EQ(e, LoopEvent::kFreeObject);
  // 0.2 rad/s clockwise: 2 pi + 1 = 7.283 rad is passed at t = 36.5 s.
  EXPECT_NEAR(t_event, 36.5, 1e-9);
  EXPECT_NEAR(d.orbit_turned(), 0, 1e-9);  // starts over after the event
}

TEST(LoopDetectorTest, TheRoomCounterClockwiseWithAWallBoxDetourIsNoFreeObject) {
  // Along a wall (heading 0), round a box standing at it: an inner corner
  // (+pi/2), two outer corners (-pi/2 each, arced), an inner corner back to the
  // wall; then the room's corner (+pi/2); four times round, all unsteady.
  LoopDetector d({});
  double theta = 0, t = 0;
  const auto turn = [&](double by) {
    for (int i = 0; i < 20; ++i) {
      theta += by / 20;
      t += 0.1;
      ASSERT_EQ(d.Update(t, false, {0, 0, NormalizeAngle(theta)}, t), LoopEvent::kNone);
    }
  };
  for (int loop = 0; loop < 4; ++loop) {
    for (int side = 0; side < 4; ++side) {
      turn(M_PI / 2);
      turn(-M_PI / 2);
      turn(-M_PI / 2);
      turn(M_PI / 2);
      turn(M_PI / 2);
    }
  }
  EXPECT_NEAR(d.orbit_turned(), 0, 1e-9);  // never far below its peak
}

TEST(LoopDetectorTest, ASearchForAWallStartsTheOrbitCheckOver) {
  // Most of a turn clockwise round something, then the follower lost it and
  // searched (left it, or found it again): what comes after counts afresh.
  LoopDetector d({});
  double t = 0, theta = 0;
  const auto step = [&](double by, bool searching) {
    theta += by;
    t += 0.1;
    return d.Update(t, false, {0, 0, NormalizeAngle(theta)}, 0, searching);
  };
  for (int i = 0; i < 60; ++i) ASSERT_EQ(step(-0.1, false), LoopEvent::kNone) << i;
  EXPECT_NEAR(d.orbit_turned(), 5.9, 1e-9);  // (the first update only sets the heading)
  EXPECT_EQ(step(0.0, true), LoopEvent::kNone);
  EXPECT_NEAR(d.orbit_turned(), 0, 1e-9);
  for (int i = 0; i < 68; ++i) ASSERT_EQ(step(-0.1, false), LoopEvent::kNone) << i;
  EXPECT_NEAR(d.orbit_turned(), 6.8, 1e-9);
  EXPECT_EQ(step(-0.5, false), LoopEvent::kFreeObject);  // 7.3 > 2 pi + 1
}

}  // namespace
}  // namespace irslam::control
