#include "sim/bounce.h"

#include <cmath>
#include <random>

#include "drivers/ir_conditioner.h"
#include "drivers/motor_client.h"
#include "sim/sim_run.h"

namespace irslam::sim {

std::unique_ptr<SimController> RunBounce(const World& world, const robot::CoreOptions& options,
                                         uint64_t seed, double duration_s,
                                         const BounceOptions& b) {
  auto sim = std::make_unique<SimController>(world, SimOptionsFrom(options), seed);
  drivers::MotorClient motor(options.motor);
  drivers::IrConditioner ir(options.ir);
  std::mt19937_64 rng(seed * 7919 + 17);
  std::uniform_real_distribution<double> angle(b.min_turn_rad, b.max_turn_rad);
  std::bernoulli_distribution side(0.5);
  const double io_dt = 0.002;
  const double radius = options.slam.geometry.radius_m;
  double next_tick = options.period_s, last_heartbeat = -1e9;
  double turn_left_rad = 0, turn_sign = 1, heading = 0;  // heading: odometry, to measure turns
  double escape_until = 0;
  std::vector<can_frame> frames;
  for (double t = 0; t < duration_s;) {
    t += io_dt;
    frames.clear();
    sim->AdvanceTo(t, &frames);
    for (const can_frame& f : frames) {
      const auto ev = motor.Handle(f, t);
      if (ev.ir_adc) ir.Add(ev.ir_t, *ev.ir_adc);
    }
    if (t < next_tick - 1e-9) continue;
    next_tick += options.period_s;
    // The turn so far, from the true heading change the wheels made (the cleaner
    // only needs it roughly: a random angle stays random).
    const double th = sim->true_pose().theta;
    const double dth = std::remainder(th - heading, 2 * M_PI);
    heading = th;
    WheelCommand cmd{0, 0, true};
    bool near = motor.bumpers() != 0;
    const RangeScan& scan = ir.scan();
    for (int i = 2; i <= 4; ++i) {  // the three forward sensors
      const auto& m = options.slam.mounts[static_cast<size_t>(i)];
      if (scan.range_m[static_cast<size_t>(i)] &&
          *scan.range_m[static_cast<size_t>(i)] + std::hypot(m.x, m.y) - radius < b.near_m)
        near = true;
    }
    if (turn_left_rad > 0) {
      turn_left_rad -= std::abs(dth);
      const double w = turn_sign * b.turn_rate_rad_s * 0.5 * options.slam.geometry.wheel_base_m;
      cmd = {-w, w, true};
      if (turn_left_rad <= 0) escape_until = t + 1.0;
    } else if (near && t >= escape_until) {
      turn_left_rad = angle(rng);
      turn_sign = side(rng) ? 1 : -1;
    } else if (!(near && motor.bumpers() != 0)) {
      cmd = {b.speed_mps, b.speed_mps, true};
    }
    sim->HandleFrame(motor.MakeCommand(cmd));
    if (t - last_heartbeat >= options.heartbeat_period_s) {
      last_heartbeat = t;
      sim->HandleFrame(motor.MakeHeartbeat(static_cast<uint8_t>(control::MissionState::kClean)));
    }
  }
  return sim;
}

}  // namespace irslam::sim
