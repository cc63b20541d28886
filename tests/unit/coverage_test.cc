// Coverage planning (control/coverage.h): cell counts and areas on known shapes,
// lanes clear of every object, a tour that visits every cell, the covered-floor grid.
#include "control/coverage.h"

#include "control/clean.h"

#include <gtest/gtest.h>

#include <cmath>

namespace irslam::control {
namespace {

constexpr double kRadius = 0.17;

CleaningOptions Options() {
  CleaningOptions o;
  o.clearance_m = 0.03;  // inflation 0.2 m
  o.edge_clearance_m = 0.03;  // the edge pass on the cell boundary (unless a test says otherwise)
  o.cleaning_width_m = 0.34;
  o.overlap_m = 0.04;  // lanes 0.3 m apart
  o.both_directions = false;  // lanes along y, the sweep along x (unless a test says otherwise)
  return o;
}

double TotalArea(const std::vector<CoverageCell>& cells) {
  double a = 0;
  for (const auto& c : cells) a += c.area_m2();
  return a;
}

// Distance from p to a box (0 inside).
double BoxDistance(const Box& b, const Eigen::Vector2d& p) {
  const double dx = std::max({b.xmin - p.x(), 0.0, p.x() - b.xmax});
  const double dy = std::max({b.ymin - p.y(), 0.0, p.y() - b.ymax});
  return std::hypot(dx, dy);
}

// The least distance of a polyline's points (sampled every 1 cm) to the box.
double RouteClearance(const std::vector<Eigen::Vector2d>& r, const Box& b) {
  double least = 1e9;
  for (size_t k = 1; k < r.size(); ++k) {
    const double len = (r[k] - r[k - 1]).norm();
    const int n = std::max(1, static_cast<int>(len / 0.01));
    for (int i = 0; i <= n; ++i) {
      least = std::min(least, BoxDistance(b, r[k - 1] + (r[k] - r[k - 1]) * i / n));
    }
  }
  return least;
}

TEST(CoverageTest, AnEmptyRoomIsOneCellOfTheShrunkRoom) {
  CleaningOptions o = Options();
  o.both_directions = false;
  const CoveragePlan p = PlanCoverage({0, 0, 4, 3}, {}, {}, {1, 1}, kRadius, o);
  ASSERT_EQ(p.cells.size(), 1u);
  EXPECT_NEAR(p.cells[0].area_m2(), 3.6 * 2.6, 1e-9);
  ASSERT_EQ(p.routes.size(), 1u);
  // 3.6 m wide at 0.3 m: 13 lanes, the first and last in the edge pass.
  int up_or_down = 0;
  for (size_t k = 1; k < p.routes[0].size(); ++k) {
    const Eigen::Vector2d d = p.routes[0][k] - p.routes[0][k - 1];
    if (std::abs(d.x()) < 1e-9 && std::abs(std::abs(d.y()) - 2.6) < 1e-9) ++up_or_down;
  }
  EXPECT_EQ(up_or_down, 13);
  // Edge pass (2 x 3.6 + 2 x 2.6) + 11 inner lanes of 2.6 + 11 steps of 0.3.
  EXPECT_NEAR(p.route_length_m, 12.4 + 11 * 2.6 + 11 * 0.3, 1e-6);
}

TEST(CoverageTest, AFreeBoxInTheMiddleMakesFourCells) {
  const Box box{1.5, 1.0, 2.5, 2.0};
  CleaningOptions o = Options();
  o.both_directions = false;  // lanes along y: the sweep goes along x
  const CoveragePlan p = PlanCoverage({0, 0, 4, 3}, {box}, {}, {0.5, 0.5}, kRadius, o);
  ASSERT_EQ(p.cells.size(), 4u);  // left, below, above, right
  EXPECT_NEAR(TotalArea(p.cells), 3.6 * 2.6 - 1.4 * 1.4, 1e-9);
  std::vector<double> areas;
  for (const auto& c : p.cells) areas.push_back(c.area_m2());
  std::sort(areas.begin(), areas.end());
  EXPECT_NEAR(areas[0], 1.4 * 0.6, 1e-9);  // below: 1.4 wide, 0.2 .. 0.8
  EXPECT_NEAR(areas[1], 1.4 * 0.6, 1e-9);  // above: 2.2 .. 2.8
  EXPECT_NEAR(areas[2], 1.1 * 2.6, 1e-9);  // left: 0.2 .. 1.3
  EXPECT_NEAR(areas[3], 1.1 * 2.6, 1e-9);  // right: 2.7 .. 3.8
  // Left and right each touch both middle cells, and they each both sides.
  for (const auto& c : p.cells) EXPECT_EQ(c.neighbours.size(), 2u) << "cell " << c.id;
}

TEST(CoverageTest, WallContactBoxesChangeNoConnectivity) {
  // A box against the bottom wall and one against the top wall, not overlapping
  // in x: the free space stays one piece in every slab, so one cell.
  const std::vector<Box> objects = {{1.0, 0, 1.8, 0.8}, {2.5, 2.2, 3.2, 3.0}};
  const CoveragePlan p = PlanCoverage({0, 0, 4, 3}, objects, {}, {0.5, 1.5}, kRadius, Options());
  ASSERT_EQ(p.cells.size(), 1u);
  EXPECT_NEAR(p.cells[0].area_m2(), 3.6 * 2.6 - 1.2 * 0.8 - 1.1 * 0.8, 1e-9);
}

TEST(CoverageTest, AGapWiderThanTheRobotIsCleanedThroughNarrowerIsNot) {
  // Two boxes from the bottom and top walls leave a gap between them.
  const auto cells_with_gap = [](double gap) {
    const std::vector<Box> objects = {{1.5, 0, 2.5, 1.5 - gap / 2}, {1.5, 1.5 + gap / 2, 2.5, 3}};
    return PlanCoverage({0, 0, 4, 3}, objects, {}, {0.5, 1.5}, kRadius, Options()).cells;
  };
  // 0.5 m > 2 x 0.2 m: the gap is free space (a cell of its own between left and right).
  const auto wide = cells_with_gap(0.5);
  ASSERT_EQ(wide.size(), 1u);  // one-to-one all along: left, gap, right are one cell
  EXPECT_NEAR(wide[0].area_m2(), 3.6 * 2.6 - 1.4 * 2.5, 1e-9);
  // 0.35 m < 0.4 m: no way through, the left and right parts are separate cells.
  EXPECT_EQ(cells_with_gap(0.35).size(), 2u);
}

TEST(CoverageTest, LanesNeverCrossAnObjectAndTheTourVisitsEveryCell) {
  const std::vector<Box> objects = {{0, 2.0, 0.6, 3.2}, {1.4, 1.2, 2.2, 1.8}, {2.3, 3.6, 3.0, 4.4}};
  const CleaningOptions o = Options();
  const CoveragePlan p = PlanCoverage({0, 0, 4, 5.5}, objects, {}, {2.0, 0.8}, kRadius, o);
  ASSERT_GE(p.cells.size(), 4u);
  std::vector<int> seen(p.cells.size(), 0);
  for (int i : p.order) ++seen[static_cast<size_t>(i)];
  for (size_t i = 0; i < seen.size(); ++i) EXPECT_EQ(seen[i], 1) << "cell " << i;
  ASSERT_EQ(p.routes.size(), p.cells.size());
  for (const auto& r : p.routes) {
    ASSERT_GE(r.size(), 2u);
    for (const auto& b : objects) EXPECT_GE(RouteClearance(r, b), kRadius + o.clearance_m - 1e-6);
    for (const auto& q : r) {
      EXPECT_GE(q.x(), 0.2 - 1e-9);
      EXPECT_LE(q.x(), 3.8 + 1e-9);
      EXPECT_GE(q.y(), 0.2 - 1e-9);
      EXPECT_LE(q.y(), 5.3 + 1e-9);
    }
  }
  // The sweep is not much longer than the area over the lane spacing.
  const double area = TotalArea(p.cells);
  EXPECT_LT(p.route_length_m, 1.6 * area / p.lane_spacing_m + 15);
}

TEST(CoverageTest, TheEdgePassRunsCloserToTheWallsThanTheLanes) {
  CleaningOptions o = Options();
  o.clearance_m = 0.05;       // lanes 0.22 m from the walls
  o.edge_clearance_m = 0.01;  // the edge pass 0.18 m
  const CoveragePlan p = PlanCoverage({0, 0, 4, 3}, {}, {}, {0.3, 0.3}, kRadius, o);
  EXPECT_NEAR(p.edge_out_m, 0.04, 1e-12);
  ASSERT_EQ(p.routes.size(), 1u);
  const auto& r = p.routes[0];
  // It starts in the cell's corner (where a planner can take it), goes out to
  // the edge pass's corner and round the room 0.18 m from every wall.
  ASSERT_GE(r.size(), 7u);
  EXPECT_NEAR((r[0] - Eigen::Vector2d(0.22, 0.22)).norm(), 0, 1e-9);
  const Eigen::Vector2d loop[] = {{0.18, 0.18}, {3.82, 0.18}, {3.82, 2.82}, {0.18, 2.82}, {0.18, 0.18}};
  for (int k = 0; k < 5; ++k) EXPECT_NEAR((r[1 + k] - loop[k]).norm(), 0, 1e-9) << "point " << 1 + k;
  EXPECT_NEAR((r[6] - Eigen::Vector2d(0.22, 0.22)).norm(), 0, 1e-9);
  // The lanes after it keep the lane clearance.
  for (size_t k = 6; k < r.size(); ++k) {
    EXPECT_GE(r[k].x(), 0.22 - 1e-9);
    EXPECT_LE(r[k].x(), 3.78 + 1e-9);
    EXPECT_GE(r[k].y(), 0.22 - 1e-9);
    EXPECT_LE(r[k].y(), 2.78 + 1e-9);
  }
  // 3.64 m between the edge pass's sides at 0.3 m: 14 lanes, 12 of them inside.
  int lanes = 0;
  for (size_t k = 7; k < r.size(); ++k) {
    const Eigen::Vector2d d = r[k] - r[k - 1];
    if (std::abs(d.x()) < 1e-9 && std::abs(std::abs(d.y()) - 2.56) < 1e-9) ++lanes;
  }
  EXPECT_EQ(lanes, 12);
}

TEST(CoverageTest, TheEdgePassRoundFurnitureKeepsTheEdgeClearanceAndNoLess) {
  const std::vector<Box> objects = {{0, 2.0, 0.6, 3.2}, {1.4, 1.2, 2.2, 1.8}, {2.3, 3.6, 3.0, 4.4}};
  CleaningOptions o = Options();
  o.clearance_m = 0.05;
  o.edge_clearance_m = 0.015;
  for (bool both : {false, true}) {
    o.both_directions = both;
    const CoveragePlan p = PlanCoverage({0, 0, 4, 5.5}, objects, {}, {2.0, 0.8}, kRadius, o);
    ASSERT_EQ(p.routes.size(), p.cells.size());
    std::vector<double> least(objects.size(), 1e9);
    for (const auto& r : p.routes) {
      for (size_t i = 0; i < objects.size(); ++i) least[i] = std::min(least[i], RouteClearance(r, objects[i]));
      for (const auto& q : r) {
        EXPECT_GE(q.x(), 0.185 - 1e-9);
        EXPECT_LE(q.x(), 3.815 + 1e-9);
        EXPECT_GE(q.y(), 0.185 - 1e-9);
        EXPECT_LE(q.y(), 5.315 + 1e-9);
      }
    }
    // Every box is passed at the edge clearance: closer than the lanes, never closer than that.
    for (size_t i = 0; i < objects.size(); ++i) {
      EXPECT_GE(least[i], kRadius + 0.015 - 1e-6) << "box " << i;
      EXPECT_LE(least[i], kRadius + 0.015 + 0.005) << "box " << i;
    }
  }
}

TEST(CoverageTest, AContactBlocksTheFloorRoundIt) {
  const CoveragePlan none = PlanCoverage({0, 0, 4, 3}, {}, {}, {1, 1}, kRadius, Options());
  const CoveragePlan one = PlanCoverage({0, 0, 4, 3}, {}, {{2.0, 1.5}}, {1, 1}, kRadius, Options());
  const double side = 2 * (kRadius + Options().bump_block_m);
  EXPECT_NEAR(TotalArea(none.cells) - TotalArea(one.cells), side * side, 1e-9);
  EXPECT_EQ(one.cells.size(), 4u);
}

TEST(CoverageTest, TheGridCountsTheReachableFloorAndWhatTheBodySwept) {
  const CoveragePlan p = PlanCoverage({0, 0, 4, 3}, {}, {}, {1, 1}, kRadius, Options());
  CoverageGrid g;
  g.Init({0, 0, 4, 3}, p.FreeRects(), 0.17, 0.02);
  // The shrunk room grown by the body radius: all but a 3 cm strip and rounded corners.
  const double expect = 3.6 * 2.6 + 2 * 0.17 * (3.6 + 2.6) + M_PI * 0.17 * 0.17;
  EXPECT_NEAR(g.total_m2(), expect, 0.2);
  EXPECT_EQ(g.covered_m2(), 0);
  for (double x = 0.2; x <= 3.8; x += 0.01) g.Mark({x, 1.5});
  EXPECT_NEAR(g.covered_m2(), 3.6 * 0.34 + M_PI * 0.17 * 0.17, 0.08);
}

TEST(CoverageTest, LanesGoAlongTheLongerSideWhenThatIsShorterInAll) {
  // 6 m x 2 m: lanes along x (2 m / 0.3 m: 7 lanes of 5.6 m) beat lanes along y
  // (20 lanes of 1.6 m and their turns).
  CleaningOptions both = Options();
  both.both_directions = true;
  const CoveragePlan p = PlanCoverage({0, 0, 6, 2}, {}, {}, {1, 1}, kRadius, both);
  EXPECT_TRUE(p.swapped);
  ASSERT_EQ(p.routes.size(), 1u);
  int along_x = 0;
  for (size_t k = 1; k < p.routes[0].size(); ++k) {
    const Eigen::Vector2d d = p.routes[0][k] - p.routes[0][k - 1];
    if (std::abs(d.y()) < 1e-9 && std::abs(std::abs(d.x()) - 5.6) < 1e-9) ++along_x;
  }
  EXPECT_EQ(along_x, 7);
  CleaningOptions o = Options();
  o.both_directions = false;
  const CoveragePlan q = PlanCoverage({0, 0, 6, 2}, {}, {}, {1, 1}, kRadius, o);
  EXPECT_FALSE(q.swapped);
  EXPECT_LT(p.route_length_m + p.transit_length_m, q.route_length_m + q.transit_length_m);
}

// Issue 15: the planner in bounded steps makes exactly PlanCoverage's plan (the
// paper's rooms and an 8 x 6 m one, with contacts, under the options that change
// the plan's shape), in a bounded number of steps.
struct PlanCase {
  const char* name;
  Box room;
  std::vector<Box> objects;
  std::vector<Eigen::Vector2d> bumps;
  Eigen::Vector2d start;
};

std::vector<PlanCase> PlanCases() {
  return {
      {"fig14", {0, 0, 4, 5.5}, {{0, 2, 0.6, 3.2}, {1.4, 1.2, 2.2, 1.8}, {2.3, 3.6, 3, 4.4}}, {}, {2, 0.8}},
      {"fig19",
       {0, 0, 4, 4},
       {{0.8, 0.9, 1.4, 1.4}, {2.6, 0.9, 3.2, 1.5}, {0.9, 2.6, 1.5, 3.1}, {2.5, 2.6, 3.1, 3.2}},
       {{2.0, 3.5}},
       {2, 2}},
      {"fig20",
       {0, 0, 4, 4},
       {{0, 1.4, 0.5, 2.4}, {1.6, 3.5, 2.6, 4}, {1.2, 0.9, 1.8, 1.5}, {2.6, 1.8, 3.1, 2.6}},
       {},
       {3.4, 0.6}},
      {"large_room",
       {0, 0, 8, 6},
       {{0, 2.2, 0.6, 3.6}, {2, 1.4, 3.2, 2.2}, {5, 3.4, 6, 4.4}, {7.2, 0, 8, 1.2}, {3.2, 5.4, 4.6, 6}},
       {{4.0, 3.0}, {6.5, 2.0}, {1.0, 5.0}},
       {4, 0.8}},
  };
}

void ExpectSamePlan(const CoveragePlan& a, const CoveragePlan& b) {
  EXPECT_EQ(a.swapped, b.swapped);
  EXPECT_EQ(a.order, b.order);
  ASSERT_EQ(a.cells.size(), b.cells.size());
  for (size_t i = 0; i < a.cells.size(); ++i) {
    EXPECT_EQ(a.cells[i].id, b.cells[i].id);
    EXPECT_EQ(a.cells[i].neighbours, b.cells[i].neighbours);
    ASSERT_EQ(a.cells[i].slabs.size(), b.cells[i].slabs.size());
    for (size_t k = 0; k < a.cells[i].slabs.size(); ++k) {
      const Slab &s = a.cells[i].slabs[k], &t = b.cells[i].slabs[k];
      EXPECT_TRUE(s.x0 == t.x0 && s.x1 == t.x1 && s.ylo == t.ylo && s.yhi == t.yhi) << "cell " << i << " slab " << k;
    }
  }
  ASSERT_EQ(a.routes.size(), b.routes.size());
  for (size_t i = 0; i < a.routes.size(); ++i) EXPECT_TRUE(a.routes[i] == b.routes[i]) << "route " << i;
  EXPECT_EQ(a.route_length_m, b.route_length_m);
  EXPECT_EQ(a.transit_length_m, b.transit_length_m);
}

TEST(CoveragePlannerTest, StepByStepMakesExactlyTheOneShotPlan) {
  std::vector<CleaningOptions> variants(4, CleaningOptions{});
  variants[1].both_directions = false;
  variants[2].edge_pass = false;
  variants[2].two_opt_rounds = 0;
  variants[3].two_opt_rounds = 1;
  variants[3].cleaning_width_m = 0.25;
  for (const PlanCase& c : PlanCases()) {
    for (size_t v = 0; v < variants.size(); ++v) {
      SCOPED_TRACE(std::string(c.name) + " options " + std::to_string(v));
      const CleaningOptions& o = variants[v];
      const CoveragePlan one = PlanCoverage(c.room, c.objects, c.bumps, c.start, kRadius, o);
      CoveragePlanner planner;
      planner.Start(c.room, c.objects, c.bumps, c.start, kRadius, o);
      int steps = 0;
      while (!planner.Step()) ASSERT_LT(++steps, 10000);
      EXPECT_TRUE(planner.Step());  // done stays done
      // Per orientation: decomposition, greedy tour, the 2-opt rounds, a step per cell.
      const int orientations = o.both_directions ? 2 : 1;
      EXPECT_LE(planner.steps(), orientations * (2 + o.two_opt_rounds) + 2 * static_cast<int>(one.cells.size()) + 2);
      EXPECT_GT(planner.steps(), static_cast<int>(one.cells.size()));
      ExpectSamePlan(planner.Take(), one);
      EXPECT_GE(one.cells.size(), 1u);
    }
  }
}

// A resumed cleaning keeps the orientation its plan had (Clean reads it from
// the saved routes): the planner plans only that one, even where the other is
// shorter.
TEST(CoveragePlannerTest, AGivenOrientationIsTheOnlyOnePlanned) {
  const Box room{0, 0, 6, 2};
  CleaningOptions both = Options();
  both.both_directions = true;
  for (const bool along_x : {false, true}) {
    CoveragePlanner planner;
    planner.Start(room, {}, {}, {1, 1}, kRadius, both, along_x);
    int steps = 0;
    while (!planner.Step()) ASSERT_LT(++steps, 10000);
    const CoveragePlan p = planner.Take();
    EXPECT_EQ(p.swapped, along_x);
    CleaningOptions one = Options();
    one.both_directions = false;
    const CoveragePlan along_y = PlanCoverage(room, {}, {}, {1, 1}, kRadius, one);
    if (!along_x) ExpectSamePlan(p, along_y);
  }
  // Without one, both are planned and the shorter (along x here) is kept.
  CoveragePlanner planner;
  planner.Start(room, {}, {}, {1, 1}, kRadius, both);
  while (!planner.Step()) {
  }
  EXPECT_TRUE(planner.Take().swapped);
}

TEST(CoverageTest, MarkInsideCoversTheTargetUnderAPolygonAndNothingElse) {
  const CoveragePlan p = PlanCoverage({0, 0, 4, 3}, {}, {}, {1, 1}, kRadius, Options());
  CoverageGrid g;
  g.Init({0, 0, 4, 3}, p.FreeRects(), 0.17, 0.02);
  // An L: 2 x 1 and 1 x 1 more, well inside the target.
  g.MarkInside({{1, 1}, {3, 1}, {3, 2}, {2, 2}, {2, 2.5}, {1, 2.5}});
  EXPECT_NEAR(g.covered_m2(), 2 * 1 + 1 * 0.5, 0.05);
  const double once = g.covered_m2();
  g.MarkInside({{1, 1}, {3, 1}, {3, 2}, {1, 2}});  // inside what is covered: nothing new
  EXPECT_EQ(g.covered_m2(), once);
  g.MarkInside({{-5, -5}, {-4, -5}, {-4, -4}});  // outside the room
  g.MarkInside({{1, 1}, {2, 1}});                // not a polygon
  EXPECT_EQ(g.covered_m2(), once);
}

TEST(CoveragePlannerTest, ARoomWithNoFreeFloorIsAnEmptyPlanInAFewSteps) {
  CoveragePlanner planner;
  planner.Start({0, 0, 0.3, 0.3}, {}, {}, {0.15, 0.15}, kRadius, CleaningOptions{});
  int steps = 0;
  while (!planner.Step()) ++steps;
  EXPECT_LE(planner.steps(), 2);
  const CoveragePlan p = planner.Take();
  EXPECT_TRUE(p.cells.empty());
  EXPECT_TRUE(p.routes.empty());
}

TEST(CoverageTest, TheGridInPiecesIsTheGridInOneGo) {
  const PlanCase c = PlanCases()[3];
  const CoveragePlan p = PlanCoverage(c.room, c.objects, c.bumps, c.start, kRadius, CleaningOptions{});
  CoverageGrid whole, pieces;
  whole.Init(c.room, p.FreeRects(), 0.17, 0.05);
  pieces.Reset(c.room, 0.17, 0.05);
  for (const Box& b : p.FreeRects()) pieces.AddTarget(b);
  EXPECT_GT(whole.total_m2(), 30.0);
  EXPECT_EQ(whole.total_m2(), pieces.total_m2());
  for (double x = 0.5; x < 7.5; x += 0.02) {
    whole.Mark({x, 0.8});
    pieces.Mark({x, 0.8});
  }
  EXPECT_EQ(whole.covered_m2(), pieces.covered_m2());
}

// Resuming a cleaning (control/clean.h SameModel): the stopped plan's inputs are
// planned from again only while the room and every object are where they were.
TEST(SameModelTest, TheModelIsTheSameWhileEveryEdgeIsWithinTheTolerance) {
  CleaningProgress::PlanInputs planned;
  planned.room = {0, 0, 4, 3};
  planned.objects = {{1, 1, 1.5, 2}, {3, 0, 4, 0.6}};
  planned.contacts = {{2, 2}};
  CleaningProgress::PlanInputs now = planned;
  now.contacts.clear();  // contacts do not count: they are the plan's own
  EXPECT_TRUE(SameModel(planned, now, 0.05));
  std::swap(now.objects[0], now.objects[1]);  // paired by place, not by order
  now.room.xmax += 0.04;
  now.objects[0].ymin -= 0.049;
  EXPECT_TRUE(SameModel(planned, now, 0.05));
  EXPECT_FALSE(SameModel(planned, now, 0.0));  // 0: never
  EXPECT_FALSE(SameModel(planned, now, 0.03));
  now = planned;
  now.room.ymin += 0.06;  // the room moved
  EXPECT_FALSE(SameModel(planned, now, 0.05));
  now = planned;
  now.objects[1].xmin -= 0.5;  // an object moved (issue 14's moved furniture)
  EXPECT_FALSE(SameModel(planned, now, 0.05));
  now = planned;
  now.objects.push_back({2, 2, 2.3, 2.3});  // one more
  EXPECT_FALSE(SameModel(planned, now, 0.05));
  now.objects = {planned.objects[0], planned.objects[0]};  // two near one: one each
  EXPECT_FALSE(SameModel(planned, now, 0.05));
}

}  // namespace
}  // namespace irslam::control
