#include <gtest/gtest.h>

#include "slam/odometry.h"

namespace irslam::slam {
namespace {

RobotGeometry Geometry() { return RobotGeometry{}; }

int64_t Counts(double metres) {
  return static_cast<int64_t>(std::llround(metres / Geometry().metres_per_count()));
}

TEST(OdometryTest, StraightLine) {
  Odometry o(Geometry());
  EXPECT_FALSE(o.Add({0, 0, 0}));
  const auto m = o.Add({1, Counts(1.0), Counts(1.0)});
  ASSERT_TRUE(m);
  EXPECT_NEAR(m->ds, 1.0, 1e-4);
  EXPECT_NEAR(o.pose().x, 1.0, 1e-4);
  EXPECT_NEAR(o.pose().y, 0.0, 1e-12);
  EXPECT_NEAR(o.pose().theta, 0.0, 1e-12);
}

TEST(OdometryTest, TurnInPlace) {
  Odometry o(Geometry());
  o.Add({0, 0, 0});
  // Wheels move +-(b/2)*(pi/2) for a quarter turn to the left.
  const double arc = 0.5 * Geometry().wheel_base_m * M_PI / 2;
  o.Add({1, -Counts(arc), Counts(arc)});
  EXPECT_NEAR(o.pose().theta, M_PI / 2, 2e-3);
  EXPECT_NEAR(o.pose().x, 0.0, 1e-12);
  EXPECT_NEAR(o.distance_m(), 0.0, 1e-3);
}

TEST(OdometryTest, QuarterCircleInSmallSteps) {
  Odometry o(Geometry());
  const double r = 1.0, b = Geometry().wheel_base_m;
  o.Add({0, 0, 0});
  const int n = 200;
  for (int i = 1; i <= n; ++i) {
    const double phi = M_PI / 2 * i / n;
    o.Add({i * 0.01, Counts((r - b / 2) * phi), Counts((r + b / 2) * phi)});
  }
  // Left quarter circle of radius 1 from the origin heading +x ends at (1, 1).
  EXPECT_NEAR(o.pose().x, 1.0, 3e-3);
  EXPECT_NEAR(o.pose().y, 1.0, 3e-3);
  EXPECT_NEAR(o.pose().theta, M_PI / 2, 2e-3);
}

TEST(OdometryTest, JacobianMatchesFiniteDifferences) {
  const Pose2 p{0.3, -0.2, 0.7};
  const Motion m{0.05, 0.02};
  const Eigen::Matrix3d j = Odometry::JacobianPose(p, m);
  const double h = 1e-7;
  for (int k = 0; k < 3; ++k) {
    Pose2 q = p;
    (k == 0 ? q.x : k == 1 ? q.y : q.theta) += h;
    const Pose2 a = Odometry::Apply(p, m), b = Odometry::Apply(q, m);
    EXPECT_NEAR((b.x - a.x) / h, j(0, k), 1e-6);
    EXPECT_NEAR((b.y - a.y) / h, j(1, k), 1e-6);
    EXPECT_NEAR((b.theta - a.theta) / h, j(2, k), 1e-6);
  }
}

TEST(OdometryTest, ProcessNoiseGrowsWithDistanceAndTurn) {
  const MotionNoise n;
  const Eigen::Matrix3d q1 = Odometry::ProcessNoise({}, {0.1, 0}, n);
  const Eigen::Matrix3d q2 = Odometry::ProcessNoise({}, {0.2, 0}, n);
  const Eigen::Matrix3d q3 = Odometry::ProcessNoise({}, {0.0, 0.5}, n);
  EXPECT_NEAR(q1(0, 0), n.var_per_m * 0.1, 1e-10);
  EXPECT_NEAR(q2(0, 0), 2 * q1(0, 0), 1e-10);
  EXPECT_NEAR(q3(2, 2), n.var_theta_per_rad * 0.5, 1e-10);
  EXPECT_GT(q3(2, 2), q1(2, 2));
}

}  // namespace
}  // namespace irslam::slam
