// The simulated motor controller and robot: differential-drive kinematics
// integrated at 500 Hz, encoders with quantisation, slip and a wheel-radius
// mismatch, seven Sharp-like IR sensors ray-cast with a 5 deg beam, collisions
// that stop the robot and set a bumper bit, and the controller's CAN protocol
// (proto/irslam.dbc): it stops the wheels when commands stop for 200 ms.
// Pure: time advances only through AdvanceTo(). Seeded, reproducible.
#ifndef IRSLAM_SIM_SIM_CONTROLLER_H_
#define IRSLAM_SIM_SIM_CONTROLLER_H_

#include <linux/can.h>

#include <array>
#include <nlohmann/json.hpp>
#include <random>
#include <vector>

#include "drivers/ir_calibration.h"
#include "slam/slam.h"
#include "sim/world.h"

namespace irslam::sim {

struct SimOptions {
  RobotGeometry geometry;
  std::array<SensorMount, kNumIrSensors> mounts{};
  drivers::IrCalibrationOptions ir;
  double physics_dt_s = 0.002;
  double encoder_period_s = 0.010;
  double status_period_s = 0.050;
  double command_timeout_s = 0.200;
  double wheel_accel_mps2 = 1.5;
  double truth_period_s = 0.05;
};

class SimController {
 public:
  SimController(World world, SimOptions options, uint64_t seed);

  // A frame from the bus (wheel commands; everything else is ignored).
  void HandleFrame(const can_frame& frame);
  // The robot is lifted and put down at p (world frame; the kidnap fault,
  // sim/faults.h): the true pose jumps, the wheels do not turn for the jump, so
  // the encoders (and the truth file's dead reckoning) count no motion for it.
  void Teleport(const Pose2& p);
  // Advances the simulation to robot time t, appending the frames sent meanwhile.
  void AdvanceTo(double t, std::vector<can_frame>* out);

  double time() const { return t_; }
  const Pose2& true_pose() const { return pose_; }
  const Pose2& odometry_pose() const { return odom_pose_; }
  uint64_t collisions() const { return collisions_; }
  // Where the robot was at each contact: [t, x, y].
  const std::vector<std::array<double, 3>>& collision_points() const { return collision_points_; }
  uint8_t bumpers() const { return bumpers_; }
  double wheel_speed_left() const { return vl_; }
  double wheel_speed_right() const { return vr_; }
  const World& world() const { return world_; }
  // Truth file (contracts §5).
  nlohmann::json Truth() const;
  // Minimum distance from the robot's centre to any obstacle over the run.
  double min_clearance() const { return min_clearance_; }

 private:
  void PhysicsStep(double dt);
  void SampleIr(std::vector<can_frame>* out);
  // Wheel slip (relative, left and right) for one physics step.
  std::pair<double, double> Slip(double dt, double turn_rate);
  // Surface bias, incidence drop-out and outliers applied to a return from
  // segment seg along the ray at angle; returns the factor on the voltage noise.
  double SurfaceEffects(std::optional<double>* range, size_t seg, double angle);
  double Clearance(const Pose2& p, uint8_t* bumpers) const;

  World world_;
  SimOptions options_;
  drivers::IrCalibration calibration_;
  std::vector<Segment> segments_;
  std::mt19937_64 rng_;
  // The error envelope's effects draw from their own generator, so a world
  // without them sees exactly the random sequence it always did.
  std::mt19937_64 effects_rng_;
  std::vector<double> surface_bias_m_;  // per segment
  double slip_l_ = 0, slip_r_ = 0;      // correlated slip state
  double t_ = 0;
  Pose2 pose_;
  Pose2 odom_pose_;
  double vl_ = 0, vr_ = 0;          // actual wheel surface speeds (nominal radius)
  double target_l_ = 0, target_r_ = 0;
  bool enabled_ = false;
  double last_cmd_t_ = -1e9;
  double wheel_angle_l_ = 0, wheel_angle_r_ = 0;  // rad
  int64_t counts_l_ = 0, counts_r_ = 0;
  int64_t odom_counts_l_ = 0, odom_counts_r_ = 0;
  uint8_t bumpers_ = 0;
  bool in_contact_ = false;
  bool blocked_ = false;
  bool ever_commanded_ = false;
  uint64_t collisions_ = 0;
  std::vector<std::array<double, 3>> collision_points_;  // [t, x, y] of the robot at each contact
  double min_clearance_ = 1e9;
  double next_encoder_, next_status_, next_ir_ = 0, next_truth_ = 0;
  uint8_t seq_enc_ = 0, seq_status_ = 0, seq_ir_ = 0;
  std::vector<std::array<double, 4>> truth_, odom_;
};

}  // namespace irslam::sim

#endif  // IRSLAM_SIM_SIM_CONTROLLER_H_
