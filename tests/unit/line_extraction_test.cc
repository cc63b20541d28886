#include <gtest/gtest.h>

#include <Eigen/LU>
#include <random>

#include "slam/line_extraction.h"
#include "types/geometry.h"
#include "types/signals.h"

namespace irslam::slam {
namespace {

// Points on x cos(theta) + y sin(theta) = rho, from s0 to s1 along the line.
Points OnLine(double rho, double theta, double s0, double s1, int n, double noise = 0,
              uint32_t seed = 1) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> g(0, noise > 0 ? noise : 1);
  const Eigen::Vector2d nrm(std::cos(theta), std::sin(theta)), dir(-std::sin(theta), std::cos(theta));
  Points p;
  for (int i = 0; i < n; ++i) {
    const double s = s0 + (s1 - s0) * i / (n - 1);
    p.push_back(rho * nrm + s * dir + (noise > 0 ? g(rng) : 0.0) * nrm);
  }
  return p;
}

TEST(LineExtractionTest, NormalizeLineKeepsRhoPositiveAndThetaInRange) {
  double r = -1, t = 0.5;
  NormalizeLine(&r, &t);
  EXPECT_DOUBLE_EQ(r, 1);
  EXPECT_NEAR(t, 0.5 - M_PI, 1e-12);
  r = 2, t = 3 * M_PI;
  NormalizeLine(&r, &t);
  EXPECT_NEAR(t, M_PI, 1e-12);  // (-pi, pi]: pi, never -pi
}

TEST(LineExtractionTest, OrthogonalFitIsExactOnExactPoints) {
  const LineFit f = FitLine(OnLine(0.7, 0.3, -0.5, 0.5, 20));
  EXPECT_NEAR(f.rho, 0.7, 1e-12);
  EXPECT_NEAR(f.theta, 0.3, 1e-12);
  EXPECT_NEAR(f.rms, 0, 1e-9);
}

TEST(LineExtractionTest, FitsALineThroughTheAngleCut) {
  // x = -1: normal angle pi, where -pi and pi meet.
  const LineFit f = FitLine(OnLine(1.0, M_PI, -0.5, 0.5, 20, 0.002));
  EXPECT_NEAR(f.rho, 1.0, 0.003);
  EXPECT_NEAR(std::abs(NormalizeAngle(f.theta - M_PI)), 0, 0.01);
}

TEST(LineExtractionTest, GravityResamplingAveragesNeighbours) {
  Points p;
  for (int i = 0; i < 10; ++i) {
    p.emplace_back(1.0, 0.1 * i);
    p.emplace_back(1.0, 0.1 * i + 0.004);  // a twin 4 mm away
  }
  const Points r = GravityResample(p, {0, 0}, 0.02, 4);
  ASSERT_EQ(r.size(), 10u);
  EXPECT_NEAR(r[3].y(), 0.302, 1e-12);
  EXPECT_NEAR(r[3].x(), 1.0, 1e-12);
}

TEST(LineExtractionTest, ResamplingKeepsASurfaceAcrossThePolarCutInOnePiece) {
  // A wall behind the centre spans polar angles around +-pi.
  const Points p = OnLine(1.0, M_PI, -0.6, 0.6, 40);
  const Points r = GravityResample(p, {0, 0}, 0.01, 1);
  const auto clusters = GapCluster(r, 0.1);
  EXPECT_EQ(clusters.size(), 1u);
}

TEST(LineExtractionTest, GapClusteringSplitsAtGaps) {
  Points p = OnLine(1, 0, 0, 0.5, 11);
  const Points q = OnLine(1, 0, 0.8, 1.2, 9);
  p.insert(p.end(), q.begin(), q.end());
  const auto c = GapCluster(p, 0.1);
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c[0].size(), 11u);
  EXPECT_EQ(c[1].size(), 9u);
}

TEST(LineExtractionTest, IepfSplitsACornerAndKeepsAStraightLine) {
  Points corner = OnLine(1, -M_PI / 2, 0, 1, 21);  // y = -1, x from 0 to 1 (dir = (1,0))
  for (const auto& v : OnLine(1, 0, -0.95, 0, 20)) corner.push_back(v);  // x = 1, up to y = 0
  const auto pieces = SplitAndMerge(corner, 0.02);
  ASSERT_EQ(pieces.size(), 2u);
  EXPECT_NEAR(pieces[0].back().x(), 1.0, 1e-9);  // the corner point ends the first piece
  EXPECT_EQ(SplitAndMerge(OnLine(1, 0.2, -1, 1, 50, 0.003), 0.03).size(), 1u);
}

TEST(LineExtractionTest, PruningDropsShortAndSparseClusters) {
  std::vector<Points> c = {OnLine(1, 0, 0, 1, 20), OnLine(1, 0, 0, 0.1, 20), OnLine(1, 0, 0, 1, 3)};
  const auto kept = Prune(c, 6, 0.3);
  ASSERT_EQ(kept.size(), 1u);
  EXPECT_EQ(kept[0].size(), 20u);
}

TEST(LineExtractionTest, ConstrainedHoughRefinesTheFitInA121CellWindow) {
  const Points p = OnLine(0.5, 1.0, -0.4, 0.4, 40, 0.003, 7);
  ExtractionOptions o;
  // Start 2 cm and 2 degrees off: the votes pull the estimate back.
  const HoughResult h = ConstrainedHough(p, 0.52, 1.0 + 2 * M_PI / 180, o);
  EXPECT_EQ(h.cells, 121);
  EXPECT_LE(h.votes_cast, 40 * 11);  // one vote per point and theta column at most
  EXPECT_GE(h.peak_votes, 20);
  EXPECT_NEAR(h.rho, 0.5, 0.006);
  EXPECT_NEAR(h.theta, 1.0, 0.6 * M_PI / 180);
  // Eq. (7) covariance: symmetric, positive definite, at least the cell quantisation.
  EXPECT_NEAR(h.cov(0, 1), h.cov(1, 0), 1e-15);
  EXPECT_GT(h.cov.determinant(), 0);
  EXPECT_GE(h.cov(0, 0), 0.01 * 0.01 / 12);
}

TEST(LineExtractionTest, FullHoughUses64800CellsForTheSameAnswer) {
  const Points p = OnLine(0.5, 1.0, -0.4, 0.4, 40, 0.0, 7);
  ExtractionOptions o;
  const HoughResult h = FullHough(p, 1.79, o);
  EXPECT_EQ(h.cells, 180 * 360);  // the paper's Table 1
  EXPECT_NEAR(h.rho, 0.5, 0.011);
  EXPECT_NEAR(std::abs(NormalizeAngle(h.theta - 1.0)), 0, 1.1 * M_PI / 180);
}

TEST(LineExtractionTest, CombinedUncertaintyIsEquation8) {
  ExtractionOptions o;
  Eigen::Matrix2d c;
  c << 1e-4, 0, 0, 2e-4;
  EXPECT_NEAR(CombinedUncertainty(0.5, c, o),
              o.weight_length / 0.5 + o.weight_rho * 1e-4 + o.weight_theta * 2e-4, 1e-12);
}

TEST(LineExtractionTest, ExtractsTwoWallsOfACornerAndIgnoresOutliers) {
  Points pts = OnLine(0.4, -M_PI / 2, -0.2, 0.8, 40, 0.004, 1);  // y = -0.4 (right wall)
  const Points front = OnLine(0.9, 0.0, -0.39, 0.5, 36, 0.004, 2);  // x = 0.9 (wall ahead)
  pts.insert(pts.end(), front.begin(), front.end());
  pts.emplace_back(0.3, 0.3);  // stray readings
  pts.emplace_back(-0.5, 0.6);
  ExtractionStats st;
  const auto lines = ExtractLines(pts, {0, 0}, ExtractionOptions{}, &st);
  ASSERT_EQ(lines.size(), 2u);
  EXPECT_EQ(st.kept, 2);
  for (const auto& l : lines) {
    const bool right = std::abs(NormalizeAngle(l.theta + M_PI / 2)) < 0.1;
    EXPECT_NEAR(l.rho, right ? 0.4 : 0.9, 0.01);
    EXPECT_NEAR(NormalizeAngle(l.theta - (right ? -M_PI / 2 : 0.0)), 0, 1.0 * M_PI / 180);
    EXPECT_GT(l.length, right ? 0.9 : 0.8);
    EXPECT_LT(l.uncertainty, ExtractionOptions{}.max_uncertainty);
  }
}

TEST(LineExtractionTest, ASingleWallGivesOneLine) {
  const auto lines = ExtractLines(OnLine(0.35, -M_PI / 2, -0.3, 0.3, 30, 0.003), {0, 0.1}, {});
  ASSERT_EQ(lines.size(), 1u);
  EXPECT_NEAR(lines[0].rho, 0.35, 0.006);
}

TEST(LineExtractionTest, SparsePointsAtTheRangeLimitGiveNoLine) {
  // At ~1.2 m the sensors are noisy (3 cm) and sparse: nothing passes the filters.
  const auto lines = ExtractLines(OnLine(1.2, 0.0, -0.3, 0.3, 5, 0.03), {0, 0}, {});
  EXPECT_TRUE(lines.empty());
}

}  // namespace
}  // namespace irslam::slam
