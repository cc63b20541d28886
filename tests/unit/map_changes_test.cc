#include "control/map_changes.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "tests/testing/lines.h"

namespace irslam::control {
namespace {

using testing::Line;

// A 4 m x 4 m room and a piece against its top wall (y = 4): x 1.6..2.6,
// y 3.5..4 (the paper's Fig. 20, box 1), its sides seen from outside.
std::vector<slam::LineFeature> Lines() {
  return {Line(1, 0, 4, 4, 4), Line(10, 1.6, 3.5, 1.6, 4.0), Line(11, 1.6, 3.5, 2.6, 3.5),
          Line(12, 2.6, 3.5, 2.6, 4.0)};
}

slam::LineFeature& Find(std::vector<slam::LineFeature>* lines, int id) {
  return *std::find_if(lines->begin(), lines->end(), [&](const auto& l) { return l.id == id; });
}

std::vector<TimedPose> SavedTrajectory() {
  return {{0, {1.2, 3.75, 0}}, {1, {2.1, 3.0, 0}}, {2, {3.0, 3.75, 0}}};
}

EnvironmentModel Model() {
  EnvironmentModel m;
  m.room.box = Box{0, 0, 4, 4};
  ObjectModel o;
  o.id = 5;
  o.kind = ObjectKind::kWallContact;
  o.lines = {10, 11, 12};
  o.complete = true;
  o.box = {1.6, 3.5, 2.6, 4.0};
  m.objects.push_back(o);
  return m;
}

// The robot along an end side, 0.3 m from it, towards the wall, as an edge
// pass goes: its centre stops 0.25 m short of the wall; then away.
std::vector<int> PassEndSide(MapChanges* changes, double x, double away_x,
                             const std::vector<slam::LineFeature>& lines) {
  std::vector<int> moved;
  for (double y = 3.0; y <= 3.75 + 1e-9; y += 0.02) {
    for (int id : changes->Step({x, y, M_PI / 2}, lines)) moved.push_back(id);
  }
  for (double s = 0; s <= 1.0 + 1e-9; s += 0.02) {
    for (int id : changes->Step({x + (away_x - x) * s, 3.75 - 0.75 * s, 0}, lines)) moved.push_back(id);
  }
  return moved;
}

TEST(MapChangesTest, EndSidesOfAPieceAtAWallPassedAsFarAsTheRobotGoesAndNotSeenAgainMeanItMoved) {
  MapChanges changes(MapChangeOptions{});
  changes.Reset(Lines(), SavedTrajectory(), Model(), 0.1);
  // The right end side from the right, then the left one from the left: the
  // SLAM matched neither again (their observation counts unchanged).
  EXPECT_TRUE(PassEndSide(&changes, 2.9, 3.6, Lines()).empty());  // one side missing is not a move
  EXPECT_EQ(PassEndSide(&changes, 1.3, 0.6, Lines()), std::vector<int>{5});
}

TEST(MapChangesTest, WithoutTheWallMarginAnEndSideAtAWallIsNeverPassedFarEnough) {
  MapChangeOptions o;
  o.wall_margin_m = 0;  // the whole 0.5 m asked for; the robot passes 0.25 m of it
  MapChanges changes(o);
  changes.Reset(Lines(), SavedTrajectory(), Model(), 0.1);
  EXPECT_TRUE(PassEndSide(&changes, 2.9, 3.6, Lines()).empty());
  EXPECT_TRUE(PassEndSide(&changes, 1.3, 0.6, Lines()).empty());
}

TEST(MapChangesTest, SidesSeenAgainAreNotMissing) {
  MapChanges changes(MapChangeOptions{});
  changes.Reset(Lines(), SavedTrajectory(), Model(), 0.1);
  std::vector<slam::LineFeature> seen = Lines();
  for (auto& l : seen) ++l.observations;
  EXPECT_TRUE(PassEndSide(&changes, 2.9, 3.6, seen).empty());
  EXPECT_TRUE(PassEndSide(&changes, 1.3, 0.6, seen).empty());
}

// Moved 0.5 m along its wall (+x): the long side's new place is collinear
// with the old one and the SLAM stretches it over both (1.6..3.1), wherever
// the robot is; with the left end side passed and not seen again, that is two
// sides not where they were. (Stretched past the box it would also be a move
// alone: ASideReachingPastItsClosedBoxMeansThePieceMoved; off here.)
TEST(MapChangesTest, ASideStretchedBetweenItsCornersIsNotWhereItWas) {
  MapChangeOptions o;
  o.past_box_moves = false;
  MapChanges changes(o);
  changes.Reset(Lines(), SavedTrajectory(), Model(), 0.1);
  std::vector<slam::LineFeature> now = Lines();
  EXPECT_TRUE(changes.Step({3.5, 1.0, 0}, now).empty());
  Find(&now, 11) = Line(11, 1.6, 3.5, 3.1, 3.5);
  EXPECT_TRUE(changes.Step({3.5, 1.0, 0}, now).empty());  // one side
  EXPECT_EQ(PassEndSide(&changes, 1.3, 0.6, now), std::vector<int>{5});
}

// A side saved in part (its right end in the open, beside a collinear piece of
// itself) grows when seen whole: that is no move.
TEST(MapChangesTest, ASideSavedInPartMayGrow) {
  std::vector<slam::LineFeature> saved = Lines();
  Find(&saved, 11) = Line(11, 1.6, 3.5, 2.0, 3.5);
  saved.push_back(Line(13, 2.05, 3.5, 2.6, 3.5));
  EnvironmentModel model = Model();
  model.objects[0].lines.push_back(13);
  MapChanges changes(MapChangeOptions{});
  changes.Reset(saved, SavedTrajectory(), model, 0.1);
  std::vector<slam::LineFeature> now = Lines();  // 11 whole, 13 merged into it
  EXPECT_TRUE(changes.Step({3.5, 1.0, 0}, now).empty());
  EXPECT_TRUE(PassEndSide(&changes, 1.3, 0.6, now).empty());  // one side missing only
}

// fig20's box as its first mission saved it: the long side only in part (to
// x = 2.37 of 2.6, its right end in the open, so not bounded by corners), the
// model complete with the box right. Moved 0.5 m along its wall (+x), the SLAM
// stretches the long side over the new place: past the box's corner by more
// than stretched_m, the piece has moved, with no second side needed (the end
// sides are at the wall or under the piece's new place).
TEST(MapChangesTest, ASideReachingPastItsClosedBoxMeansThePieceMoved) {
  std::vector<slam::LineFeature> saved = Lines();
  Find(&saved, 11) = Line(11, 1.6, 3.5, 2.37, 3.5);
  MapChanges changes(MapChangeOptions{});
  changes.Reset(saved, SavedTrajectory(), Model(), 0.1);
  std::vector<slam::LineFeature> now = saved;
  Find(&now, 11) = Line(11, 1.6, 3.5, 2.85, 3.5);  // 0.25 m past the box: not yet
  EXPECT_TRUE(changes.Step({3.5, 1.0, 0}, now).empty());
  Find(&now, 11) = Line(11, 1.6, 3.5, 3.1, 3.5);  // 0.5 m past
  EXPECT_EQ(changes.Step({3.5, 1.0, 0}, now), std::vector<int>{5});
  EXPECT_TRUE(changes.Step({3.5, 1.0, 0}, now).empty());  // reported once
  // Without the rule (or for an incomplete object) one side is not a move.
  MapChangeOptions off;
  off.past_box_moves = false;
  MapChanges without(off);
  without.Reset(saved, SavedTrajectory(), Model(), 0.1);
  EXPECT_TRUE(without.Step({3.5, 1.0, 0}, now).empty());
  EnvironmentModel open = Model();
  open.objects[0].complete = false;
  MapChanges incomplete(MapChangeOptions{});
  incomplete.Reset(saved, SavedTrajectory(), open, 0.1);
  EXPECT_TRUE(incomplete.Step({3.5, 1.0, 0}, now).empty());
}

}  // namespace
}  // namespace irslam::control
