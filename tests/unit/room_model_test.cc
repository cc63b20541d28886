#include <gtest/gtest.h>

#include "control/path_planner.h"
#include "control/room_model.h"

namespace irslam::control {
namespace {

slam::LineFeature Line(int id, double x0, double y0, double x1, double y1) {
  slam::LineFeature l;
  l.id = id;
  l.p0 = {x0, y0};
  l.p1 = {x1, y1};
  const Eigen::Vector2d d = (l.p1 - l.p0).normalized();
  l.theta = std::atan2(d.x(), -d.y());  // normal = d rotated by -90 deg
  l.rho = l.p0.dot(Eigen::Vector2d(std::cos(l.theta), std::sin(l.theta)));
  if (l.rho < 0) {
    l.rho = -l.rho;
    l.theta = NormalizeAngle(l.theta + M_PI);
  }
  return l;
}

// A 4 x 4 room walked at 0.4 m from its walls (the trajectory tells which side
// each line was seen from).
std::vector<slam::TrajectoryPoint> Loop() {
  std::vector<slam::TrajectoryPoint> t;
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
