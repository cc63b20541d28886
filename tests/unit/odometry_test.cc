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
  EXPECT_NEAR(m->dl, 1.0, 1e-4);
  EXPECT_NEAR(m->dr, 1.0, 1e-4);
  EXPECT_NEAR(o.ToMotion(*m).ds, 1.0, 1e-4);
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

TEST(OdometryTest, CalibratedMotionScalesEachWheelAndTheTrack) {
  // Wheel radii 1 % and 0.5 % larger than nominal, track 2 % wider: the wheels
  // really travel 1.01 and 1.005 times what the nominal geometry says.
  const WheelMotion w{0.10, 0.12};
  const double b = 0.25;
  const Motion m = Odometry::Calibrated(w, b, {1.01, 1.005, 1.02});
  EXPECT_NEAR(m.ds, 0.5 * (0.101 + 0.1206), 1e-15);
  EXPECT_NEAR(m.dtheta, (0.1206 - 0.101) / (1.02 * b), 1e-15);
  const Motion nominal = Odometry::Calibrated(w, b, {});
  EXPECT_NEAR(nominal.ds, 0.11, 1e-15);
  EXPECT_NEAR(nominal.dtheta, 0.02 / b, 1e-15);
}

TEST(OdometryTest, CalibrationJacobianMatchesFiniteDifferences) {
  const Pose2 p{0.3, -0.2, 0.7};
  const double b = 0.25;
  const OdometryCalibration c{1.012, 0.991, 1.03};
  const double h = 1e-7;
  for (const WheelMotion& w : {WheelMotion{0.05, 0.06}, WheelMotion{-0.04, 0.04}, WheelMotion{0.03, -0.01}}) {
    const Eigen::Matrix<double, 2, 3> jm = Odometry::JacobianCalibration(w, b, c);
    // The pose's Jacobian with respect to the calibration, as LineEkf::Predict
    // composes it: d Apply / d motion * d motion / d calibration.
    const Eigen::Matrix<double, 3, 3> jp = Odometry::JacobianMotion(p, Odometry::Calibrated(w, b, c)) * jm;
    for (int k = 0; k < 3; ++k) {
      OdometryCalibration d = c;
      (k == 0 ? d.left : k == 1 ? d.right : d.base) += h;
      const Motion m0 = Odometry::Calibrated(w, b, c), m1 = Odometry::Calibrated(w, b, d);
      EXPECT_NEAR((m1.ds - m0.ds) / h, jm(0, k), 1e-6);
      EXPECT_NEAR((m1.dtheta - m0.dtheta) / h, jm(1, k), 1e-6);
      const Pose2 a = Odometry::Apply(p, m0), e = Odometry::Apply(p, m1);
      EXPECT_NEAR((e.x - a.x) / h, jp(0, k), 1e-6);
      EXPECT_NEAR((e.y - a.y) / h, jp(1, k), 1e-6);
      EXPECT_NEAR(NormalizeAngle(e.theta - a.theta) / h, jp(2, k), 1e-6);
    }
  }
}

TEST(OdometryTest, MotionJacobianMatchesFiniteDifferences) {
  const Pose2 p{0.3, -0.2, 0.7};
  const Motion m{0.05, 0.02};
  const Eigen::Matrix<double, 3, 2> g = Odometry::JacobianMotion(p, m);
  const double h = 1e-7;
  for (int k = 0; k < 2; ++k) {
    Motion q = m;
    (k == 0 ? q.ds : q.dtheta) += h;
    const Pose2 a = Odometry::Apply(p, m), b = Odometry::Apply(p, q);
    EXPECT_NEAR((b.x - a.x) / h, g(0, k), 1e-6);
    EXPECT_NEAR((b.y - a.y) / h, g(1, k), 1e-6);
    EXPECT_NEAR(NormalizeAngle(b.theta - a.theta) / h, g(2, k), 1e-6);
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
