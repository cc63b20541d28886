#include "sim/sim_controller.h"

#include <algorithm>
#include <cmath>

#include "proto/codec.h"

namespace irslam::sim {

SimController::SimController(World world, SimOptions options, uint64_t seed)
    : world_(std::move(world)),
      options_(options),
      calibration_(options_.ir),
      segments_(world_.Segments()),
      rng_(seed),
      effects_rng_(seed ^ 0x9e3779b97f4a7c15ULL),
      pose_(world_.start),
      odom_pose_(world_.start),
      next_encoder_(options_.encoder_period_s),
      next_status_(options_.status_period_s) {
  surface_bias_m_.assign(segments_.size(), 0.0);
  if (world_.noise.ir_surface_bias_m > 0) {
    std::uniform_real_distribution<double> bias(-world_.noise.ir_surface_bias_m, world_.noise.ir_surface_bias_m);
    for (double& b : surface_bias_m_) b = bias(effects_rng_);
  }
}

std::pair<double, double> SimController::Slip(double dt, double turn_rate) {
  const SimNoise& n = world_.noise;
  if (n.slip_correlation_s <= 0) {
    // White slip per physics step (the default).
    std::normal_distribution<double> slip(0.0, n.slip_sigma);
    const double l = slip(rng_);
    return {l, slip(rng_)};
  }
  // Ornstein-Uhlenbeck per wheel: stationary sigma slip_sigma, correlation time
  // slip_correlation_s; it grows with the turn rate (a wheel scrubs in turns).
  const double a = std::exp(-dt / n.slip_correlation_s);
  std::normal_distribution<double> w(0.0, n.slip_sigma * std::sqrt(1 - a * a));
  slip_l_ = a * slip_l_ + w(effects_rng_);
  slip_r_ = a * slip_r_ + w(effects_rng_);
  const double grow = 1.0 + std::abs(turn_rate);  // x2 at 1 rad/s
  return {slip_l_ * grow, slip_r_ * grow};
}

void SimController::HandleFrame(const can_frame& frame) {
  const proto::DecodeResult r = proto::Decode(frame);
  if (!r.ok()) return;
  if (const auto* c = std::get_if<proto::WheelCmd>(&r.message)) {
    const double vmax = options_.geometry.max_wheel_speed_mps;
    enabled_ = c->enable;
    target_l_ = c->enable ? std::clamp(c->left_mps, -vmax, vmax) : 0.0;
    target_r_ = c->enable ? std::clamp(c->right_mps, -vmax, vmax) : 0.0;
    last_cmd_t_ = t_;
    ever_commanded_ = true;
  }
}

void SimController::Teleport(const Pose2& p) {
  pose_ = {p.x, p.y, NormalizeAngle(p.theta)};
  // Put down at rest: the wheels start again from standstill, out of any contact.
  vl_ = vr_ = 0;
  blocked_ = false;
  in_contact_ = false;
  bumpers_ = 0;
}

double SimController::Clearance(const Pose2& p, uint8_t* bumpers) const {
  // The nearest side by squared distance (hypot, a libm call, only for the
  // nearest: this runs twice per physics step over every side).
  double best2 = 1e18;
  Vec2 contact{};
  for (const Segment& s : segments_) {
    const Vec2 c = ClosestOnSegment({p.x, p.y}, s);
    const double dx = p.x - c.x, dy = p.y - c.y, d2 = dx * dx + dy * dy;
    if (d2 < best2) {
      best2 = d2;
      contact = c;
    }
  }
  const double best = segments_.empty() ? 1e9 : std::hypot(p.x - contact.x, p.y - contact.y);
  if (bumpers) {
    *bumpers = 0;
    if (best < options_.geometry.radius_m + 0.003) {
      const double a = NormalizeAngle(std::atan2(contact.y - p.y, contact.x - p.x) - p.theta);
      if (a > -0.35) *bumpers |= kBumperLeft;
      if (a < 0.35) *bumpers |= kBumperRight;
    }
  }
  return best;
}

void SimController::PhysicsStep(double dt) {
  // The controller's safety stop: no command for command_timeout_s -> wheels to zero.
  const bool timed_out = t_ - last_cmd_t_ > options_.command_timeout_s;
  const double tl = timed_out ? 0.0 : target_l_;
  const double tr = timed_out ? 0.0 : target_r_;
  const double dv = options_.wheel_accel_mps2 * dt;
  vl_ = std::clamp(tl, vl_ - dv, vl_ + dv);
  vr_ = std::clamp(tr, vr_ - dv, vr_ + dv);

  // Ground motion: true radii and track width differ from nominal, and wheels slip.
  const double true_base = options_.geometry.wheel_base_m * (1.0 + world_.noise.wheel_base_error);
  const auto [slip_l, slip_r] = Slip(dt, (vr_ - vl_) / true_base);
  const double gl = vl_ * dt * (1.0 + world_.noise.wheel_radius_error_left) * (1.0 + slip_l);
  const double gr = vr_ * dt * (1.0 + world_.noise.wheel_radius_error_right) * (1.0 + slip_r);
  const double ds = 0.5 * (gl + gr);
  const double dth = (gr - gl) / true_base;
  const double mid = pose_.theta + 0.5 * dth;
  Pose2 next{pose_.x + ds * std::cos(mid), pose_.y + ds * std::sin(mid),
             NormalizeAngle(pose_.theta + dth)};

  const double before = Clearance(pose_, nullptr);
  uint8_t bump = 0;
  const double after = Clearance(next, &bump);
  const double radius = options_.geometry.radius_m;
  if (after < radius && after < before) {
    // Blocked: the robot does not move and the motors stall (no encoder counts).
    // One collision per contact: touching again before backing off 1 cm is the same one.
    if (!blocked_) {
      ++collisions_;
      collision_points_.push_back({t_, pose_.x, pose_.y});
    }
    blocked_ = true;
    in_contact_ = true;
    Clearance(pose_, &bump);
    bumpers_ = bump ? bump : static_cast<uint8_t>(kBumperLeft | kBumperRight);
    vl_ = vr_ = 0;
    return;
  }
  if (after > radius + 0.01) blocked_ = false;
  in_contact_ = after < radius + 0.003;
  bumpers_ = in_contact_ ? bump : 0;
  pose_ = next;
  min_clearance_ = std::min(min_clearance_, after);

  // Encoders see the wheel rotation (nominal radius), quantised to whole counts.
  const double r = options_.geometry.wheel_radius_m;
  wheel_angle_l_ += vl_ * dt / r;
  wheel_angle_r_ += vr_ * dt / r;
  const double cpr = options_.geometry.counts_per_rev;
  counts_l_ = static_cast<int64_t>(std::floor(wheel_angle_l_ / (2 * M_PI) * cpr));
  counts_r_ = static_cast<int64_t>(std::floor(wheel_angle_r_ / (2 * M_PI) * cpr));
}

double SimController::SurfaceEffects(std::optional<double>* range, size_t seg, double angle) {
  const SimNoise& n = world_.noise;
  double gain = 1.0;
  if (n.ir_max_incidence_deg < 90) {
    // Incidence: the angle between the beam and the surface's normal.
    const Segment& sg = segments_[seg];
    const double ex = sg.b.x - sg.a.x, ey = sg.b.y - sg.a.y;
    const double along = std::abs(std::cos(angle) * ex + std::sin(angle) * ey) / std::hypot(ex, ey);
    const double incidence = std::asin(std::min(1.0, along));  // 0: head-on
    if (incidence > n.ir_max_incidence_deg * M_PI / 180.0) {
      range->reset();  // grazing: nothing comes back
      return 1.0;
    }
    gain = 1.0 / std::max(0.2, std::cos(incidence));
  }
  **range += surface_bias_m_[seg];
  if (n.ir_outlier_rate > 0) {
    std::uniform_real_distribution<double> u(0.0, 1.0);
    if (u(effects_rng_) < n.ir_outlier_rate) *range = 0.1 + 1.4 * u(effects_rng_);
  }
  return gain;
}

void SimController::SampleIr(std::vector<can_frame>* out) {
  std::array<uint16_t, kNumIrSensors> adc{};
  const double half_beam = 0.5 * world_.noise.ir_beam_deg * M_PI / 180.0;
  for (int i = 0; i < kNumIrSensors; ++i) {
    const Pose2 s = Compose(pose_, {options_.mounts[i].x, options_.mounts[i].y,
                                    options_.mounts[i].theta});
    // The beam returns the nearest surface inside its cone.
    std::optional<double> best;
    size_t best_seg = 0;
    double best_angle = s.theta;
    constexpr int kRays = 5;
    for (int k = 0; k < kRays; ++k) {
      const double a = s.theta - half_beam + 2 * half_beam * k / (kRays - 1);
      size_t seg = 0;
      const auto d = RayCast(segments_, {s.x, s.y}, a, 10.0, &seg);
      if (d && (!best || *d < *best)) best = d, best_seg = seg, best_angle = a;
    }
    const double noise_gain = best ? SurfaceEffects(&best, best_seg, best_angle) : 1.0;
    double volts = best ? calibration_.DistanceToVolts(*best) : 0.3;
    std::normal_distribution<double> noise(0.0, world_.noise.ir_voltage_sigma_rel * volts * noise_gain);
    volts = std::max(0.0, volts + noise(rng_));
    adc[i] = calibration_.VoltsToCounts(volts);
  }
  const auto stamp = static_cast<uint16_t>(static_cast<int64_t>(std::llround(t_ * 1000)) & 0xFFFF);
  proto::IrA a{seq_ir_, stamp, {adc[0], adc[1], adc[2]}};
  proto::IrB b{seq_ir_, {adc[3], adc[4], adc[5], adc[6]}};
  ++seq_ir_;
  out->push_back(proto::Encode(a));
  out->push_back(proto::Encode(b));
}

void SimController::AdvanceTo(double t, std::vector<can_frame>* out) {
  const double dt = options_.physics_dt_s;
  while (t_ + dt <= t + 1e-12) {
    PhysicsStep(dt);
    t_ += dt;
    const auto stamp =
        static_cast<uint16_t>(static_cast<int64_t>(std::llround(t_ * 1000)) & 0xFFFF);
    if (t_ >= next_encoder_ - 1e-9) {
      next_encoder_ += options_.encoder_period_s;
      out->push_back(proto::Encode(proto::EncoderCounts{
          stamp, static_cast<uint16_t>(counts_l_ & 0xFFFF),
          static_cast<uint16_t>(counts_r_ & 0xFFFF), seq_enc_++}));
      // Dead reckoning from the same counts (truth file's baseline).
      const double k = options_.geometry.metres_per_count();
      const double dl = static_cast<double>(counts_l_ - odom_counts_l_) * k;
      const double dr = static_cast<double>(counts_r_ - odom_counts_r_) * k;
      odom_counts_l_ = counts_l_;
      odom_counts_r_ = counts_r_;
      const double ds = 0.5 * (dl + dr), dth = (dr - dl) / options_.geometry.wheel_base_m;
      const double mid = odom_pose_.theta + 0.5 * dth;
      odom_pose_ = {odom_pose_.x + ds * std::cos(mid), odom_pose_.y + ds * std::sin(mid),
                    NormalizeAngle(odom_pose_.theta + dth)};
    }
    if (t_ >= next_status_ - 1e-9) {
      next_status_ += options_.status_period_s;
      const bool timed_out = t_ - last_cmd_t_ > options_.command_timeout_s;
      proto::ControllerStatus s;
      s.state = (enabled_ && !timed_out) ? proto::ControllerState::kDriving
                                         : proto::ControllerState::kReady;
      s.faults = timed_out && ever_commanded_ ? proto::kFaultCommandTimeout : 0;
      s.bumpers = bumpers_;
      s.battery_v = 14.4;
      s.timestamp_ms = stamp;
      s.seq = seq_status_++;
      out->push_back(proto::Encode(s));
    }
    if (t_ >= next_ir_ - 1e-9) {
      std::uniform_real_distribution<double> jitter(-world_.noise.ir_period_jitter_s,
                                                    world_.noise.ir_period_jitter_s);
      next_ir_ = t_ + world_.noise.ir_period_s + jitter(rng_);
      SampleIr(out);
    }
    if (t_ >= next_truth_ - 1e-9) {
      next_truth_ += options_.truth_period_s;
      truth_.push_back({t_, pose_.x, pose_.y, pose_.theta});
      odom_.push_back({t_, odom_pose_.x, odom_pose_.y, odom_pose_.theta});
    }
  }
}

nlohmann::json SimController::Truth() const {
  nlohmann::json tr = nlohmann::json::array(), od = nlohmann::json::array();
  for (const auto& p : truth_) tr.push_back(p);
  for (const auto& p : odom_) od.push_back(p);
  return {{"world", world_.name},
          {"trajectory", tr},
          {"odometry", od},
          {"collisions", collisions_},
          {"collision_points", collision_points_},
          {"min_clearance", min_clearance_},
          // The odometry's true systematic errors (world noise keys) and, as the
          // SLAM estimates them (status slam.calibration, the map's
          // "calibration"), the scale factors of the nominal left/right wheel
          // radius and track width.
          {"odometry_calibration",
           {{"wheel_radius_error_left", world_.noise.wheel_radius_error_left},
            {"wheel_radius_error_right", world_.noise.wheel_radius_error_right},
            {"wheel_base_error", world_.noise.wheel_base_error},
            {"scale",
             {1 + world_.noise.wheel_radius_error_left, 1 + world_.noise.wheel_radius_error_right,
              1 + world_.noise.wheel_base_error}},
            {"ratio", (1 + world_.noise.wheel_radius_error_right) / (1 + world_.noise.wheel_radius_error_left)}}}};
}

}  // namespace irslam::sim
