#include <gtest/gtest.h>

#include <algorithm>

#include "control/path_planner.h"
#include "control/room_geometry.h"
#include "control/room_model.h"
#include "tests/testing/lines.h"

namespace irslam::control {
namespace {

using testing::Line;

// A 4 x 4 room walked at 0.4 m from its walls (the trajectory tells which side
// each line was seen from).
std::vector<TimedPose> Loop() {
  std::vector<TimedPose> t;
  for (double s = 0.4; s <= 3.6; s += 0.1) {
    t.push_back({0, {s, 0.4, 0}});
    t.push_back({0, {3.6, s, 0}});
    t.push_back({0, {s, 3.6, 0}});
    t.push_back({0, {0.4, s, 0}});
  }
  return t;
}

std::vector<slam::LineFeature> Room() {
  // The left wall is split by a wall-contact object (x 0..0.6, y 1.5..2.5).
  return {Line(1, 0, 0, 4, 0), Line(2, 4, 0, 4, 4), Line(3, 4, 4, 0, 4), Line(4, 0, 4, 0, 2.6),
          Line(5, 0, 1.4, 0, 0)};
}

TEST(RoomModelTest, FindsTheRoomWithAWallInPieces) {
  Modeler m{ModelOptions{}};
  const auto& model = m.Update(Room(), Loop());
  ASSERT_TRUE(model.room.box);
  EXPECT_NEAR(model.room.box->xmax, 4, 1e-9);
  EXPECT_NEAR(model.room.box->ymax, 4, 1e-9);
  EXPECT_EQ(model.room.walls[0], std::vector<int>({1}));
  EXPECT_EQ(model.room.walls[3], std::vector<int>({4, 5}));
  EXPECT_TRUE(model.objects.empty());
}

TEST(RoomModelTest, ClassifiesWallContactAndFreeObjectsAndCompleteness) {
  auto lines = Room();
  // Wall-contact box against the left wall: its three visible sides.
  lines.push_back(Line(6, 0.02, 1.5, 0.6, 1.5));
  lines.push_back(Line(7, 0.6, 1.52, 0.6, 2.48));
  lines.push_back(Line(8, 0.6, 2.5, 0.02, 2.5));
  // A free box seen from two sides only, and a complete one (sides shortened by 8 cm).
  lines.push_back(Line(9, 1.6, 1.0, 2.2, 1.0));
  lines.push_back(Line(10, 2.2, 1.0, 2.2, 1.6));
  lines.push_back(Line(11, 2.6, 2.6, 3.12, 2.6));
  lines.push_back(Line(12, 3.2, 2.68, 3.2, 3.12));
  lines.push_back(Line(13, 3.12, 3.2, 2.68, 3.2));
  lines.push_back(Line(14, 2.6, 3.12, 2.6, 2.68));
  Modeler m{ModelOptions{}};
  const auto& model = m.Update(lines, Loop());
  ASSERT_EQ(model.objects.size(), 3u);
  const auto& wc = model.objects[0];
  EXPECT_EQ(wc.kind, ObjectKind::kWallContact);
  EXPECT_TRUE(wc.complete);
  EXPECT_EQ(wc.lines, std::vector<int>({6, 7, 8}));
  EXPECT_NEAR(wc.box.xmax, 0.6, 1e-9);
  const auto& partial = model.objects[1];
  EXPECT_EQ(partial.kind, ObjectKind::kFree);
  EXPECT_FALSE(partial.complete);
  EXPECT_EQ(partial.open_ends, 2);
  const auto& full = model.objects[2];
  EXPECT_EQ(full.kind, ObjectKind::kFree);
  EXPECT_TRUE(full.complete);
  EXPECT_NEAR(full.box.xmin, 2.6, 1e-9);
  EXPECT_NEAR(full.box.ymax, 3.2, 1e-9);
  EXPECT_EQ(model.pending(), 1);
}

TEST(RoomModelTest, ObjectIdsAreStableAndGivingUpIsRemembered) {
  auto lines = Room();
  lines.push_back(Line(9, 1.6, 1.0, 2.2, 1.0));
  Modeler m{ModelOptions{}};
  const int id = m.Update(lines, Loop()).objects.at(0).id;
  m.GiveUp(id, "P1 unreachable");
  lines.push_back(Line(10, 2.2, 1.0, 2.2, 1.6));  // more of it seen later
  const auto& model = m.Update(lines, Loop());
  ASSERT_EQ(model.objects.size(), 1u);
  EXPECT_EQ(model.objects[0].id, id);
  EXPECT_TRUE(model.objects[0].given_up);
  EXPECT_EQ(model.objects[0].note, "P1 unreachable");
  EXPECT_EQ(model.pending(), 0);
}

TEST(RoomModelTest, BoxEdgesComeFromTheFacesNotTheEnds) {
  auto lines = Room();
  // A free box 1.5..2.1 x 1.5..2.1 whose horizontal sides were seen 6 cm past the
  // vertical faces (noise at the ends) and the vertical ones 5 cm short.
  lines.push_back(Line(10, 1.44, 1.5, 2.16, 1.5));
  lines.push_back(Line(11, 2.1, 1.55, 2.1, 2.05));
  lines.push_back(Line(12, 2.16, 2.1, 1.44, 2.1));
  lines.push_back(Line(13, 1.5, 2.05, 1.5, 1.55));
  auto traj = Loop();
  for (double a = 0; a < 2 * M_PI; a += 0.1) traj.push_back({0, {1.8 + 0.7 * std::cos(a), 1.8 + 0.7 * std::sin(a), 0}});
  Modeler m{ModelOptions{}};
  const auto& model = m.Update(lines, traj);
  ASSERT_EQ(model.objects.size(), 1u);
  const Box& b = model.objects[0].box;
  EXPECT_NEAR(b.xmin, 1.5, 1e-9);
  EXPECT_NEAR(b.xmax, 2.1, 1e-9);
  EXPECT_NEAR(b.ymin, 1.5, 1e-9);
  EXPECT_NEAR(b.ymax, 2.1, 1e-9);
  EXPECT_TRUE(model.objects[0].complete);
}

TEST(RoomModelTest, AnUnseenFaceLiesAtTheMeanOfTheEndsThatReachIt) {
  auto lines = Room();
  // A free box 1.5..2.1 x 1.5..2.1, its right face never mapped: the bottom side
  // was seen 5 cm past the corner, the top one 3 cm short of it.
  lines.push_back(Line(10, 1.5, 1.5, 2.15, 1.5));
  lines.push_back(Line(12, 2.07, 2.1, 1.5, 2.1));
  lines.push_back(Line(13, 1.5, 2.08, 1.5, 1.52));
  Modeler m{ModelOptions{}};
  const auto& model = m.Update(lines, Loop());
  ASSERT_EQ(model.objects.size(), 1u);
  EXPECT_NEAR(model.objects[0].box.xmax, 2.11, 1e-9);
  EXPECT_NEAR(model.objects[0].box.xmin, 1.5, 1e-9);
}

TEST(RoomModelTest, ABoxInACornerOfTheRoomIsCompleteWithItsTwoFreeSides) {
  // Room walls in pieces around a box in the top-left corner (x 0..0.7, y 3.2..4).
  std::vector<slam::LineFeature> lines = {Line(1, 0, 0, 4, 0), Line(2, 4, 0, 4, 4), Line(3, 4, 4, 0.7, 4),
                                          Line(4, 0, 3.2, 0, 0)};
  lines.push_back(Line(6, 0.7, 3.98, 0.7, 3.2));   // its right side
  lines.push_back(Line(7, 0.68, 3.2, 0.02, 3.2));  // its bottom side
  Modeler m{ModelOptions{}};
  const auto& model = m.Update(lines, Loop());
  ASSERT_EQ(model.objects.size(), 1u);
  EXPECT_EQ(model.objects[0].kind, ObjectKind::kWallContact);
  EXPECT_EQ(model.objects[0].open_ends, 0);
  EXPECT_TRUE(model.objects[0].complete);
}

TEST(RoomModelTest, SidesInsideAFollowedContourAreOneObject) {
  // Compound furniture: a box 1.3..2.1 x 2.2..2.8 and a taller one 2.1..2.5 x
  // 2.2..3.0. Mapped: the bottom (both), the right side and the top of the
  // first box; the 0.2 m step and the second box's top were never long enough
  // to map, nor the left side.
  auto lines = Room();
  lines.push_back(Line(12, 2.5, 2.99, 2.5, 2.19));
  lines.push_back(Line(13, 2.47, 2.2, 1.24, 2.2));
  lines.push_back(Line(14, 2.06, 2.8, 1.28, 2.8));
  auto traj = Loop();
  std::vector<Eigen::Vector2d> loop;
  for (double a = 0; a < 2 * M_PI; a += 0.1) {
    const Eigen::Vector2d p(1.9 + 1.0 * std::cos(a), 2.6 + 0.8 * std::sin(a));
    loop.push_back(p);
    traj.push_back({0, {p.x(), p.y(), 0}});
  }
  // (Their boxes touch, and model.merge_touching_m alone joins them too: off
  // here, to test the contour.)
  ModelOptions apart;
  apart.merge_touching_m = 0;
  Modeler m{apart};
  // Without the loop: two objects (the top of the first box meets nothing).
  EXPECT_EQ(m.Update(lines, traj).objects.size(), 2u);
  const int id = m.model().objects[0].id;
  EXPECT_TRUE(m.CloseByContour(id, loop, lines, traj));
  ASSERT_EQ(m.model().objects.size(), 1u);
  const ObjectModel& o = m.model().objects[0];
  EXPECT_EQ(o.lines, std::vector<int>({12, 13, 14}));
  EXPECT_TRUE(o.complete);
  EXPECT_NEAR(o.box.xmax, 2.5, 1e-9);
  EXPECT_NEAR(o.box.ymin, 2.2, 1e-9);
}

// A box against the bottom wall (x 1.5..2.3, y 0..0.6) whose right side was
// never mapped (a short side turned round on an outer corner), and the robot's
// way along its free sides: up beside the left side, over the top, down beside
// the right side (`right_side_offset_m` off it), then along the wall away.
struct AlongWall {
  std::vector<slam::LineFeature> lines;
  std::vector<TimedPose> trajectory;
  std::vector<Eigen::Vector2d> trace;
};
AlongWall BoxOnTheBottomWall(double right_side_offset_m) {
  AlongWall a;
  a.lines = Room();
  a.lines.push_back(Line(6, 1.5, 0.02, 1.5, 0.58));
  a.lines.push_back(Line(7, 1.52, 0.6, 2.28, 0.6));
  for (const auto& p : Loop()) {
    if (p.pose.y > 0.5) a.trajectory.push_back(p);  // not the bottom run: it crosses the box
  }
  const double right = 2.3 + right_side_offset_m;
  for (double y = 0.4; y <= 1.0; y += 0.1) a.trace.emplace_back(1.1, y);
  for (double x = 1.1; x <= right; x += 0.1) a.trace.emplace_back(x, 1.0);
  for (double y = 1.0; y >= 0.4; y -= 0.1) a.trace.emplace_back(right, y);
  for (double x = right; x <= 3.6; x += 0.1) a.trace.emplace_back(x, 0.4);
  for (const auto& p : a.trace) a.trajectory.push_back({0, {p.x(), p.y(), 0}});
  return a;
}

TEST(RoomModelTest, AWallContactObjectsLastSideIsInferredWhereItsFreeSidesWereFollowedPast) {
  const AlongWall a = BoxOnTheBottomWall(0.4);  // the follow distance
  Modeler m{ModelOptions{}};
  ASSERT_EQ(m.Update(a.lines, a.trajectory).objects.size(), 1u);
  const ObjectModel& before = m.model().objects[0];
  EXPECT_EQ(before.kind, ObjectKind::kWallContact);
  EXPECT_FALSE(before.complete);  // two of its three free sides
  const int id = before.id;
  EXPECT_TRUE(m.CloseAlongWall(id, a.trace, a.lines, a.trajectory));
  const ObjectModel& o = m.model().objects[0];
  EXPECT_EQ(o.id, id);
  EXPECT_TRUE(o.complete);
  EXPECT_EQ(o.note, "one side inferred from the contour along the wall");
  EXPECT_NEAR(o.box.xmax, 2.28, 1e-9);
  EXPECT_NEAR(o.box.ymax, 0.6, 1e-9);
  // Kept by later updates (a new line elsewhere).
  auto more = a.lines;
  more.push_back(Line(20, 3.0, 3.0, 3.5, 3.0));
  EXPECT_TRUE(m.Update(more, a.trajectory).objects[0].complete);
}

TEST(RoomModelTest, NoSideIsInferredWhereTheRobotDidNotGoPast) {
  // The robot went past 0.8 m off the right side: the side may be anywhere
  // within, or the box have a step there.
  {
    const AlongWall a = BoxOnTheBottomWall(0.8);
    Modeler m{ModelOptions{}};
    const int id = m.Update(a.lines, a.trajectory).objects[0].id;
    EXPECT_FALSE(m.CloseAlongWall(id, a.trace, a.lines, a.trajectory));
  }
  // It followed the left side only and left along the wall the other way.
  {
    AlongWall a = BoxOnTheBottomWall(0.4);
    a.trace.clear();
    for (double y = 1.0; y >= 0.4; y -= 0.1) a.trace.emplace_back(1.1, y);
    for (double x = 1.1; x >= 0.4; x -= 0.1) a.trace.emplace_back(x, 0.4);
    Modeler m{ModelOptions{}};
    const int id = m.Update(a.lines, a.trajectory).objects[0].id;
    EXPECT_FALSE(m.CloseAlongWall(id, a.trace, a.lines, a.trajectory));
    EXPECT_FALSE(m.model().objects[0].complete);
  }
}

TEST(RoomModelTest, ASideInferredAlongTheWallStaysInferredInASavedMap) {
  const AlongWall a = BoxOnTheBottomWall(0.4);
  Modeler m{ModelOptions{}};
  const int id = m.Update(a.lines, a.trajectory).objects[0].id;
  ASSERT_TRUE(m.CloseAlongWall(id, a.trace, a.lines, a.trajectory));
  // A mission continuing in the saved map (no trace of its own yet): still complete.
  Modeler next{ModelOptions{}};
  next.Seed(m.model(), a.trajectory);
  const ObjectModel& again = next.Update(a.lines, {}).objects[0];
  EXPECT_EQ(again.id, id);
  EXPECT_TRUE(again.complete);
  EXPECT_EQ(again.note, "one side inferred from the contour along the wall");
}

// A free box x 1.5..2.3 standing `gap_m` above the bottom wall, three sides
// mapped (left, top, right); the robot followed them and met the wall in the
// gap below it.
AlongWall FreeBoxAboveTheBottomWall(double gap_m) {
  AlongWall a;
  a.lines = Room();
  const double y0 = gap_m, y1 = gap_m + 0.6;
  a.lines.push_back(Line(6, 1.5, y0, 1.5, y1 - 0.02));
  a.lines.push_back(Line(7, 1.52, y1, 2.28, y1));
  a.lines.push_back(Line(8, 2.3, y1 - 0.02, 2.3, y0));
  for (const auto& p : Loop()) {
    if (p.pose.y > 0.5) a.trajectory.push_back(p);
  }
  for (double y = y0; y <= y1 + 0.4; y += 0.1) a.trace.emplace_back(1.1, y);
  for (double x = 1.1; x <= 2.7; x += 0.1) a.trace.emplace_back(x, y1 + 0.4);
  for (double y = y1 + 0.4; y >= 0.4; y -= 0.1) a.trace.emplace_back(2.7, y);
  for (double x = 2.7; x <= 3.6; x += 0.1) a.trace.emplace_back(x, 0.4);  // along the wall, away
  for (const auto& p : a.trace) a.trajectory.push_back({0, {p.x(), p.y(), 0}});
  return a;
}

TEST(RoomModelTest, AFreeObjectsSideFacingAWallTooNearToGoBetweenIsInferredOnceLeftThere) {
  const AlongWall a = FreeBoxAboveTheBottomWall(0.6);  // the robot needs 0.85 m
  Modeler m{ModelOptions{}};
  ASSERT_EQ(m.Update(a.lines, a.trajectory).objects.size(), 1u);
  const int id = m.model().objects[0].id;
  EXPECT_EQ(m.model().objects[0].kind, ObjectKind::kFree);
  EXPECT_FALSE(m.model().objects[0].complete);  // not before the robot has tried to go round
  EXPECT_TRUE(m.CloseNearWall(id, a.lines, a.trajectory));
  const ObjectModel& o = m.model().objects[0];
  EXPECT_EQ(o.id, id);
  EXPECT_TRUE(o.complete);
  EXPECT_EQ(o.kind, ObjectKind::kFree);
  EXPECT_EQ(o.note, "the side facing the wall inferred (too near it to go between)");
  EXPECT_NEAR(o.box.ymin, 0.6, 1e-9);  // from its sides' ends
  // Kept by later updates, and in a saved map.
  auto more = a.lines;
  more.push_back(Line(20, 3.0, 3.0, 3.5, 3.0));
  EXPECT_TRUE(m.Update(more, a.trajectory).objects[0].complete);
  Modeler next{ModelOptions{}};
  next.Seed(m.model(), a.trajectory);
  EXPECT_TRUE(next.Update(a.lines, {}).objects[0].complete);
  EXPECT_EQ(next.model().objects[0].note, "the side facing the wall inferred (too near it to go between)");
  // Many updates later: the note is not repeated.
  for (int i = 0; i < 50; ++i) m.Update(more, a.trajectory);
  EXPECT_EQ(m.model().objects[0].note, "the side facing the wall inferred (too near it to go between)");
}

TEST(RoomModelTest, NoSideFacingAWallIsInferredWhereTheRobotCouldGoBetween) {
  {
    const AlongWall a = FreeBoxAboveTheBottomWall(1.0);
    Modeler m{ModelOptions{}};
    const int id = m.Update(a.lines, a.trajectory).objects[0].id;
    EXPECT_FALSE(m.CloseNearWall(id, a.lines, a.trajectory));
    EXPECT_FALSE(m.model().objects[0].complete);
  }
  {  // Off.
    const AlongWall a = FreeBoxAboveTheBottomWall(0.6);
    ModelOptions off;
    off.narrow_gap_m = 0;
    Modeler m{off};
    const int id = m.Update(a.lines, a.trajectory).objects[0].id;
    EXPECT_FALSE(m.CloseNearWall(id, a.lines, a.trajectory));
  }
  {  // Two sides mapped: where the others are is not known.
    AlongWall a = FreeBoxAboveTheBottomWall(0.6);
    a.lines.pop_back();
    Modeler m{ModelOptions{}};
    const int id = m.Update(a.lines, a.trajectory).objects[0].id;
    EXPECT_FALSE(m.CloseNearWall(id, a.lines, a.trajectory));
  }
  {  // The side not mapped faces into the room (the top one): not inferred.
    AlongWall a = FreeBoxAboveTheBottomWall(0.6);
    a.lines[a.lines.size() - 2] = Line(7, 1.52, 0.6, 2.28, 0.6);  // the bottom seen, not the top
    for (double x = 1.5; x <= 2.3; x += 0.1) a.trajectory.push_back({0, {x, 0.3, 0}});
    Modeler m{ModelOptions{}};
    const int id = m.Update(a.lines, a.trajectory).objects[0].id;
    EXPECT_FALSE(m.CloseNearWall(id, a.lines, a.trajectory));
  }
}

// A free box x 1.5..2.3, y 1.4..2.0 in the middle of the room, three sides
// mapped (left, top, right; its bottom a short side never mapped), and the
// robot's contour round it: up the left, over the top, down the right, and,
// if `past_bottom`, back under the bottom before it is drawn off down to the
// wall (it leaves before it has turned a full contour).
// (`x1`: its right side; the contour keeps 0.4 m off.)
AlongWall FreeBoxInTheRoom(bool past_bottom, double x1 = 2.3) {
  AlongWall a;
  a.lines = Room();
  const double y0 = 1.4, y1 = 2.0;
  a.lines.push_back(Line(6, 1.5, y0 + 0.02, 1.5, y1 - 0.02));
  a.lines.push_back(Line(7, 1.52, y1, x1 - 0.02, y1));
  a.lines.push_back(Line(8, x1, y1 - 0.02, x1, y0 + 0.02));
  a.trajectory = Loop();
  const double right = x1 + 0.4;
  for (double y = y0; y <= y1 + 0.4; y += 0.1) a.trace.emplace_back(1.1, y);
  for (double x = 1.1; x <= right; x += 0.1) a.trace.emplace_back(x, y1 + 0.4);
  if (past_bottom) {
    for (double y = y1 + 0.4; y >= y0 - 0.4; y -= 0.1) a.trace.emplace_back(right, y);
    for (double x = right; x >= 1.1; x -= 0.1) a.trace.emplace_back(x, y0 - 0.4);
    for (double y = y0 - 0.4; y >= 0.4; y -= 0.1) a.trace.emplace_back(1.1, y);
  } else {
    // Down the right side past its end, and off to the right wall.
    for (double y = y1 + 0.4; y >= y0 - 0.4; y -= 0.1) a.trace.emplace_back(right, y);
    for (double x = right; x <= 3.6; x += 0.1) a.trace.emplace_back(x, y0 - 0.4);
  }
  for (const auto& p : a.trace) a.trajectory.push_back({0, {p.x(), p.y(), 0}});
  return a;
}

TEST(RoomModelTest, AFreeObjectsOneSideNotMappedIsInferredWhereItsContourWentPastIt) {
  const AlongWall a = FreeBoxInTheRoom(true);
  Modeler m{ModelOptions{}};
  ASSERT_EQ(m.Update(a.lines, a.trajectory).objects.size(), 1u);
  const int id = m.model().objects[0].id;
  EXPECT_EQ(m.model().objects[0].kind, ObjectKind::kFree);
  EXPECT_FALSE(m.model().objects[0].complete);
  EXPECT_FALSE(m.CloseNearWall(id, a.lines, a.trajectory));  // 1.4 m from the wall: not that
  EXPECT_TRUE(m.CloseAlongWall(id, a.trace, a.lines, a.trajectory));
  const ObjectModel& o = m.model().objects[0];
  EXPECT_EQ(o.id, id);
  EXPECT_TRUE(o.complete);
  EXPECT_EQ(o.kind, ObjectKind::kFree);
  EXPECT_EQ(o.note, "one side inferred from the contour that went past it");
  EXPECT_NEAR(o.box.ymin, 1.42, 1e-9);  // from its sides' ends
  // Kept in a saved map, with its note.
  Modeler next{ModelOptions{}};
  next.Seed(m.model(), a.trajectory);
  EXPECT_TRUE(next.Update(a.lines, {}).objects[0].complete);
  EXPECT_EQ(next.model().objects[0].note, "one side inferred from the contour that went past it");
}

TEST(RoomModelTest, AFreeObjectsSideTheContourDidNotGoPastIsNotInferred) {
  {  // It left down the right side, never under the box.
    const AlongWall a = FreeBoxInTheRoom(false);
    Modeler m{ModelOptions{}};
    const int id = m.Update(a.lines, a.trajectory).objects[0].id;
    EXPECT_FALSE(m.CloseAlongWall(id, a.trace, a.lines, a.trajectory));
    EXPECT_FALSE(m.model().objects[0].complete);
  }
  {  // A narrow box (0.3 m): down its right side, past the end, is within the band of
     // its bottom's middle, but not beside it.
    const AlongWall a = FreeBoxInTheRoom(false, 1.8);
    Modeler m{ModelOptions{}};
    ASSERT_EQ(m.Update(a.lines, a.trajectory).objects.size(), 1u);
    const int id = m.model().objects[0].id;
    EXPECT_FALSE(m.CloseAlongWall(id, a.trace, a.lines, a.trajectory));
  }
  {  // Two sides mapped: the trace went all round, but where the others are is not known.
    AlongWall a = FreeBoxInTheRoom(true);
    a.lines.pop_back();
    Modeler m{ModelOptions{}};
    const int id = m.Update(a.lines, a.trajectory).objects[0].id;
    EXPECT_FALSE(m.CloseAlongWall(id, a.trace, a.lines, a.trajectory));
  }
  {  // Another target's contour went past it: not its own.
    const AlongWall a = FreeBoxInTheRoom(true);
    Modeler m{ModelOptions{}};
    const int id = m.Update(a.lines, a.trajectory).objects[0].id;
    EXPECT_FALSE(m.CloseAlongWall(id + 1, a.trace, a.lines, a.trajectory));
    EXPECT_FALSE(m.model().objects[0].complete);
    EXPECT_TRUE(m.CloseAlongWall(id, a.trace, a.lines, a.trajectory));  // its own: yes
  }
}

TEST(RoomModelTest, IncompleteObjectsWhoseBoxesTouchArePiecesOfOne) {
  // Compound furniture: a box 1.5..2.0 x 1.5..2.0 seen from below and the left,
  // and a lower one 2.0..2.6 x 1.5..1.8 beside it seen from the right and above;
  // the step between them and the tall box's top were never mapped, and no
  // corner joins the two pairs of sides.
  auto lines = Room();
  lines.push_back(Line(6, 1.5, 1.5, 2.0, 1.5));
  lines.push_back(Line(7, 1.5, 2.0, 1.5, 1.5));
  lines.push_back(Line(8, 2.6, 1.5, 2.6, 1.8));
  lines.push_back(Line(9, 2.6, 1.8, 2.0, 1.8));
  auto traj = Loop();
  for (double x = 2.0; x <= 2.6; x += 0.1) traj.push_back({0, {x, 2.3, 0}});
  ModelOptions apart;
  apart.merge_touching_m = 0;
  Modeler separate{apart};
  EXPECT_EQ(separate.Update(lines, traj).objects.size(), 2u);
  Modeler m{ModelOptions{}};
  const auto& model = m.Update(lines, traj);
  ASSERT_EQ(model.objects.size(), 1u);
  EXPECT_EQ(model.objects[0].lines, std::vector<int>({6, 7, 8, 9}));
  EXPECT_NEAR(model.objects[0].box.xmin, 1.5, 1e-9);
  EXPECT_NEAR(model.objects[0].box.xmax, 2.6, 1e-9);
  // 25 cm apart: two pieces.
  lines.resize(lines.size() - 2);
  lines.push_back(Line(8, 2.85, 1.5, 2.85, 1.8));
  lines.push_back(Line(9, 2.85, 1.8, 2.25, 1.8));
  for (double x = 2.25; x <= 2.85; x += 0.1) traj.push_back({0, {x, 2.3, 0}});
  Modeler far{ModelOptions{}};
  EXPECT_EQ(far.Update(lines, traj).objects.size(), 2u);
}

// The one corner rule (corner_m 0.35: loose 0.525, tight 0.1).
TEST(RoomModelTest, TheCornerRule) {
  using room_geometry::CornerEnd;
  using room_geometry::MakeCorner;
  // Both ends near the corner.
  EXPECT_TRUE(MakeCorner(CornerEnd{0.2, false}, CornerEnd{0.3, false}, 0.35));
  // One end near it, the other side runs past it.
  EXPECT_TRUE(MakeCorner(CornerEnd{0.3, false}, CornerEnd{1.0, true}, 0.35));
  // Both far: no corner.
  EXPECT_FALSE(MakeCorner(CornerEnd{0.4, false}, CornerEnd{0.4, false}, 0.35));
  // One ends right at it, the other was seen short of it by less than 1.5 corner_m ...
  EXPECT_TRUE(MakeCorner(CornerEnd{0.05, false}, CornerEnd{0.5, false}, 0.35));
  EXPECT_TRUE(MakeCorner(CornerEnd{0.5, false}, CornerEnd{0.05, false}, 0.35));
  // ... but not by more.
  EXPECT_FALSE(MakeCorner(CornerEnd{0.05, false}, CornerEnd{0.6, false}, 0.35));
  EXPECT_FALSE(MakeCorner(CornerEnd{0.12, false}, CornerEnd{0.5, false}, 0.35));
  // Within neither side's extent nor near an end of the other: no corner.
  EXPECT_FALSE(MakeCorner(CornerEnd{0.3, false}, CornerEnd{0.6, false}, 0.35));
}

// A free 0.6 x 0.6 box (sides shortened by 8 cm, as mapped) at x0, y0, ids from id.
std::vector<slam::LineFeature> Box06(int id, double x0, double y0) {
  const double x1 = x0 + 0.6, y1 = y0 + 0.6;
  return {Line(id, x0, y0, x1 - 0.08, y0), Line(id + 1, x1, y0 + 0.08, x1, y1 - 0.08),
          Line(id + 2, x1 - 0.08, y1, x0 + 0.08, y1), Line(id + 3, x0, y1 - 0.08, x0, y0 + 0.08)};
}

// The saved map of the moved-piece tests: the room and one free 0.6 m box at
// (2.6, 2.6) (lines 11-14), modelled complete.
struct SavedBox {
  std::vector<slam::LineFeature> lines = Room();
  EnvironmentModel model;
  SavedBox() {
    for (const auto& l : Box06(11, 2.6, 2.6)) lines.push_back(l);
    Modeler before{ModelOptions{}};
    model = before.Update(lines, Loop());
  }
};

TEST(RoomModelTest, AMovedPieceModelledAsNewBeforeItWasFoundMissingTakesItsIdButNotAtItsOldPlace) {
  // The saved map: one free box at (2.6, 2.6).
  const SavedBox box;
  const auto& saved_lines = box.lines;
  const EnvironmentModel& saved = box.model;
  ASSERT_EQ(saved.objects.size(), 1u);
  const ObjectModel piece = saved.objects[0];
  ASSERT_TRUE(piece.complete);

  // Today it stands 1.6 m to the left; mapped there (new lines 21-24) before
  // the check finds its old sides missing: a new object.
  Modeler m{ModelOptions{}};
  m.Seed(saved, Loop());
  auto lines = saved_lines;
  for (const auto& l : Box06(21, 1.0, 2.6)) lines.push_back(l);
  const EnvironmentModel& first = m.Update(lines, Loop());
  ASSERT_EQ(first.objects.size(), 2u);
  const auto at_new = [](const EnvironmentModel& model) {
    return std::find_if(model.objects.begin(), model.objects.end(),
                        [](const ObjectModel& o) { return o.box.xmin < 2; });
  };
  const int fresh = at_new(first)->id;
  EXPECT_NE(fresh, piece.id);
  EXPECT_EQ(at_new(first)->note, "new since the saved map");

  // Found missing: its old sides are still in the map for this call (they
  // leave it after), and the object they make is not taken for the piece.
  m.NoteMoved(piece.id, piece.box);
  EXPECT_TRUE(m.moved_unplaced());
  const EnvironmentModel& second = m.Update(lines, Loop());
  ASSERT_EQ(second.objects.size(), 2u);
  EXPECT_EQ(at_new(second)->id, piece.id);
  EXPECT_EQ(at_new(second)->note, "moved since the saved map by 160 cm (was at [260, 260, 320, 320] cm)");
  for (const auto& o : second.objects) {
    if (o.box.xmin > 2) {
      EXPECT_EQ(o.note, "new since the saved map");
    }
  }
  EXPECT_FALSE(m.moved_unplaced());

  // The old sides out of the map: the piece keeps its id and its note.
  auto after = Room();
  for (const auto& l : Box06(21, 1.0, 2.6)) after.push_back(l);
  const EnvironmentModel& third = m.Update(after, Loop());
  ASSERT_EQ(third.objects.size(), 1u);
  EXPECT_EQ(third.objects[0].id, piece.id);
  EXPECT_TRUE(third.objects[0].complete);
  EXPECT_EQ(third.objects[0].note.rfind("moved since the saved map by 160 cm", 0), 0u);
}

TEST(RoomModelTest, AMovedPieceGivenUpWithThreeSidesOfItsSizeTakesItsIdAndKeepsBothNotes) {
  // The saved map: one free box at (2.6, 2.6). It was found missing; today it
  // stands at (1.0, 2.6) in a tight spot: one side is mapped first (a new
  // object: not the piece's size), then two more, and the contour following
  // times out (Fig. 16's desk moved 0.5 m towards a wall).
  const SavedBox box;
  const EnvironmentModel& saved = box.model;
  ASSERT_EQ(saved.objects.size(), 1u);
  const ObjectModel piece = saved.objects[0];

  Modeler m{ModelOptions{}};
  m.Seed(saved, Loop());
  m.NoteMoved(piece.id, piece.box);
  const auto sides = Box06(21, 1.0, 2.6);
  auto lines = Room();
  lines.push_back(sides[0]);
  const EnvironmentModel& one = m.Update(lines, Loop());
  ASSERT_EQ(one.objects.size(), 1u);
  const int fresh = one.objects[0].id;
  EXPECT_NE(fresh, piece.id);
  EXPECT_EQ(one.objects[0].note, "new since the saved map");
  // Three sides, still open and not given up: its box may not be its size yet.
  lines.push_back(sides[1]);
  lines.push_back(sides[2]);
  const EnvironmentModel& open = m.Update(lines, Loop());
  ASSERT_EQ(open.objects.size(), 1u);
  EXPECT_FALSE(open.objects[0].complete);
  EXPECT_EQ(open.objects[0].id, fresh);
  EXPECT_TRUE(m.moved_unplaced());

  // Given up with three sides spanning the piece's size: it is the piece (the
  // unseen left face at the mean of the ends that reach it, x 1.04: 158 cm).
  m.GiveUp(fresh, "contour following timed out");
  const EnvironmentModel& given_up = m.Update(lines, Loop());
  ASSERT_EQ(given_up.objects.size(), 1u);
  EXPECT_EQ(given_up.objects[0].id, piece.id);
  EXPECT_TRUE(given_up.objects[0].given_up);
  EXPECT_FALSE(m.moved_unplaced());
  // And stays so, both notes kept, "moved" first.
  const EnvironmentModel& later = m.Update(lines, Loop());
  ASSERT_EQ(later.objects.size(), 1u);
  EXPECT_EQ(later.objects[0].id, piece.id);
  EXPECT_TRUE(later.objects[0].given_up);
  EXPECT_EQ(later.objects[0].note,
            "moved since the saved map by 158 cm (was at [260, 260, 320, 320] cm); contour following timed out");
}

TEST(PathPlannerTest, LeavesATightSpotEvenFromWithinTheHardClearance) {
  PlannerOptions o;
  // The robot stands 0.12 m from a mapped side's (extended) end: within hard_m.
  const std::vector<Obstacle> obs = {{{0, 0}, {1, 0}}};
  const auto path = PlanPath(obs, {1.05, 0.11}, {2.0, 1.0}, o);
  ASSERT_TRUE(path);
  // Its first step leads away from the side.
  const Eigen::Vector2d first = (*path)[1];
  EXPECT_GT(first.y(), 0.11);
  // It never goes nearer to the side than it stands, and is clear of the hard
  // clearance after leaving.
  for (size_t i = 0; i + 1 < path->size(); ++i) {
    for (double u = 0; u <= 1; u += 0.02) {
      const Eigen::Vector2d p = (*path)[i] + u * ((*path)[i + 1] - (*path)[i]);
      const double d = p.x() > 1 ? (p - Eigen::Vector2d(1, 0)).norm() : std::abs(p.y());
      EXPECT_GE(d, 0.11 - 1e-9) << p.transpose();
      if ((p - Eigen::Vector2d(1.05, 0.11)).norm() > 0.3) {
        EXPECT_GE(d, o.hard_m - 0.03) << p.transpose();
      }
    }
  }
}

TEST(PathPlannerTest, TellsWhetherAPathIsStillClear) {
  const std::vector<Obstacle> obs = {{{1, -1}, {1, 1}}};
  const std::vector<Eigen::Vector2d> around = {{0, 0}, {0, 1.5}, {2, 1.5}, {2, 0}};
  const std::vector<Eigen::Vector2d> through = {{0, 0}, {2, 0}};
  EXPECT_NEAR(PathLength(around), 1.5 + 2 + 1.5, 1e-12);
  EXPECT_TRUE(PathClear(obs, around, 0.3, 0.0));
  EXPECT_FALSE(PathClear(obs, through, 0.3, 0.0));
  EXPECT_FALSE(PathClear(obs, around, 0.6, 0.0));  // passes the segment's end at 0.5
  // Near the start the robot may stand closer.
  EXPECT_TRUE(PathClear({{{0, -0.1}, {0, -1}}}, around, 0.3, 0.3));
  EXPECT_FALSE(PathClear({{{0, -0.1}, {0, -1}}}, around, 0.3, 0.0));
}

TEST(PathPlannerTest, GoesAroundAnObstacleKeepingTheClearance) {
  PlannerOptions o;
  std::vector<Obstacle> obs = {{{1, -1}, {1, 1}}};  // a wall segment between start and goal
  const auto path = PlanPath(obs, {0, 0}, {2, 0}, o);
  ASSERT_TRUE(path);
  EXPECT_GE(path->size(), 3u);
  // Every straight leg stays clear of the segment by the inflation (within a cell).
  for (size_t i = 0; i + 1 < path->size(); ++i) {
    for (double u = 0; u <= 1; u += 0.02) {
      const Eigen::Vector2d p = (*path)[i] + u * ((*path)[i + 1] - (*path)[i]);
      const double d = p.y() > 1 ? (p - Eigen::Vector2d(1, 1)).norm()
                       : p.y() < -1 ? (p - Eigen::Vector2d(1, -1)).norm() : std::abs(p.x() - 1);
      EXPECT_GT(d, o.inflation_m - 0.05) << p.transpose();
    }
  }
  // A closed room divided in two: the goal's half cannot be reached.
  EXPECT_FALSE(PlanPath({{{-1, 1}, {3, 1}}, {{-1, -1}, {3, -1}}, {{-1, -1}, {-1, 1}}, {{3, -1}, {3, 1}},
                         {{1, -1}, {1, 1}}},
                        {0, 0}, {2, 0}, o));
}

}  // namespace
}  // namespace irslam::control
