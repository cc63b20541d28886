// LoopDetector on a circular wall-following path of radius 1 m at 0.2 m/s.
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

}  // namespace
}  // namespace irslam::control
