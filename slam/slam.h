// The SLAM front door: wheel ticks and range scans in (each with its own time),
// corrected pose, its covariance, the line map and the trajectory out.
// Pure: no clock, socket or file.
#ifndef IRSLAM_SLAM_SLAM_H_
#define IRSLAM_SLAM_SLAM_H_

#include <Eigen/Core>
#include <array>
#include <vector>

#include "slam/odometry.h"
#include "slam/types.h"

namespace irslam::slam {

// Where an IR sensor sits on the robot (robot frame: x forward, y left).
struct SensorMount {
  double x = 0;
  double y = 0;
  double theta = 0;
};

struct SlamOptions {
  RobotGeometry geometry;
  MotionNoise motion_noise;
  std::array<SensorMount, kNumIrSensors> mounts{};
  double trajectory_period_s = 0.25;  // trajectory sampling (>= 2 Hz, contracts §4)
};

struct LineFeature {
  int id = 0;
  double rho = 0;
  double theta = 0;
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  Eigen::Vector2d p0 = Eigen::Vector2d::Zero();
  Eigen::Vector2d p1 = Eigen::Vector2d::Zero();
  double length() const { return (p1 - p0).norm(); }
};

struct TrajectoryPoint {
  double t = 0;
  Pose2 pose;
};

class Slam {
 public:
  explicit Slam(SlamOptions options);

  void AddWheelTicks(const WheelTicks& ticks);
  void AddRangeScan(const RangeScan& scan);

  const Pose2& pose() const { return pose_; }
  const Eigen::Matrix3d& pose_cov() const { return pose_cov_; }
  const std::vector<LineFeature>& lines() const { return lines_; }
  const std::vector<TrajectoryPoint>& trajectory() const { return trajectory_; }
  double distance_m() const { return odometry_.distance_m(); }
  double time() const { return odometry_.last_t(); }
  const SlamOptions& options() const { return options_; }

 private:
  SlamOptions options_;
  Odometry odometry_;
  Pose2 pose_;
  Eigen::Matrix3d pose_cov_ = Eigen::Matrix3d::Zero();
  std::vector<LineFeature> lines_;
  std::vector<TrajectoryPoint> trajectory_;
};

}  // namespace irslam::slam

#endif  // IRSLAM_SLAM_SLAM_H_
