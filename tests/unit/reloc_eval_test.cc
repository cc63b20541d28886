// The relocalisation evaluation's metric parts (tests/tools/reloc_eval.h) on
// synthetic data: the map -> world fit, errors through it, kept ids, duplicate
// lines and the random free start poses.
#include "tests/tools/reloc_eval.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "sim/sim_run.h"
#include "tests/testing/lines.h"
#include "tests/tools/metrics.h"
#include "tests/tools/reloc_picture.h"

namespace irslam::metrics {
namespace {

using testing::Line;

TEST(RelocEvalTest, TheRigidFitRecoversAKnownTransformFromANoisyTrajectory) {
  const Pose2 truth_tf{1.7, -0.4, 2.3};  // map -> world
  std::mt19937_64 rng(5);
  std::normal_distribution<double> noise(0, 0.01);
  std::vector<TimedPose> map_traj, truth;
  for (int i = 0; i < 400; ++i) {
    const double t = 0.25 * i;
    const Pose2 m{std::cos(0.05 * i) * 1.5 + 0.002 * i, std::sin(0.03 * i) * 2.0, 0.01 * i};
    map_traj.push_back({t, m});
    Pose2 w = Compose(truth_tf, m);
    w.x += noise(rng);
    w.y += noise(rng);
    truth.push_back({t, w});
    truth.push_back({t + 0.05, w});  // the truth is sampled faster; pairs by time
  }
  double rms = 0;
  const Pose2 fit = MapToWorldFit(map_traj, truth, &rms);
  EXPECT_NEAR(fit.x, truth_tf.x, 0.005);
  EXPECT_NEAR(fit.y, truth_tf.y, 0.005);
  EXPECT_NEAR(fit.theta, truth_tf.theta, 0.003);
  EXPECT_NEAR(rms, 0.01 * std::sqrt(2.0), 0.003);
  // Exact points: exact transform, zero residual; too few points: identity.
  const std::vector<Eigen::Vector2d> a = {{0, 0}, {1, 0}, {0, 2}};
  std::vector<Eigen::Vector2d> b;
  for (const auto& p : a) b.push_back(Eigen::Rotation2Dd(-0.5) * p + Eigen::Vector2d(3, 4));
  const Pose2 exact = FitRigid(a, b, &rms);
  EXPECT_NEAR(exact.theta, -0.5, 1e-12);
  EXPECT_NEAR(exact.x, 3, 1e-12);
  EXPECT_NEAR(exact.y, 4, 1e-12);
  EXPECT_NEAR(rms, 0, 1e-12);
  const Pose2 none = FitRigid({{1, 1}}, {{2, 2}});
  EXPECT_EQ(none.x, 0);
  EXPECT_EQ(none.theta, 0);
}

TEST(RelocEvalTest, ErrorsAreJudgedInTheWorldFrameThroughTheFit) {
  const Pose2 tf{1, 2, M_PI / 2};
  // Map pose (1, 0, 0) is world (1, 3, pi/2).
  PoseError e = ErrorInWorld({1, 0, 0}, tf, {1, 3, M_PI / 2});
  EXPECT_NEAR(e.position_m, 0, 1e-12);
  EXPECT_NEAR(e.heading_rad, 0, 1e-12);
  e = ErrorInWorld({1, 0.1, 0.1}, tf, {1, 3, M_PI / 2});
  EXPECT_NEAR(e.position_m, 0.1, 1e-12);
  EXPECT_NEAR(e.heading_rad, 0.1, 1e-12);
  // Heading error wraps.
  e = ErrorInWorld({0, 0, M_PI / 2 - 0.05}, tf, {1, 2, -M_PI + 0.05});
  EXPECT_NEAR(e.heading_rad, 0.1, 1e-12);
}

TEST(RelocEvalTest, KeptIdsAndDuplicateLines) {
  const std::vector<slam::LineFeature> saved = {Line(1, {0, 0}, {4, 0}), Line(3, {4, 0}, {4, 5}),
                                                Line(7, {1, 1}, {2, 1})};
  std::vector<slam::LineFeature> out = {
      Line(1, {0, 0.01}, {4, 0.01}),       // the same wall, kept id
      Line(3, {4, 0}, {4, 5}),             // kept
      Line(20, {1, 0.03}, {3, 0.02}),      // a new line on wall 1: duplicate
      Line(21, {4.04, 4.8}, {4.03, 2}),    // on wall 3, reversed direction: duplicate
      Line(22, {5, 0.01}, {6, 0.01}),      // collinear with 1 but beyond its end: new wall
      Line(23, {1, 0.2}, {3, 0.2}),        // parallel, 20 cm off: not
      Line(24, {0.5, 0.0}, {3.5, 0.2}),    // 3.8 deg off: not
      Line(25, {1.2, 1.04}, {1.8, 0.98}),  // over object side 7 but 5.7 deg off: not
  };
  EXPECT_EQ(KeptLineIds(saved, out), 2);
  out[0].merged = {7};  // saved line 7 merged into line 1 (a piece of the same wall): its id kept
  EXPECT_EQ(KeptLineIds(saved, out), 3);
  out[0].merged.clear();
  EXPECT_EQ(DuplicateLines(saved, out), 2);
  out[7] = Line(25, {1.2, 1.02}, {1.8, 1.0});  // 1.9 deg, 2 cm: a duplicate
  EXPECT_EQ(DuplicateLines(saved, out), 3);
  EXPECT_EQ(DuplicateLines(saved, out, 0.25, 5 * M_PI / 180), 5);  // looser: 23 and 24 too
  EXPECT_EQ(DuplicateLines(saved, saved), 0);  // the saved lines themselves are not
}

TEST(RelocEvalTest, RandomStartsAreFreeSeededAndSpread) {
  std::string error;
  auto world =
      sim::LoadWorldFile(std::string(IRSLAM_SOURCE_DIR) + "/tests/worlds/fig14.json", &error);
  ASSERT_TRUE(world) << error;
  const auto a = RandomFreeStarts(*world, 50, 0.3, 11);
  const auto b = RandomFreeStarts(*world, 50, 0.3, 11);
  const auto c = RandomFreeStarts(*world, 50, 0.3, 12);
  ASSERT_EQ(a.size(), 50u);
  double sx = 0, sc = 0;
  for (size_t i = 0; i < a.size(); ++i) {
    EXPECT_TRUE(sim::FreePose(*world, a[i], 0.3, &error)) << error;
    EXPECT_EQ(a[i].x, b[i].x);
    EXPECT_EQ(a[i].theta, b[i].theta);
    sx += a[i].x;
    sc += std::cos(a[i].theta);
  }
  EXPECT_NE(a[0].x, c[0].x);
  EXPECT_NEAR(sx / 50, world->Bounds().xmax / 2, 0.6);  // spread over the room
  EXPECT_LT(std::abs(sc / 50), 0.4);                    // and over headings
}

TEST(RelocEvalTest, FreePoseSaysWhyNot) {
  std::string error;
  auto world =
      sim::LoadWorldFile(std::string(IRSLAM_SOURCE_DIR) + "/tests/worlds/fig14.json", &error);
  ASSERT_TRUE(world) << error;
  std::string why;
  EXPECT_TRUE(sim::FreePose(*world, {3.0, 0.8, 0}, 0.2, &why)) << why;
  EXPECT_FALSE(sim::FreePose(*world, {9.0, 1.0, 0}, 0.2, &why));
  EXPECT_EQ(why, "(9.00, 1.00) lies outside the room");
  EXPECT_FALSE(sim::FreePose(*world, {0.3, 2.5, 0}, 0.2, &why));
  EXPECT_EQ(why, "(0.30, 2.50) lies inside object 1 [0.00, 2.00, 0.60, 3.20]");
  EXPECT_FALSE(sim::FreePose(*world, {3.9, 0.8, 0}, 0.2, &why));
  EXPECT_EQ(why, "(3.90, 0.80) is 0.10 m from a wall or object side (at least 0.20 m needed)");
  EXPECT_FALSE(sim::FreePose(*world, {NAN, 0.8, 0}, 0.2, &why));
  // The --start argument.
  const auto p = sim::ParsePoseArg("1.5,-2,4", &why);
  ASSERT_TRUE(p) << why;
  EXPECT_DOUBLE_EQ(p->y, -2);
  EXPECT_NEAR(p->theta, 4 - 2 * M_PI, 1e-12);
  for (const char* bad : {"1,2", "1,2,3,4", "1,,3", "a,b,c", "1,2,nan", "", "1,2,3,"}) {
    EXPECT_FALSE(sim::ParsePoseArg(bad, &why)) << bad;
    EXPECT_EQ(why,
              std::string("expected X,Y,THETA (three numbers: metres, metres, radians), got '") +
                  bad + "'");
  }
}

TEST(RelocEvalTest, FurnitureIsMovedOnlyToAFreePlaceOrAlongItsWall) {
  sim::World w;
  w.outline = {{0, 0}, {4, 0}, {4, 3}, {0, 3}};
  w.objects = {{0, 1, 0.6, 2}, {2, 1, 2.5, 1.5}};  // against the left wall; free
  w.start = {3, 2.5, 0};
  // Away from its wall into free floor: allowed, shifted exactly.
  const auto right = metrics::MoveObject(w, 0, 0.5, 0, 0.45);
  ASSERT_TRUE(right.has_value());
  EXPECT_DOUBLE_EQ(right->objects[0].xmin, 0.5);
  EXPECT_DOUBLE_EQ(right->objects[0].xmax, 1.1);
  EXPECT_DOUBLE_EQ(w.objects[0].xmin, 0.0);  // the world itself untouched
  // Along its wall: allowed (still against it).
  EXPECT_TRUE(metrics::MoveObject(w, 0, 0, 0.5, 0.45).has_value());
  // Through the wall: refused.
  EXPECT_FALSE(metrics::MoveObject(w, 0, -0.5, 0, 0.45).has_value());
  // The free piece moved to 0.4 m from the other one: refused (0.45 m needed).
  EXPECT_FALSE(metrics::MoveObject(w, 1, -1.0, 0, 0.45).has_value());
  EXPECT_TRUE(metrics::MoveObject(w, 1, -0.9, 0, 0.45).has_value());  // 0.5 m from it
  // 0.5 m up leaves 1.0 m to the top wall: allowed; 0.2 m from the right wall: refused.
  EXPECT_TRUE(metrics::MoveObject(w, 1, 0, 0.5, 0.45).has_value());
  EXPECT_FALSE(metrics::MoveObject(w, 1, 1.3, 0, 0.45).has_value());
  EXPECT_FALSE(metrics::MoveObject(w, 5, 0.5, 0, 0.45).has_value());  // no such piece
}

// The cleaning report counts contacts with clutter apart (issue 13: no contact
// with mapped furniture, clutter contacts counted): what the robot touched is
// the nearest of the walls and the objects, clutter when no side of it is
// longer than 6 cm (the generator's legs and posts).
TEST(ContactsTest, AContactIsWithClutterWhenTheNearestThingIsALegOrAPost) {
  sim::World w;
  w.outline = {{0, 0}, {4, 0}, {4, 3}, {0, 3}};
  w.objects = {{1, 1, 1.04, 1.05}, {2, 1, 2.8, 1.6}, {3.22, 2.94, 3.28, 3.0}};  // a leg, a table, a post
  EXPECT_TRUE(metrics::ContactWithClutter(w, 1.02 - 0.19, 1.02));   // beside the leg
  EXPECT_FALSE(metrics::ContactWithClutter(w, 2.4, 1.6 + 0.17));    // beside the table
  EXPECT_FALSE(metrics::ContactWithClutter(w, 0.17, 2.0));          // at the left wall
  // Below the post at the top wall, the post nearer than the wall: the post.
  EXPECT_TRUE(metrics::ContactWithClutter(w, 3.25, 2.94 - 0.16));
  // The leg beside the table, the table nearer: the table.
  EXPECT_FALSE(metrics::ContactWithClutter(w, 1.9 - 0.17, 1.3));
}

// Boxes that touch are one piece of furniture (the paper's Fig. 16 draws an
// L-shaped desk as two boxes): found together, and moved together, never
// half of it away from the other half.
TEST(RelocEvalTest, TouchingBoxesAreOnePieceAndMoveTogether) {
  sim::World w;
  w.outline = {{0, 0}, {4, 0}, {4, 4}, {0, 4}};
  // Fig. 16's upper desk (two boxes touching at x = 2.1), a box 1 cm clear of
  // nothing else, and a chain of three touching boxes.
  w.objects = {{1.3, 2.2, 2.1, 2.8}, {2.1, 2.2, 2.5, 3.0}, {3.0, 0.5, 3.5, 1.0},
               {0.5, 0.5, 1.0, 1.0}, {1.0, 0.6, 1.5, 1.2}, {1.5, 0.5, 1.8, 0.9}};
  w.start = {3.5, 3.5, 0};
  const auto pieces = metrics::FurniturePieces(w);
  ASSERT_EQ(pieces.size(), 3u);
  EXPECT_EQ(pieces[0], (std::vector<size_t>{0, 1}));
  EXPECT_EQ(pieces[1], (std::vector<size_t>{2}));
  EXPECT_EQ(pieces[2], (std::vector<size_t>{3, 4, 5}));
  // The desk 0.5 m left: both boxes move, exactly.
  const auto left = metrics::MovePiece(w, pieces[0], -0.5, 0, 0.45);
  ASSERT_TRUE(left.has_value());
  EXPECT_DOUBLE_EQ(left->objects[0].xmin, 0.8);
  EXPECT_DOUBLE_EQ(left->objects[1].xmin, 1.6);
  EXPECT_DOUBLE_EQ(left->objects[1].ymax, 3.0);
  EXPECT_DOUBLE_EQ(left->objects[3].xmin, 0.5);  // other pieces stay
  // A piece's own boxes are not "another piece" for the gap; the others are:
  // 0.5 m down leaves the desk 0.5 m above the chain (allowed), 1.0 m down
  // puts it against the chain (refused).
  EXPECT_TRUE(metrics::MovePiece(w, pieces[0], 0, -0.5, 0.45).has_value());
  EXPECT_FALSE(metrics::MovePiece(w, pieces[0], 0, -1.0, 0.45).has_value());
  // Half the desk alone cannot leave the other half by 0.5 m to the right
  // (it is blocked by it): only as a whole.
  EXPECT_FALSE(metrics::MoveObject(w, 0, 0.5, 0, 0.45).has_value());
  EXPECT_TRUE(metrics::MovePiece(w, pieces[0], 0.5, 0, 0.45).has_value());
  EXPECT_FALSE(metrics::MovePiece(w, {0, 9}, 0.5, 0, 0.45).has_value());  // no such box
}

// The hypotheses picture draws each hypothesis' placement of the local map: in
// a 4 x 3 m room, a local wall seen 1 m in front of the start, placed by the
// right hypothesis onto the saved wall (same pixels as the saved line) and by
// the mirrored one onto the opposite wall; the legend lists them best first.
TEST(RelocPictureTest, EachHypothesisPlacesTheLocalLinesThroughItsTransform) {
  RelocPicture p;
  p.world = "box";
  p.saved_lines = {Line(1, {0, 0}, {4, 0}), Line(2, {4, 0}, {4, 3}), Line(3, {0, 3}, {4, 3}),
                   Line(4, {0, 3}, {0, 0})};
  p.map_to_world = {0, 0, 0};
  HypothesisSnapshot& s = p.snapshot;
  s.t = 12.5;
  s.commit_t = 14;
  s.evidence_m = 4;
  // Local frame: the robot started at the origin facing +x; the wall 1 m
  // to its right runs along x from -1 to 3.
  s.local_lines = {Line(7, {-1, -1}, {3, -1})};
  s.local_trajectory = {{0, {0, 0, 0}}, {10, {2, 0, 0}}};
  slam::PoseHypothesis right, mirrored;
  right.local_to_map = {1, 1, 0};  // start at (1, 1): the wall is y = 0
  right.score = 0.9;
  right.explained_m = 3.6;
  mirrored.local_to_map = {3, 2, M_PI};  // start at (3, 2) facing -x: the wall is y = 3
  mirrored.score = 0.4;
  mirrored.explained_m = 1.6;
  mirrored.conflict_m = 0.5;
  s.hypotheses = {right, mirrored};
  const std::string svg = HypothesesSvg(p);
  // The saved bottom wall (0,0)-(4,0) and the first hypothesis' line
  // (0,0)-(4,0) are the same polyline; the second's lies on the top wall,
  // drawn from (4,3) to (0,3) (its end points turned by pi).
  const auto count = [&](const std::string& needle) {
    size_t n = 0;
    for (size_t at = svg.find(needle); at != std::string::npos; at = svg.find(needle, at + 1)) ++n;
    return n;
  };
  const auto points = [&](const std::string& a, const std::string& b) { return "points=\"" + a + " " + b + "\""; };
  // View: x0 = y0 = -0.3 (the bounds grown by 0.3 m), scale = 560 / 4.6 px per m.
  const double k = 560.0 / 4.6;
  const auto px = [&](double x, double y) {
    char b[64];
    std::snprintf(b, sizeof b, "%.1f,%.1f", (x + 0.3) * k + 20, (3.6 * k + 40) - ((y + 0.3) * k + 20));
    return std::string(b);
  };
  EXPECT_EQ(count(points(px(0, 0), px(4, 0))), 2u) << svg;  // the saved wall and hypothesis 1's line
  EXPECT_EQ(count(points(px(4, 3), px(0, 3))), 1u) << svg;  // hypothesis 2's line
  EXPECT_EQ(count(points(px(0, 3), px(4, 3)) + " stroke=\"#999\""), 1u) << svg;  // the saved top wall
  EXPECT_NE(svg.find("#1: score 0.90 (explained 3.60 m, conflicting 0.00 m"), std::string::npos) << svg;
  EXPECT_NE(svg.find("#2: score 0.40 (explained 1.60 m, conflicting 0.50 m"), std::string::npos) << svg;
  EXPECT_LT(svg.find("#1: score"), svg.find("#2: score"));
  EXPECT_NE(svg.find("the search at 12.5 s, 4.0 m of evidence, 2 hypotheses; committed at 14.0 s"), std::string::npos);
}

// irslam-report --noise-nominal: the named effects of a drawn error envelope go
// back to the nominal robot's, the others keep their drawn values, and a key
// that is not a world-file noise key is refused by name.
TEST(NoiseAblationTest, NamedKeysGoBackToNominalTheOthersStayAndUnknownKeysAreRefused) {
  sim::SimNoise n;
  n.wheel_radius_error_left = 0.008;
  n.wheel_radius_error_right = -0.004;
  n.wheel_base_error = 0.015;
  n.slip_correlation_s = 1.5;
  n.ir_surface_bias_m = 0.02;
  std::string error;
  ASSERT_TRUE(SetNoiseNominal("wheel_radius_error_left,wheel_base_error,slip_correlation_s", &n, &error));
  const sim::SimNoise nominal;
  EXPECT_DOUBLE_EQ(n.wheel_radius_error_left, nominal.wheel_radius_error_left);
  EXPECT_DOUBLE_EQ(n.wheel_radius_error_left, 0.0006);
  EXPECT_DOUBLE_EQ(n.wheel_base_error, 0.0);
  EXPECT_DOUBLE_EQ(n.slip_correlation_s, 0.0);
  EXPECT_DOUBLE_EQ(n.wheel_radius_error_right, -0.004);
  EXPECT_DOUBLE_EQ(n.ir_surface_bias_m, 0.02);
  EXPECT_TRUE(SetNoiseNominal("", &n, &error));
  EXPECT_DOUBLE_EQ(n.ir_surface_bias_m, 0.02);
  EXPECT_FALSE(SetNoiseNominal("ir_surface_bias_m,wheel_bse_error", &n, &error));
  EXPECT_NE(error.find("'wheel_bse_error'"), std::string::npos) << error;
}

}  // namespace
}  // namespace irslam::metrics
