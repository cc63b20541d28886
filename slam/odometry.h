// Wheel odometry for a differential-drive robot: cumulative encoder counts in,
// pose increments out. Also the motion noise model used to grow the pose
// covariance (noise growing with distance travelled and angle turned).
#ifndef IRSLAM_SLAM_ODOMETRY_H_
#define IRSLAM_SLAM_ODOMETRY_H_

#include <Eigen/Core>
#include <optional>

#include "types/geometry.h"
#include "types/options.h"
#include "types/robot.h"
#include "types/signals.h"

namespace irslam::slam {

struct MotionNoise {
  double var_per_m = 4e-4;          // m^2 of position variance per metre travelled
  double var_theta_per_rad = 1e-3;  // rad^2 of heading variance per radian turned
  double var_theta_per_m = 2e-4;    // rad^2 of heading variance per metre travelled
};

// A pose increment in the robot frame at the start of the increment.
struct Motion {
  double ds = 0;      // distance travelled by the centre
  double dtheta = 0;  // rotation
};

// Config section [slam] (odometry noise keys).
options::Table<MotionNoise> MotionNoiseKeys();

class Odometry {
 public:
  explicit Odometry(RobotGeometry geometry) : geometry_(geometry) {}

  // Returns the motion since the previous ticks (nullopt for the first sample).
  std::optional<Motion> Add(const WheelTicks& ticks);
  // Dead-reckoned pose in the odometry frame (starts at the origin).
  const Pose2& pose() const { return pose_; }
  double distance_m() const { return distance_m_; }
  double last_t() const { return last_ ? last_->t : 0.0; }

  // Applies a motion to a pose (midpoint integration).
  static Pose2 Apply(const Pose2& p, const Motion& m);
  // Jacobians of Apply with respect to the pose (3x3) and process noise Q for m.
  static Eigen::Matrix3d JacobianPose(const Pose2& p, const Motion& m);
  static Eigen::Matrix3d ProcessNoise(const Pose2& p, const Motion& m, const MotionNoise& n);

 private:
  RobotGeometry geometry_;
  std::optional<WheelTicks> last_;
  Pose2 pose_;
  double distance_m_ = 0;
};

}  // namespace irslam::slam

#endif  // IRSLAM_SLAM_ODOMETRY_H_
