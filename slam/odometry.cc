#include "slam/odometry.h"

#include <cassert>
#include <cmath>

namespace irslam::slam {

std::optional<WheelMotion> Odometry::Add(const WheelTicks& ticks, const OdometryCalibration& c) {
  if (!last_) {
    last_ = ticks;
    return std::nullopt;
  }
  assert(ticks.t >= last_->t && "wheel ticks must not go back in time");
  const double k = geometry_.metres_per_count();
  const double dl = static_cast<double>(ticks.left - last_->left) * k;
  const double dr = static_cast<double>(ticks.right - last_->right) * k;
  last_ = ticks;
  const WheelMotion w{dl, dr};
  const Motion m = Calibrated(w, geometry_.wheel_base_m, c);
  pose_ = Apply(pose_, m);
  distance_m_ += std::abs(m.ds);
  return w;
}

Motion Odometry::Calibrated(const WheelMotion& w, double wheel_base_m, const OdometryCalibration& c) {
  const double l = c.left * w.dl, r = c.right * w.dr;
  return {0.5 * (l + r), (r - l) / (c.base * wheel_base_m)};
}

Eigen::Matrix<double, 2, 3> Odometry::JacobianCalibration(const WheelMotion& w, double wheel_base_m,
                                                          const OdometryCalibration& c) {
  const double b = c.base * wheel_base_m;
  const double dtheta = (c.right * w.dr - c.left * w.dl) / b;
  Eigen::Matrix<double, 2, 3> j;
  j << 0.5 * w.dl, 0.5 * w.dr, 0,
       -w.dl / b, w.dr / b, -dtheta / c.base;
  return j;
}

Eigen::Matrix<double, 3, 2> Odometry::JacobianMotion(const Pose2& p, const Motion& m) {
  const double mid = p.theta + 0.5 * m.dtheta;
  Eigen::Matrix<double, 3, 2> g;
  g << std::cos(mid), -0.5 * m.ds * std::sin(mid),
       std::sin(mid), 0.5 * m.ds * std::cos(mid),
       0, 1;
  return g;
}

Pose2 Odometry::Apply(const Pose2& p, const Motion& m) {
  const double mid = p.theta + 0.5 * m.dtheta;
  return {p.x + m.ds * std::cos(mid), p.y + m.ds * std::sin(mid),
          NormalizeAngle(p.theta + m.dtheta)};
}

Eigen::Matrix3d Odometry::JacobianPose(const Pose2& p, const Motion& m) {
  const double mid = p.theta + 0.5 * m.dtheta;
  Eigen::Matrix3d f = Eigen::Matrix3d::Identity();
  f(0, 2) = -m.ds * std::sin(mid);
  f(1, 2) = m.ds * std::cos(mid);
  return f;
}

Eigen::Matrix3d Odometry::ProcessNoise(const Pose2& p, const Motion& m, const MotionNoise& n) {
  // Noise in the motion (ds, dtheta), mapped into the pose through the Jacobian
  // with respect to the motion.
  const Eigen::Matrix<double, 3, 2> g = JacobianMotion(p, m);
  Eigen::Matrix2d q = Eigen::Matrix2d::Zero();
  q(0, 0) = n.var_per_m * std::abs(m.ds) + 1e-12;
  q(1, 1) = n.var_theta_per_rad * std::abs(m.dtheta) + n.var_theta_per_m * std::abs(m.ds) + 1e-12;
  return g * q * g.transpose();
}

options::Table<MotionNoise> MotionNoiseKeys() {
  using N = MotionNoise;
  static constexpr options::Key<N> kKeys[] = {
      {"var_per_m", &N::var_per_m, 0, 1, "m^2/m", "odometry position variance per metre travelled"},
      {"var_theta_per_rad", &N::var_theta_per_rad, 0, 1, "rad^2/rad", "heading variance per radian turned"},
      {"var_theta_per_m", &N::var_theta_per_m, 0, 1, "rad^2/m", "heading variance per metre travelled"},
      {"adapt_window", &N::adapt_window, 0, 1000, "",
       "> 0: the variances above scaled by the mean NIS / 2 of this many recent matches (0: fixed)"},
      {"adapt_max_scale", &N::adapt_max_scale, 1, 1e4, "", "... clamped to 1 .. this"},
  };
  return kKeys;
}

options::Table<CalibrationOptions> CalibrationKeys() {
  using C = CalibrationOptions;
  static constexpr options::Key<C> kKeys[] = {
      {"enabled", &C::enabled, 0, 0, "",
       "estimate the wheel radius and track width scale factors in the EKF (false: nominal, fixed)"},
      {"prior_sigma_wheel", &C::prior_sigma_wheel, 1e-5, 0.2, "",
       "1-sigma of each wheel radius scale factor at the start (without a saved value)"},
      {"prior_sigma_base", &C::prior_sigma_base, 1e-5, 0.3, "",
       "1-sigma of the track width scale factor at the start (without a saved value)"},
      {"resume_sigma", &C::resume_sigma, 0, 0.2, "",
       "added in quadrature to a saved calibration's sigma when a mission starts from it"},
      {"random_walk_per_m", &C::random_walk_per_m, 0, 1e-3, "1/m",
       "variance added to each scale factor per metre travelled (floor changes, wear)"},
      {"min_sigma", &C::min_sigma, 0, 0.1, "",
       "the scale factors' sigma is kept at least this (the filter never locks them)"},
  };
  return kKeys;
}

}  // namespace irslam::slam
