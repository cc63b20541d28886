// FreeSpace: the floor the beams crossed, and what lies outside a room box.
#include "control/free_space.h"

#include <gtest/gtest.h>

#include <cmath>

namespace irslam::control {
namespace {

constexpr double kDeg = M_PI / 180;

// Seven sensors at the centre, -90 ... +90 deg (index 3 straight ahead).
std::array<SensorMount, kNumIrSensors> CentreMounts() {
  std::array<SensorMount, kNumIrSensors> m{};
  const double deg[kNumIrSensors] = {-90, -45, -20, 0, 20, 45, 90};
  for (int i = 0; i < kNumIrSensors; ++i) m[static_cast<size_t>(i)] = {0, 0, deg[i] * kDeg};
  return m;
}

RangeScan Ahead(double t, std::optional<double> r) {
  RangeScan s;
  s.t = t;
  s.range_m[3] = r;
  return s;
}

TEST(FreeSpaceTest, ABeamMarksTheFloorFreeShortOfItsHit) {
  FreeSpace f({}, CentreMounts());
  // From (0.05, 0.05) along +x, a hit at 1.0 m: free to 0.9 m, the hit at 1.05.
  f.Record({0.05, 0.05, 0}, Ahead(0, 1.0));
  const Box box{-1, -1, 0.1, 1};
  // Outside the box by more than 0.2 m: the cells whose centres are at x 0.35 ... 0.95.
  EXPECT_NEAR(f.OutsideArea(RoomOutline{box, {}}, 0, 0.2), 7 * 0.01, 1e-9);
  // The hit's cell is not free floor, nor counted.
  EXPECT_TRUE(f.HitNear({1.05, 0.05}, 0.01));
  EXPECT_FALSE(f.HitNear({0.55, 0.05}, 0.2));
  EXPECT_TRUE(f.VisitedNear({0.05, 0.05}, 0.01));
  EXPECT_FALSE(f.VisitedNear({0.55, 0.05}, 0.3));
  // The same scan again (same time) adds nothing; no return adds nothing.
  f.Record({0.05, 0.05, M_PI / 2}, Ahead(0, 1.0));
  f.Record({0.05, 0.05, M_PI / 2}, Ahead(1, std::nullopt));
  EXPECT_NEAR(f.OutsideArea(RoomOutline{Box{-1, -1, 0.1, 0.1}, {}}, 0, 0.2), 7 * 0.01, 1e-9);
}

TEST(FreeSpaceTest, FloorSeenBeyondAWallsMappedLineIsNotCounted) {
  FreeSpace f({}, CentreMounts());
  f.Record({0.05, 0.05, 0}, Ahead(0, 1.0));   // along y 0.05 past the right wall x 0.1
  f.Record({0.05, 0.55, 0}, Ahead(1, 1.0));   // along y 0.55
  RoomOutline room{Box{-1, -1, 0.1, 1}, {}};
  EXPECT_NEAR(f.OutsideArea(room, 0, 0.2), 14 * 0.01, 1e-9);
  // The right wall (index 1) mapped from y -1 to 0.3: what lies beyond it
  // there (the lower row) was seen through it; beyond its end (more than
  // pen_cover_margin_m, 0.1 m), the upper row was seen through a gap.
  room.covered[1].emplace_back(-1, 0.3);
  EXPECT_NEAR(f.OutsideArea(room, 0, 0.2), 7 * 0.01, 1e-9);
  for (const auto& p : f.OutsidePoints(room, 0, 0.2, 0, 0, 100)) EXPECT_NEAR(p.y(), 0.55, 1e-9);
  room.covered[1].emplace_back(0.45, 0.5);  // within 0.1 m of y 0.55
  EXPECT_DOUBLE_EQ(f.OutsideArea(room, 0, 0.2), 0);
  // A stretch of another wall does not cover it.
  room.covered[1].clear();
  room.covered[2].emplace_back(-1, 2);
  EXPECT_NEAR(f.OutsideArea(room, 0, 0.2), 14 * 0.01, 1e-9);
}

TEST(FreeSpaceTest, FreeFloorFarBeyondTheRangeLimitIsNotMarked) {
  PenOptions o;
  o.pen_free_range_m = 0.5;
  FreeSpace f(o, CentreMounts());
  f.Record({0.05, 0.05, 0}, Ahead(0, 1.4));  // no hit within the limit: free to 0.5 m only
  EXPECT_NEAR(f.OutsideArea(RoomOutline{Box{-1, -1, 0.1, 1}, {}}, 0, 0), 5 * 0.01, 1e-9);
  EXPECT_FALSE(f.HitNear({1.45, 0.05}, 0.1));
}

TEST(FreeSpaceTest, TheBoxIsInTheMapFrameTurnedFromTheSlamFrame) {
  FreeSpace f({}, CentreMounts());
  f.Record({0.05, 0.05, 0}, Ahead(0, 1.0));  // free along SLAM +x
  // The map frame is the SLAM frame turned by +90 deg: the beam runs along map +y,
  // inside a box tall in y and, past y 0.4, outside one tall in x (the cells
  // whose centres are at map y 0.45 ... 0.95).
  EXPECT_DOUBLE_EQ(f.OutsideArea(RoomOutline{Box{-0.3, -0.3, 0.3, 1.2}, {}}, M_PI / 2, 0.1), 0);
  EXPECT_NEAR(f.OutsideArea(RoomOutline{Box{-0.3, -0.3, 1.2, 0.3}, {}}, M_PI / 2, 0.1), 6 * 0.01, 1e-9);
}

TEST(FreeSpaceTest, TheWayOutIsTheFarthestFreePointAwayFromHitsAndFromThePathTaken) {
  FreeSpace f({}, CentreMounts());
  // Beams along +x from two rows; a hit at the end of the lower one.
  f.Record({0.05, 0.05, 0}, Ahead(0, 1.0));
  f.Record({0.05, 0.55, 0}, Ahead(1, 1.5));
  const RoomOutline box{Box{-1, -1, 0.1, 1}, {}};
  const auto all = f.OutsidePoints(box, 0, 0.2, 0, 0, 100);
  ASSERT_FALSE(all.empty());
  // Farthest first: the upper row's last cell (free to 1.2 m from x 0.05).
  EXPECT_NEAR(all.front().x(), 1.25, 1e-9);
  EXPECT_NEAR(all.front().y(), 0.55, 1e-9);
  // 0.3 m clear of every hit: the lower row's end (hit at 1.05, 0.05) and
  // the upper row's cells near it are out; away from the path (the two start
  // cells) by 0.5 m: x <= 0.5 is out.
  for (const auto& p : f.OutsidePoints(box, 0, 0.2, 0.3, 0.5, 100)) {
    EXPECT_GT((p - Eigen::Vector2d(1.05, 0.05)).norm(), 0.3);
    EXPECT_GT(p.x(), 0.5);
  }
  EXPECT_EQ(f.OutsidePoints(box, 0, 0.2, 0, 0, 3).size(), 3u);
}

TEST(FreeSpaceTest, TheGridIsBounded) {
  PenOptions o;
  o.pen_cell_m = 0.05;
  FreeSpace f(o, CentreMounts());
  // Beams from everywhere on a 40 x 40 m floor: far more cells than the bound.
  int t = 0;
  for (double x = -20; x < 20; x += 0.5)
    for (double y = -20; y < 20; y += 0.2) f.Record({x, y, 0}, Ahead(t++, 1.0));
  EXPECT_EQ(f.cells(), FreeSpace::kMaxCells);
  f.Reset();
  EXPECT_EQ(f.cells(), 0u);
}

}  // namespace
}  // namespace irslam::control
