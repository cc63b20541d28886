#include "slam/slam.h"

namespace irslam::slam {

Slam::Slam(SlamOptions options) : options_(options), odometry_(options.geometry) {}

void Slam::AddWheelTicks(const WheelTicks& ticks) {
  const std::optional<Motion> m = odometry_.Add(ticks);
  if (!m) {
    trajectory_.push_back({ticks.t, pose_});
    return;
  }
  // Prediction step: pose and covariance follow the motion model.
  const Eigen::Matrix3d f = Odometry::JacobianPose(pose_, *m);
  pose_cov_ = f * pose_cov_ * f.transpose() +
              Odometry::ProcessNoise(pose_, *m, options_.motion_noise);
  pose_ = Odometry::Apply(pose_, *m);
  if (trajectory_.empty() || ticks.t - trajectory_.back().t >= options_.trajectory_period_s) {
    trajectory_.push_back({ticks.t, pose_});
  }
}

void Slam::AddRangeScan(const RangeScan& /*scan*/) {}

}  // namespace irslam::slam
