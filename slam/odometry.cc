#include "slam/odometry.h"

#include <cassert>
#include <cmath>

namespace irslam::slam {

std::optional<Motion> Odometry::Add(const WheelTicks& ticks) {
  if (!last_) {
    last_ = ticks;
    return std::nullopt;
  }
  assert(ticks.t >= last_->t && "wheel ticks must not go back in time");
  const double k = geometry_.metres_per_count();
  const double dl = static_cast<double>(ticks.left - last_->left) * k;
  const double dr = static_cast<double>(ticks.right - last_->right) * k;
  last_ = ticks;
  Motion m{0.5 * (dl + dr), (dr - dl) / geometry_.wheel_base_m};
  pose_ = Apply(pose_, m);
  distance_m_ += std::abs(m.ds);
  return m;
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
  const double mid = p.theta + 0.5 * m.dtheta;
  Eigen::Matrix<double, 3, 2> g;
  g << std::cos(mid), -0.5 * m.ds * std::sin(mid),
       std::sin(mid), 0.5 * m.ds * std::cos(mid),
       0, 1;
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
  };
  return kKeys;
}

}  // namespace irslam::slam
