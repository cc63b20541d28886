// BumpMemory: where a contact is remembered and which beams see it.
#include "control/bump_memory.h"

#include <gtest/gtest.h>

#include <cmath>

namespace irslam::control {
namespace {

constexpr double kRadius = 0.17;
constexpr double kDeg = M_PI / 180;

// Seven sensors at the centre, -90 ... +90 deg.
std::array<SensorMount, kNumIrSensors> CentreMounts() {
  std::array<SensorMount, kNumIrSensors> m{};
  const double deg[kNumIrSensors] = {-90, -45, -20, 0, 20, 45, 90};
  for (int i = 0; i < kNumIrSensors; ++i) m[static_cast<size_t>(i)] = {0, 0, deg[i] * kDeg};
  return m;
}

TEST(BumpMemoryTest, LeftBumperContactIsAheadLeftAtTheBodyEdge) {
  BumpMemory b({}, CentreMounts(), kRadius);
  EXPECT_DOUBLE_EQ(b.ContactBearing(1), 0.6);
  EXPECT_DOUBLE_EQ(b.ContactBearing(2), -0.6);
  EXPECT_DOUBLE_EQ(b.ContactBearing(3), 0.0);
  b.Record({1.0, 2.0, M_PI / 2}, 1);
  ASSERT_EQ(b.points().size(), 1u);
  // radius + 2 cm, at heading + 0.6 rad.
  EXPECT_NEAR(b.points()[0].x(), 1.0 + 0.19 * std::cos(M_PI / 2 + 0.6), 1e-12);
  EXPECT_NEAR(b.points()[0].y(), 2.0 + 0.19 * std::sin(M_PI / 2 + 0.6), 1e-12);
  // The same contact again (within 3 cm) is not a new point; no bumper: nothing.
  b.Record({1.0, 2.01, M_PI / 2}, 1);
  b.Record({3.0, 3.0, 0}, 0);
  EXPECT_EQ(b.points().size(), 1u);
}

TEST(BumpMemoryTest, BeamsThatWouldSweepIntoTheContactSeeIt) {
  BumpMemory b({}, CentreMounts(), kRadius);
  b.Record({0, 0, 0}, 1);  // contact at 0.19 m, bearing 0.6 rad
  const RangeScan out = b.Apply(RangeScan{}, {0, 0, 0});
  // +20 and +45 deg beams pass within half a radius (8.5 cm) of it.
  ASSERT_TRUE(out.range_m[4]);
  EXPECT_NEAR(*out.range_m[4], 0.19 * std::cos(0.6 - 20 * kDeg), 1e-12);  // 0.184
  ASSERT_TRUE(out.range_m[5]);
  EXPECT_NEAR(*out.range_m[5], 0.19 * std::cos(0.6 - 45 * kDeg), 1e-12);  // 0.187
  // The front beam passes 10.7 cm from it; the others farther or away.
  for (int i : {0, 1, 2, 3, 6}) EXPECT_FALSE(out.range_m[static_cast<size_t>(i)]) << i;
  // A real, shorter reading is kept; a longer one is replaced.
  RangeScan real;
  real.range_m[4] = 0.10;
  real.range_m[5] = 0.50;
  const RangeScan mixed = b.Apply(real, {0, 0, 0});
  EXPECT_DOUBLE_EQ(*mixed.range_m[4], 0.10);
  EXPECT_NEAR(*mixed.range_m[5], 0.187, 1e-3);
}

TEST(BumpMemoryTest, FarContactsAndOptionsApply) {
  BumpMemoryOptions o;
  o.bump_beam_half_width = 0.7;  // 11.9 cm: the front beam (10.7 cm off) sees it too
  BumpMemory b(o, CentreMounts(), kRadius);
  b.Record({0, 0, 0}, 1);
  EXPECT_NEAR(*b.Apply(RangeScan{}, {0, 0, 0}).range_m[3], 0.19 * std::cos(0.6), 1e-12);
  // Beyond bump_reach_m (1 m) a contact is ignored.
  const RangeScan far = b.Apply(RangeScan{}, {-1.2, 0, 0});
  for (const auto& r : far.range_m) EXPECT_FALSE(r);
}

// Relocalising, the robot is in a fresh local SLAM's frame: the contacts
// remembered before (the map's frame) are not shown, those since are.
TEST(BumpMemoryTest, ContactsBeforeAnIndexAreNotShown) {
  BumpMemory b({}, CentreMounts(), kRadius);
  b.Record({0, 0, 0}, 3);  // straight ahead, at 0.19 m (the map's frame)
  const size_t from = b.points().size();
  RangeScan empty;
  EXPECT_TRUE(b.Apply(empty, {0, 0, 0}).range_m[3].has_value());
  EXPECT_FALSE(b.Apply(empty, {0, 0, 0}, from).range_m[3].has_value());
  b.Record({0, 0, M_PI / 2}, 3);  // one in the local frame: ahead at +90 deg
  const RangeScan seen = b.Apply(empty, {0, 0, M_PI / 2}, from);
  ASSERT_TRUE(seen.range_m[3].has_value());
  EXPECT_NEAR(*seen.range_m[3], 0.19, 1e-9);
}

// A go-to's front check leaves out the contacts under the body that its plans
// leave out (under_body_contacts_m): they would read 0.09-0.10 m ahead and
// hold the robot still on the path planned over them.
TEST(BumpMemoryTest, ContactsUnderTheBodyCanBeLeftOut) {
  BumpMemory b({}, CentreMounts(), kRadius);
  b.Record({0, 0, 0}, 3);    // ahead at 0.19 m
  b.Record({0.5, 0, 0}, 3);  // at (0.69, 0)
  RangeScan empty;
  const Pose2 on_first{0.1, 0, 0};  // the first contact 0.09 m ahead: under the body
  ASSERT_TRUE(b.Apply(empty, on_first).range_m[3].has_value());
  EXPECT_NEAR(*b.Apply(empty, on_first).range_m[3], 0.09, 1e-9);
  const RangeScan skipped = b.Apply(empty, on_first, 0, 0.14);
  ASSERT_TRUE(skipped.range_m[3].has_value());  // the farther one is still seen
  EXPECT_NEAR(*skipped.range_m[3], 0.59, 1e-9);
  EXPECT_NEAR(*b.Apply(empty, on_first, 0, 0.0).range_m[3], 0.09, 1e-9);  // 0: none left out
}

}  // namespace
}  // namespace irslam::control
