#include "slam/relocalizer.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <variant>

#include "tests/testing/lines.h"

namespace irslam::slam {
namespace {

using Vec2 = Eigen::Vector2d;

constexpr double kFollowM = 0.3;  // wall-following distance of the synthetic robot

// A line feature between two end points (tests/testing/lines.h), seen ten times.
LineFeature MakeLine(int id, const Vec2& a, const Vec2& b) {
  LineFeature l = testing::Line(id, a, b);
  l.observations = 10;
  return l;
}

Pose2 Inverse(const Pose2& t) {
  const auto [x, y] = ToLocal(t, 0, 0);
  return {x, y, NormalizeAngle(-t.theta)};
}

Vec2 Apply(const Pose2& t, const Vec2& p) {
  const auto [x, y] = ToParent(t, p.x(), p.y());
  return {x, y};
}

// A rectilinear polygon, counter-clockwise, offset by m to its left (inside
// for a room contour) or, with m < 0, to its right (outside, for an object).
std::vector<Vec2> Offset(const std::vector<Vec2>& poly, double m) {
  std::vector<Vec2> out;
  const size_t n = poly.size();
  for (size_t i = 0; i < n; ++i) {
    const Vec2 dp = (poly[i] - poly[(i + n - 1) % n]).normalized();
    const Vec2 dn = (poly[(i + 1) % n] - poly[i]).normalized();
    out.push_back(poly[i] + m * (Vec2(-dp.y(), dp.x()) + Vec2(-dn.y(), dn.x())));
  }
  return out;
}

// A saved map: a room contour (counter-clockwise) with wall-contact objects as
// notches in it, and free objects (counter-clockwise boxes).
struct World {
  std::vector<Vec2> contour;
  std::vector<std::vector<Vec2>> objects;

  std::vector<LineFeature> Lines() const {
    std::vector<LineFeature> lines;
    auto add = [&](const std::vector<Vec2>& poly) {
      for (size_t i = 0; i < poly.size(); ++i) {
        lines.push_back(
            MakeLine(static_cast<int>(lines.size()) + 1, poly[i], poly[(i + 1) % poly.size()]));
      }
    };
    add(contour);
    for (const auto& o : objects) add(o);
    return lines;
  }

  // The saved mission's trajectory: around the contour inside, around each object outside.
  std::vector<TimedPose> Trajectory() const {
    std::vector<TimedPose> out;
    auto add = [&](const std::vector<Vec2>& path) {
      for (size_t i = 0; i < path.size(); ++i) {
        const Vec2 a = path[i], b = path[(i + 1) % path.size()];
        const int steps = static_cast<int>(std::ceil((b - a).norm() / 0.05));
        const double heading = std::atan2(b.y() - a.y(), b.x() - a.x());
        for (int k = 0; k < steps; ++k) {
          const Vec2 p = a + (b - a) * (static_cast<double>(k) / steps);
          out.push_back({0.25 * static_cast<double>(out.size()), {p.x(), p.y(), heading}});
        }
      }
    };
    add(Offset(contour, kFollowM));
    for (const auto& o : objects) add(Offset(o, -kFollowM));
    return out;
  }
};

World Rectangle(double w, double h) { return {{{0, 0}, {w, 0}, {w, h}, {0, h}}, {}}; }

// 4 m x 5.5 m (the paper's room) with a wall-contact object on the right wall
// and a free object.
World RoomWithBox() {
  return {{{0, 0}, {4, 0}, {4, 2}, {3.4, 2}, {3.4, 3}, {4, 3}, {4, 5.5}, {0, 5.5}},
          {{{1.2, 2.5}, {2.0, 2.5}, {2.0, 3.3}, {1.2, 3.3}}}};
}

World LRoom() { return {{{0, 0}, {6, 0}, {6, 3}, {3, 3}, {3, 5}, {0, 5}}, {}}; }

// What a fresh local SLAM has after following the contour from arc length s0
// for `length` metres: the wall pieces beside the walked path (noisy: ~1 cm,
// ~0.5 deg for a 1 m piece) and the trajectory, both in the local frame given by
// local_to_map.
struct Evidence {
  std::vector<LineFeature> lines;
  std::vector<TimedPose> trajectory;
};

Evidence Walk(const World& world, const Pose2& local_to_map, double s0, double length,
              uint32_t seed, double noise_m = 0.01, double noise_rad = 0.5 * M_PI / 180) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> offset_noise(0, noise_m), angle_noise(0, noise_rad);
  const std::vector<Vec2> path = Offset(world.contour, kFollowM);
  const size_t n = path.size();
  std::vector<double> arc{0};
  for (size_t i = 0; i < n; ++i) arc.push_back(arc.back() + (path[(i + 1) % n] - path[i]).norm());
  const double perimeter = arc.back();
  s0 = std::fmod(s0, perimeter);
  const Pose2 to_local = Inverse(local_to_map);
  Evidence ev;
  for (int lap = 0; lap < 3; ++lap) {
    for (size_t i = 0; i < n; ++i) {
      const double e0 = arc[i] + lap * perimeter, e1 = arc[i + 1] + lap * perimeter;
      const double from = std::max(s0, e0), to = std::min(s0 + length, e1);
      if (to <= from) continue;
      const Vec2 a = path[i], b = path[(i + 1) % n];
      const Vec2 d = (b - a).normalized();
      const Vec2 inward(-d.y(), d.x());
      // The trajectory along this edge.
      for (double s = from; s < to; s += 0.05) {
        const Vec2 p = a + d * (s - e0);
        const Pose2 map_pose{p.x(), p.y(), std::atan2(d.y(), d.x())};
        ev.trajectory.push_back(
            {0.25 * static_cast<double>(ev.trajectory.size()), Compose(to_local, map_pose)});
      }
      // The wall beside it, clipped to the wall edge.
      const Vec2 w0 = world.contour[i], w1 = world.contour[(i + 1) % n];
      const double wl = (w1 - w0).norm();
      const Vec2 pa = a + d * (from - e0) - kFollowM * inward,
                 pb = a + d * (to - e0) - kFollowM * inward;
      const double ta = std::clamp(d.dot(pa - w0), 0.0, wl),
                   tb = std::clamp(d.dot(pb - w0), 0.0, wl);
      if (tb - ta < 0.3) continue;
      Vec2 q0 = w0 + d * ta, q1 = w0 + d * tb;
      // Noise: turned about the middle, shifted along the normal. The angle of
      // a longer line is better known (a fit over more points): the tilt
      // moves the end points by about as much as the offset noise.
      const Vec2 mid = (q0 + q1) / 2 + offset_noise(rng) * inward;
      const Pose2 noise{0, 0, angle_noise(rng) * std::min(1.0, 1.0 / (tb - ta))};
      const Vec2 half = Apply(noise, (q1 - q0) / 2);
      q0 = mid - half;
      q1 = mid + half;
      ev.lines.push_back(MakeLine(static_cast<int>(ev.lines.size()) + 1, Apply(to_local, q0),
                                  Apply(to_local, q1)));
    }
  }
  return ev;
}

double Perimeter(const World& world) {
  const std::vector<Vec2> path = Offset(world.contour, kFollowM);
  double p = 0;
  for (size_t i = 0; i < path.size(); ++i) p += (path[(i + 1) % path.size()] - path[i]).norm();
  return p;
}

void ExpectPose(const Pose2& got, const Pose2& want, double tol_m = 0.03,
                double tol_rad = M_PI / 180) {
  EXPECT_NEAR(got.x, want.x, tol_m);
  EXPECT_NEAR(got.y, want.y, tol_m);
  EXPECT_NEAR(NormalizeAngle(got.theta - want.theta), 0, tol_rad);
}

bool Near(const Pose2& a, const Pose2& b, double tol_m = 0.03, double tol_rad = M_PI / 180) {
  return std::hypot(a.x - b.x, a.y - b.y) < tol_m &&
         std::abs(NormalizeAngle(a.theta - b.theta)) < tol_rad;
}

TEST(RelocalizerTest, MakeLineIsConsistent) {
  const LineFeature l = MakeLine(1, {1, 2}, {3, 2});
  EXPECT_NEAR(l.rho, 2, 1e-12);
  EXPECT_NEAR(l.theta, M_PI / 2, 1e-12);
  for (const Vec2& p : {l.p0, l.p1})
    EXPECT_NEAR(p.dot(Vec2(std::cos(l.theta), std::sin(l.theta))), l.rho, 1e-12);
}

// Case 1: a room whose furniture or shape breaks the symmetry is solved, for
// headings in every quadrant, and nothing wrong is committed on the way.
void ExpectSolved(const World& world, double walk_m, uint32_t seed0) {
  Relocalizer reloc({}, world.Lines(), world.Trajectory());
  std::mt19937 rng(seed0);
  std::uniform_real_distribution<double> near(-1, 1), jitter(-0.6, 0.6), start(0, Perimeter(world));
  for (int i = 0; i < 8; ++i) {
    SCOPED_TRACE(i);
    // The local frame is the odometry frame of the start: the robot started
    // within a metre of where its wall following begins, heading anywhere.
    const double s0 = start(rng);
    const Evidence at_start = Walk(world, {}, s0, 0.01, 0);
    const Pose2& p = at_start.trajectory.front().pose;
    const Pose2 truth{p.x + near(rng), p.y + near(rng),
                      NormalizeAngle(-M_PI + (i + 0.5) * M_PI / 4 + jitter(rng))};
    std::optional<PoseHypothesis> decision;
    double committed_at = -1;
    for (double walked = 1; walked <= walk_m + 1e-9; walked += 1) {
      const Evidence ev = Walk(world, truth, s0, walked, seed0 + i);
      reloc.Update(ev.lines, ev.trajectory);
      ASSERT_LE(static_cast<int>(reloc.hypotheses().size()), reloc.options().max_hypotheses);
      const auto d = reloc.Decision();
      if (d) {
        EXPECT_TRUE(Near(d->local_to_map, truth))
            << "wrong commit after " << walked << " m: " << d->local_to_map.x << " "
            << d->local_to_map.y << " " << d->local_to_map.theta << " truth " << truth.x << " "
            << truth.y << " " << truth.theta;
        if (!decision) committed_at = walked;
        decision = d;
      }
    }
    ASSERT_TRUE(decision.has_value())
        << "no commit; best " << reloc.hypotheses()[0].score << " second "
        << (reloc.hypotheses().size() > 1 ? reloc.hypotheses()[1].score : 0);
    ExpectPose(decision->local_to_map, truth);
    EXPECT_GT(decision->score, 0.85);
    EXPECT_GT(committed_at, 1.9);  // min_evidence_m
  }
}

TEST(RelocalizerTest, FindsThePoseInARoomWithAWallContactObject) {
  ExpectSolved(RoomWithBox(), 14, 11);
}

TEST(RelocalizerTest, FindsThePoseInAnLShapedRoom) { ExpectSolved(LRoom(), 14, 23); }

// The saved map's lines need only be near the axes: the map frame of a saved
// map is turned so that line 1 is along x, and line 1 is not the best axis.
TEST(RelocalizerTest, SavedMapAFewDegreesOffAxis) {
  const World world = RoomWithBox();
  const Pose2 map_from_world{0.3, -0.2, 2.5 * M_PI / 180};
  std::vector<LineFeature> lines;
  for (const LineFeature& l : world.Lines()) {
    lines.push_back(MakeLine(l.id, Apply(map_from_world, l.p0), Apply(map_from_world, l.p1)));
  }
  std::vector<TimedPose> trajectory = world.Trajectory();
  for (TimedPose& p : trajectory) p.pose = Compose(map_from_world, p.pose);
  Relocalizer reloc({}, lines, trajectory);
  const Pose2 truth{2.0, 0.5, -1.2};  // local -> world
  const Evidence ev = Walk(world, truth, 4.0, 12, 21);
  reloc.Update(ev.lines, ev.trajectory);
  const auto d = reloc.Decision();
  ASSERT_TRUE(d.has_value());
  ExpectPose(d->local_to_map, Compose(map_from_world, truth));
}

// Without the saved trajectory the sides of the saved lines are unknown (either
// side matches): the shape alone still decides.
TEST(RelocalizerTest, FindsThePoseWithoutTheSavedTrajectory) {
  const World world = LRoom();
  Relocalizer reloc({}, world.Lines(), {});
  const Pose2 truth{4.1, 2.2, 2.9};
  const Evidence ev = Walk(world, truth, 6.0, 14, 27);
  reloc.Update(ev.lines, ev.trajectory);
  const auto d = reloc.Decision();
  ASSERT_TRUE(d.has_value());
  ExpectPose(d->local_to_map, truth);
}

// Something the saved map does not have (a chair moved in since) costs score
// but does not prevent the commit.
TEST(RelocalizerTest, AnUnmappedObjectIsTolerated) {
  const World world = RoomWithBox();
  Relocalizer reloc({}, world.Lines(), world.Trajectory());
  const Pose2 truth{0.8, 4.5, -2.0};
  Evidence ev = Walk(world, truth, 9.0, 14, 29);
  const Pose2 to_local = Inverse(truth);
  ev.lines.push_back(MakeLine(50, Apply(to_local, {2.6, 1.2}), Apply(to_local, {3.0, 1.2})));
  ev.lines.push_back(MakeLine(51, Apply(to_local, {2.6, 1.2}), Apply(to_local, {2.6, 1.6})));
  reloc.Update(ev.lines, ev.trajectory);
  const auto d = reloc.Decision();
  ASSERT_TRUE(d.has_value());
  ExpectPose(d->local_to_map, truth);
  EXPECT_NEAR(d->conflict_m, 0.8, 0.1);  // both chair sides in free space
}

// Case 2: a bare rectangle is two-fold symmetric: two walls and a corner (or
// the whole room) leave it ambiguous.
TEST(RelocalizerTest, BareRectangleStaysAmbiguous) {
  const World world = Rectangle(4, 5.5);
  Relocalizer reloc({}, world.Lines(), world.Trajectory());
  const Pose2 truth{1.3, -2.1, 2.2};
  for (double walked : {4.5, 8.0, Perimeter(world), Perimeter(world) + 3}) {
    SCOPED_TRACE(walked);
    const Evidence ev = Walk(world, truth, 1.7, walked, 5);
    reloc.Update(ev.lines, ev.trajectory);
    EXPECT_TRUE(reloc.both_directions());
    EXPECT_GT(reloc.evidence_m(), reloc.options().min_evidence_m);
    ASSERT_GE(reloc.hypotheses().size(), 2u);
    EXPECT_GT(reloc.hypotheses()[0].score, 0.85);
    EXPECT_NEAR(reloc.hypotheses()[1].score, reloc.hypotheses()[0].score, 0.1);
    EXPECT_FALSE(reloc.Decision().has_value());
    // The truth is among the equally good.
    bool found = false;
    for (const PoseHypothesis& h : reloc.hypotheses()) {
      found = found || (h.score > reloc.hypotheses()[0].score - 0.1 && Near(h.local_to_map, truth));
    }
    EXPECT_TRUE(found);
  }
}

// ... and a wall-contact object breaks the symmetry once it has been seen.
TEST(RelocalizerTest, WallContactObjectBreaksTheRectanglesSymmetry) {
  const World world{
      {{0, 0}, {4, 0}, {4, 3.5}, {3.4, 3.5}, {3.4, 4.3}, {4, 4.3}, {4, 5.5}, {0, 5.5}}, {}};
  Relocalizer reloc({}, world.Lines(), world.Trajectory());
  const Pose2 truth{-3.0, 0.7, -0.6};
  // Bottom wall from x = 2, the corner, the right wall up to y ~ 3.1: ambiguous.
  Evidence ev = Walk(world, truth, 1.7, 4.5, 7);
  reloc.Update(ev.lines, ev.trajectory);
  ASSERT_GE(reloc.hypotheses().size(), 2u);
  EXPECT_NEAR(reloc.hypotheses()[1].score, reloc.hypotheses()[0].score, 0.1);
  EXPECT_FALSE(reloc.Decision().has_value());
  // On past the object: decided, and right.
  ev = Walk(world, truth, 1.7, 8.5, 7);
  reloc.Update(ev.lines, ev.trajectory);
  const auto d = reloc.Decision();
  ASSERT_TRUE(d.has_value()) << reloc.hypotheses()[0].score << " " << reloc.hypotheses()[1].score;
  ExpectPose(d->local_to_map, truth);
  EXPECT_LT(reloc.hypotheses()[1].score, d->score - reloc.options().commit_margin);
}

// Case 3: a square room is four-fold symmetric: never committed.
TEST(RelocalizerTest, SquareRoomNeverCommits) {
  const World world = Rectangle(4, 4);
  Relocalizer reloc({}, world.Lines(), world.Trajectory());
  const Pose2 truth{0.4, 2.5, -2.7};
  for (double walked = 1; walked <= 2 * Perimeter(world); walked += 1) {
    const Evidence ev = Walk(world, truth, 0.9, walked, 3);
    reloc.Update(ev.lines, ev.trajectory);
    EXPECT_FALSE(reloc.Decision().has_value()) << walked;
  }
  ASSERT_GE(reloc.hypotheses().size(), 4u);
  EXPECT_GT(reloc.hypotheses()[0].score, 0.85);
  EXPECT_NEAR(reloc.hypotheses()[3].score, reloc.hypotheses()[0].score, 0.1);
  // The four are the truth turned by quarter turns about the room's centre.
  int found = 0;
  for (int k = 0; k < 4; ++k) {
    const Pose2 about_centre = Compose(Compose({2, 2, k * M_PI / 2}, {-2, -2, 0}), truth);
    for (size_t i = 0; i < 4; ++i)
      found += Near(reloc.hypotheses()[i].local_to_map, about_centre) ? 1 : 0;
  }
  EXPECT_EQ(found, 4);
}

// Case 4: evidence along one direction only (one wall) leaves the translation
// along it free: never committed, however long.
TEST(RelocalizerTest, OneDirectionOfEvidenceNeverCommits) {
  const World world = LRoom();
  Relocalizer reloc({}, world.Lines(), world.Trajectory());
  const Pose2 truth{2.0, 1.0, 0.9};
  // The path's first edge runs along the 6 m bottom wall (5.4 m of path).
  for (double walked = 1; walked <= 5.3; walked += 0.5) {
    const Evidence ev = Walk(world, truth, 0.0, walked, 9);
    reloc.Update(ev.lines, ev.trajectory);
    EXPECT_FALSE(reloc.both_directions());
    EXPECT_FALSE(reloc.Decision().has_value()) << walked;
  }
  EXPECT_GT(reloc.evidence_m(), 4.5);
  EXPECT_EQ(std::min(reloc.evidence_by_direction_m()[0], reloc.evidence_by_direction_m()[1]), 0);
  // The wall slides along the 6 m wall: another place explains it as well, or
  // nearly (there the trajectory ends in the next wall).
  ASSERT_GE(reloc.hypotheses().size(), 2u);
  EXPECT_GT(reloc.hypotheses()[1].score, 0.85);
}

// Even with thresholds that commit anything, one direction is not enough.
TEST(RelocalizerTest, OneDirectionIsNotCommittedWhateverTheThresholds) {
  const World world = RoomWithBox();
  RelocalizeOptions lax;
  lax.commit_score = 0;
  lax.commit_margin = 0;
  Relocalizer reloc(lax, world.Lines(), world.Trajectory());
  const Pose2 truth{1.0, 4.0, 0.4};
  // The path's last edge runs down the 5.5 m left wall (4.9 m of path).
  const double s0 = Perimeter(world) - 4.8;
  Evidence ev = Walk(world, truth, s0, 4.6, 31);
  reloc.Update(ev.lines, ev.trajectory);
  EXPECT_GT(reloc.evidence_m(), lax.min_evidence_m);
  EXPECT_FALSE(reloc.both_directions());
  EXPECT_FALSE(reloc.Decision().has_value());
  // Round the corner: lax thresholds now commit.
  ev = Walk(world, truth, s0, 6.5, 31);
  reloc.Update(ev.lines, ev.trajectory);
  EXPECT_TRUE(reloc.both_directions());
  EXPECT_TRUE(reloc.Decision().has_value());
}

// Case 5: evidence from another room: the map disagrees, nothing is committed.
TEST(RelocalizerTest, EvidenceFromAnotherRoomIsNotCommitted) {
  const World saved = LRoom();
  const World other{
      {{0, 0}, {2.5, 0}, {2.5, 1.0}, {2.0, 1.0}, {2.0, 1.6}, {2.5, 1.6}, {2.5, 2.5}, {0, 2.5}}, {}};
  Relocalizer reloc({}, saved.Lines(), saved.Trajectory());
  for (int i = 0; i < 4; ++i) {
    const Pose2 truth{0.5 * i, -1.0 * i, -2.5 + 1.4 * i};
    for (double walked = 2; walked <= 1.5 * Perimeter(other); walked += 1) {
      const Evidence ev = Walk(other, truth, 0.4 * i, walked, 40 + i);
      reloc.Update(ev.lines, ev.trajectory);
      EXPECT_FALSE(reloc.Decision().has_value()) << i << " " << walked;
    }
    ASSERT_FALSE(reloc.hypotheses().empty());
    EXPECT_LT(reloc.hypotheses()[0].score, 0.5) << i;
  }
}

// Case 6: the score of a given transform.
TEST(RelocalizerTest, ScoreHypothesisExplainsTheTruthAndNotAShiftedPose) {
  const World world = RoomWithBox();
  const Pose2 truth{1.5, -0.5, 1.9};
  const Evidence ev = Walk(world, truth, 3.0, Perimeter(world) - 0.5, 13);
  const RelocalizeOptions options;
  const auto lines = world.Lines();
  const auto saved_trajectory = world.Trajectory();
  const PoseHypothesis right =
      ScoreHypothesis(options, truth, lines, saved_trajectory, ev.lines, ev.trajectory);
  EXPECT_GT(right.score, 0.9);
  EXPECT_LT(right.conflict_m, 0.1);
  EXPECT_GT(right.explained_m, 0.9 * (Perimeter(world) - 2));
  ExpectPose(right.local_to_map, truth, 1e-12, 1e-12);

  const Pose2 shifted = Compose({0.5, 0, 0}, truth);  // 0.5 m along the map's x
  const PoseHypothesis wrong =
      ScoreHypothesis(options, shifted, lines, saved_trajectory, ev.lines, ev.trajectory);
  EXPECT_LT(wrong.score, 0.5);
  EXPECT_GT(wrong.conflict_m, 1.0);  // the trajectory crosses the right wall, lines in free space

  // The same evidence, but the robot drove through the bottom wall and back.
  Evidence through = ev;
  const Pose2 to_local = Inverse(truth);
  for (double y : {0.3, -0.4, 0.3}) {
    through.trajectory.push_back(
        {through.trajectory.back().t + 1, Compose(to_local, {2.0, y, -M_PI / 2})});
  }
  const PoseHypothesis crossed =
      ScoreHypothesis(options, truth, lines, saved_trajectory, through.lines, through.trajectory);
  // Two crossings, and the 0.7 m step out of the room (more than free_margin_m out).
  EXPECT_NEAR(crossed.conflict_m - right.conflict_m, 2 * options.crossing_conflict_m + 0.7, 0.05);
  EXPECT_LT(crossed.score, right.score - 0.05);
}

// Walls do not move, furniture does: driving through where a saved piece of
// furniture stood (it was moved since the map was made) is weaker evidence
// against a pose than driving through a wall (the wall crossing above).
TEST(RelocalizerTest, ACrossedFurnitureSideCountsLessThanACrossedWall) {
  const World world = RoomWithBox();
  const Pose2 truth{1.5, -0.5, 1.9};
  const Evidence ev = Walk(world, truth, 3.0, Perimeter(world) - 0.5, 13);
  RelocalizeOptions options;
  options.short_crossing_conflict_m = 0.2;
  const auto lines = world.Lines();
  const auto saved_trajectory = world.Trajectory();
  const PoseHypothesis right =
      ScoreHypothesis(options, truth, lines, saved_trajectory, ev.lines, ev.trajectory);
  // Into the free box (0.8 m sides, shorter than anchor_line_m) through its
  // bottom side and out through its top side, far from any wall.
  Evidence through = ev;
  const Pose2 to_local = Inverse(truth);
  for (double y : {2.2, 2.9, 3.6}) {
    through.trajectory.push_back({through.trajectory.back().t + 1, Compose(to_local, {1.6, y, M_PI / 2})});
  }
  const PoseHypothesis crossed =
      ScoreHypothesis(options, truth, lines, saved_trajectory, through.lines, through.trajectory);
  // The step from the wall-following path to (1.6, 2.2) may cross nothing;
  // the two box sides count 0.2 each, not crossing_conflict_m.
  EXPECT_NEAR(crossed.conflict_m - right.conflict_m, 2 * options.short_crossing_conflict_m, 1e-9);
  options.short_crossing_conflict_m = options.crossing_conflict_m;
  const PoseHypothesis full =
      ScoreHypothesis(options, truth, lines, saved_trajectory, through.lines, through.trajectory);
  EXPECT_NEAR(full.conflict_m - right.conflict_m, 2 * options.crossing_conflict_m, 1e-9);
}

TEST(RelocalizerTest, ScoreHypothesisCountsLinesInFreeSpace) {
  const World world = Rectangle(4, 5.5);
  const RelocalizeOptions options;
  const Pose2 truth{0.2, 0.3, 0.4};
  Evidence ev = Walk(world, truth, 1.0, 6.0, 17);
  const PoseHypothesis clean =
      ScoreHypothesis(options, truth, world.Lines(), world.Trajectory(), ev.lines, ev.trajectory);
  // A 1 m line in the middle of the room, where the saved map has nothing.
  const Pose2 to_local = Inverse(truth);
  ev.lines.push_back(MakeLine(99, Apply(to_local, {1.5, 2.7}), Apply(to_local, {2.5, 2.7})));
  const PoseHypothesis extra =
      ScoreHypothesis(options, truth, world.Lines(), world.Trajectory(), ev.lines, ev.trajectory);
  EXPECT_NEAR(extra.conflict_m - clean.conflict_m, 1.0, 0.05);
  EXPECT_NEAR(extra.explained_m, clean.explained_m, 1e-9);
}

// A wall seen from the wrong side (the robot outside the room) is not explained.
TEST(RelocalizerTest, LinesSeenFromTheOtherSideAreNotExplained) {
  const World world = Rectangle(4, 5.5);
  const RelocalizeOptions options;
  const std::vector<LineFeature> local{MakeLine(1, {0.5, 0}, {3.5, 0})};
  std::vector<TimedPose> inside, outside;
  for (double x = 0.5; x <= 3.5; x += 0.1) {
    inside.push_back({x, {x, 0.3, 0}});
    outside.push_back({x, {x, -0.3, 0}});
  }
  const Pose2 identity{};
  EXPECT_NEAR(ScoreHypothesis(options, identity, world.Lines(), world.Trajectory(), local, inside)
                  .explained_m,
              3.0, 1e-6);
  EXPECT_NEAR(ScoreHypothesis(options, identity, world.Lines(), world.Trajectory(), local, outside)
                  .explained_m,
              0, 1e-9);
}

// Case 7: bounded output on a large problem.
TEST(RelocalizerTest, LargeProblemKeepsAtMostMaxHypotheses) {
  std::mt19937 rng(77);
  std::uniform_real_distribution<double> pos(0, 10), len(0.3, 3.0);
  std::bernoulli_distribution along_x(0.5);
  auto random_lines = [&](int n, double turn) {
    std::vector<LineFeature> lines;
    for (int i = 0; i < n; ++i) {
      const Vec2 a(pos(rng), pos(rng));
      const double l = len(rng);
      const Vec2 d = along_x(rng) ? Vec2(std::cos(turn), std::sin(turn))
                                  : Vec2(-std::sin(turn), std::cos(turn));
      lines.push_back(MakeLine(i + 1, a, a + l * d));
    }
    return lines;
  };
  std::vector<TimedPose> saved_trajectory, local_trajectory;
  for (int i = 0; i < 2000; ++i) saved_trajectory.push_back({0.25 * i, {pos(rng), pos(rng), 0}});
  for (int i = 0; i < 700; ++i) local_trajectory.push_back({0.25 * i, {pos(rng), pos(rng), 0}});
  for (int max_hypotheses : {1, 3, 8, 20}) {
    RelocalizeOptions options;
    options.max_hypotheses = max_hypotheses;
    Relocalizer reloc(options, random_lines(150, 0.01), saved_trajectory);
    reloc.Update(random_lines(40, 0.7), local_trajectory);
    EXPECT_GE(reloc.hypotheses().size(), 1u);
    EXPECT_LE(static_cast<int>(reloc.hypotheses().size()), max_hypotheses);
    for (size_t i = 1; i < reloc.hypotheses().size(); ++i) {
      EXPECT_GE(reloc.hypotheses()[i - 1].score, reloc.hypotheses()[i].score);
    }
  }
}

TEST(RelocalizerTest, NoEvidenceNoHypotheses) {
  const World world = RoomWithBox();
  Relocalizer reloc({}, world.Lines(), world.Trajectory());
  reloc.Update({}, {});
  EXPECT_TRUE(reloc.hypotheses().empty());
  EXPECT_FALSE(reloc.Decision().has_value());
  Relocalizer empty({}, {}, {});
  const Evidence ev = Walk(world, {}, 0, 8, 1);
  empty.Update(ev.lines, ev.trajectory);
  EXPECT_TRUE(empty.hypotheses().empty());
  EXPECT_FALSE(empty.Decision().has_value());
}

TEST(RelocalizerTest, KeysHaveTheirDefaultsWithinBounds) {
  const RelocalizeOptions defaults;
  EXPECT_EQ(RelocalizeKeys().size(), 19u);
  for (const auto& key : RelocalizeKeys()) {
    SCOPED_TRACE(std::string(key.name));
    EXPECT_FALSE(key.doc.empty());
    double value = 0;
    if (const auto* d = std::get_if<double RelocalizeOptions::*>(&key.member)) value = defaults.**d;
    if (const auto* i = std::get_if<int RelocalizeOptions::*>(&key.member)) value = defaults.**i;
    EXPECT_GE(value, key.lo);
    EXPECT_LE(value, key.hi);
  }
}

}  // namespace
}  // namespace irslam::slam
