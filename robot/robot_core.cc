#include "robot/robot_core.h"

#include <cmath>

#include "proto/codec.h"

namespace irslam::robot {

using namespace control;  // NOLINT(google-build-using-namespace): the behaviours RobotCore orchestrates

CoreOptions DefaultCoreOptions() {
  CoreOptions o;
  // Seven IR sensors on a ring of 5 cm radius, from the right (-90 deg) to the left (+90 deg).
  const double deg[kNumIrSensors] = {-90, -45, -20, 0, 20, 45, 90};
  for (int i = 0; i < kNumIrSensors; ++i) {
    const double a = deg[i] * M_PI / 180.0;
    o.slam.mounts[i] = {0.05 * std::cos(a), 0.05 * std::sin(a), a};
  }
  return o;
}

namespace {
drivers::MotorClientOptions WithCountLimit(drivers::MotorClientOptions m, const RobotGeometry& g) {
  m.max_counts_per_s = m.plausible_speed_factor * g.max_wheel_speed_mps / (2 * M_PI * g.wheel_radius_m) *
                       g.counts_per_rev;
  return m;
}
}  // namespace

RobotCore::RobotCore(CoreOptions options)
    : options_(std::move(options)),
      motor_(WithCountLimit(options_.motor, options_.slam.geometry)),
      calibration_(options_.ir),
      slam_(options_.slam),
      mission_(options_.mission, options_.wall, options_.explore, options_.model, options_.slam),
      estop_(options_.gpio.debounce_s),
      bump_left_(options_.gpio.debounce_s),
      bump_right_(options_.gpio.debounce_s) {}

void RobotCore::OnFrame(const can_frame& frame, double now_s) {
  const drivers::MotorClient::Event ev = motor_.Handle(frame, now_s);
  if (ev.ticks) {
    // Frames older than what SLAM has seen (reordered) are not fed back in time.
    if (ev.ticks->t >= slam_.time()) slam_.AddWheelTicks(*ev.ticks);
  }
  if (ev.ir_adc) {
    scan_.t = ev.ir_t;
    const auto& ir = options_.ir;
    for (int i = 0; i < kNumIrSensors; ++i) {
      const uint16_t adc = (*ev.ir_adc)[i];
      same_adc_[i] = adc == last_adc_[i] ? same_adc_[i] + 1 : 0;
      const double v = calibration_.CountsToVolts(adc);
      if (v < ir.plausible_min_v || v > ir.plausible_max_v) {
        ++ir_out_of_range_;  // a sensor fault, not a distance
        scan_.range_m[i].reset();
      } else if (ir.stuck_samples > 0 && same_adc_[i] + 1 >= ir.stuck_samples) {
        ++ir_stuck_;
        scan_.range_m[i].reset();
      } else {
        scan_.range_m[i] = calibration_.CountsToRange(adc);
      }
    }
    last_adc_ = *ev.ir_adc;
    slam_.AddRangeScan(scan_);
  }
  if (ev.status) {
    // A bumper bit counts when two status frames in a row (50 ms apart) carry
    // it: a real contact lasts (the robot is stopped against the obstacle), a
    // flipped bit does not.
    const uint8_t raw = ev.status->bumpers;
    bumpers_ = raw & last_status_bumpers_;
    const uint8_t new_bits = static_cast<uint8_t>(last_status_bumpers_ & ~bumpers_before_);
    if (new_bits & ~raw) ++bumper_unconfirmed_;  // set in one frame only
    bumpers_before_ = last_status_bumpers_;
    last_status_bumpers_ = raw;
  }
}

void RobotCore::OnSafetyInput(SafetyInput input, bool active, double now_s) {
  switch (input) {
    case SafetyInput::kEstop:
      estop_.Input(active, now_s);
      if (estop_.Poll(now_s) && !estop_latched_) {
        estop_latched_ = true;
        mission_.SetFault(now_s, "emergency stop pressed");
        last_cmd_ = {};
      }
      break;
    case SafetyInput::kBumperLeft: bump_left_.Input(active, now_s); break;
    case SafetyInput::kBumperRight: bump_right_.Input(active, now_s); break;
  }
}

void RobotCore::LatchFault(double now_s, const std::string& reason) {
  fault_latched_ = true;
  mission_.SetFault(now_s, reason);
  last_cmd_ = {};
}

bool RobotCore::MotorEnable() const {
  if (estop_latched_ || estop_.active()) return false;
  switch (mission_.state()) {
    case MissionState::kWallFollow:
    case MissionState::kModel:
    case MissionState::kGoToP1:
    case MissionState::kContourFollow: return true;
    default: return false;
  }
}

bool RobotCore::StatusLed(double now_s) const {
  return LedOn(estop_latched_ ? MissionState::kFault : mission_.state(), now_s);
}

std::vector<can_frame> RobotCore::Tick(double now_s) {
  std::vector<can_frame> out;
  const bool alive = motor_.ControllerAlive(now_s);
  const bool active = mission_.state() != MissionState::kIdle &&
                      mission_.state() != MissionState::kDone;
  const bool estop_was_pressed = estop_.active();
  if (estop_latched_ && estop_was_pressed && !estop_.Poll(now_s)) {  // debounced release
    mission_.SetFault(now_s, "emergency stop released: start to resume");
  }
  if (estop_latched_ || fault_latched_) {
    // Only start clears an emergency stop (or a latched fault).
  } else if (!alive && active && mission_.state() != MissionState::kFault) {
    mission_.SetFault(now_s, std::string("controller lost: ") + motor_.LossReason(now_s));
  } else if (alive && mission_.state() == MissionState::kFault) {
    mission_.ClearFault(now_s);
  }
  const uint8_t gpio_bumpers = static_cast<uint8_t>((bump_left_.Poll(now_s) ? kBumperLeft : 0) |
                                                    (bump_right_.Poll(now_s) ? kBumperRight : 0));
  last_cmd_ = mission_.Step(now_s, slam_, scan_, bumpers_ | gpio_bumpers);
  out.push_back(motor_.MakeCommand(last_cmd_));
  if (now_s - last_heartbeat_ >= options_.heartbeat_period_s - 1e-9) {
    last_heartbeat_ = now_s;
    out.push_back(motor_.MakeHeartbeat(static_cast<uint8_t>(mission_.state())));
  }
  return out;
}

bool RobotCore::Start(double now_s, std::string* why) {
  if (estop_.Poll(now_s)) {
    *why = "emergency stop is pressed";
    return false;
  }
  if (!motor_.ControllerAlive(now_s)) {
    *why = std::string("controller not reachable: ") + motor_.LossReason(now_s);
    return false;
  }
  if (estop_latched_ || fault_latched_) {
    // Released and started again: carry on from where the stop came (SLAM kept).
    estop_latched_ = false;
    fault_latched_ = false;
    mission_.ClearFault(now_s);
    if (mission_.state() != MissionState::kIdle && mission_.state() != MissionState::kDone) return true;
  }
  return mission_.Start(now_s, why);
}

void RobotCore::Stop(double now_s) {
  mission_.Stop(now_s);
  last_cmd_ = {};
}

can_frame RobotCore::StopFrame() { return motor_.MakeCommand(WheelCommand{}); }

namespace {

nlohmann::json PoseJson(const Pose2& p) { return {p.x, p.y, p.theta}; }

nlohmann::json MatrixJson(const Eigen::MatrixXd& m) {
  nlohmann::json rows = nlohmann::json::array();
  for (int i = 0; i < m.rows(); ++i) {
    nlohmann::json row = nlohmann::json::array();
    for (int j = 0; j < m.cols(); ++j) row.push_back(m(i, j));
    rows.push_back(row);
  }
  return rows;
}

}  // namespace

nlohmann::json RobotCore::Status(double now_s) const {
  const auto& c = motor_.counters();
  const Eigen::Matrix3d cov = slam_.map_pose_cov();
  const auto& st = slam_.stats();
  nlohmann::json ranges = nlohmann::json::array();
  for (const auto& r : scan_.range_m) ranges.push_back(r ? nlohmann::json(*r) : nlohmann::json());
  nlohmann::json s = {
      {"state", ToString(mission_.state())},
      {"reason", mission_.reason()},
      {"behaviour", ToString(mission_.wall_follower().mode())},
      {"robot_time", now_s},
      {"pose", PoseJson(slam_.map_pose())},
      {"pose_std", {std::sqrt(cov(0, 0)), std::sqrt(cov(1, 1)), std::sqrt(cov(2, 2))}},
      {"distance", slam_.distance_m()},
      {"lines", slam_.num_lines()},
      {"slam", {{"windows", st.windows}, {"lines_extracted", st.lines_extracted},
                {"updates", st.updates}, {"insertions", st.insertions},
                {"rejected_angle", st.rejected_angle}, {"merges", st.merges},
                {"loop_closures", st.loop_closures}}},
      {"objects", mission_.model().objects.size()},
      {"objects_pending", mission_.model().pending()},
      {"target_object", mission_.target_object()},
      {"ir_ranges", ranges},
      {"ir_adc", last_adc_},
      {"command", {last_cmd_.left_mps, last_cmd_.right_mps}},
      {"safety", {{"estop", estop_.active()}, {"estop_latched", estop_latched_},
                  {"bumper_left", bump_left_.active()}, {"bumper_right", bump_right_.active()},
                  {"motor_enable", MotorEnable()}}},
      {"controller",
       {{"alive", motor_.ControllerAlive(now_s)},
        {"state", motor_.last_status() ? static_cast<int>(motor_.last_status()->state) : -1},
        {"faults", motor_.last_status() ? motor_.last_status()->faults : 0},
        {"bumpers", motor_.last_status() ? motor_.last_status()->bumpers : 0},
        {"battery", motor_.last_status() ? motor_.last_status()->battery_v : 0.0}}},
      {"frames",
       {{"encoder", c.encoder_frames},
        {"ir", c.ir_samples},
        {"status", c.status_frames},
        {"unknown_id", c.unknown_id},
        {"wrong_dlc", c.wrong_dlc},
        {"ignored", c.ignored},
        {"seq_gap_encoder", c.seq_gap_encoder},
        {"seq_gap_ir", c.seq_gap_ir},
        {"seq_gap_status", c.seq_gap_status},
        {"ir_unpaired", c.ir_unpaired},
        {"controller_resets", c.controller_resets},
        {"clock_jumps", c.clock_jumps},
        {"duplicate", c.duplicate},
        {"stale", c.stale},
        {"implausible_time", c.implausible_time},
        {"implausible_counts", c.implausible_counts},
        {"ir_out_of_range", ir_out_of_range_},
        {"ir_stuck", ir_stuck_},
        {"bumper_unconfirmed", bumper_unconfirmed_}}},
  };
  return s;
}

nlohmann::json RobotCore::Map() const {
  const EnvironmentModel& model = mission_.model();
  const auto box_json = [](const Box& b) { return nlohmann::json{b.xmin, b.ymin, b.xmax, b.ymax}; };
  nlohmann::json room = {{"walls", {{"bottom", model.room.walls[0]},
                                    {"right", model.room.walls[1]},
                                    {"top", model.room.walls[2]},
                                    {"left", model.room.walls[3]}}},
                         {"box", model.room.box ? box_json(*model.room.box) : nlohmann::json()}};
  nlohmann::json objects = nlohmann::json::array();
  for (const auto& o : model.objects) {
    nlohmann::json j = {{"id", o.id},
                        {"kind", ToString(o.kind)},
                        {"lines", o.lines},
                        {"complete", o.complete},
                        {"box", box_json(o.box)},
                        {"open_ends", o.open_ends}};
    if (!o.note.empty()) j["note"] = o.note;
    objects.push_back(j);
  }
  nlohmann::json lines = nlohmann::json::array();
  for (const auto& l : slam_.map_lines()) {
    lines.push_back({{"id", l.id},
                     {"rho", l.rho},
                     {"theta", l.theta},
                     {"cov", MatrixJson(l.cov)},
                     {"p0", {l.p0.x(), l.p0.y()}},
                     {"p1", {l.p1.x(), l.p1.y()}},
                     {"length", l.length()},
                     {"observations", l.observations}});
  }
  nlohmann::json traj = nlohmann::json::array();
  for (const auto& p : slam_.map_trajectory()) traj.push_back({p.t, p.pose.x, p.pose.y, p.pose.theta});
  return {
      {"frame", "map"},
      {"state", ToString(mission_.state())},
      {"pose", PoseJson(slam_.map_pose())},
      {"pose_cov", MatrixJson(slam_.map_pose_cov())},
      {"lines", lines},
      {"room", room},
      {"objects", objects},
      {"trajectory", traj},
  };
}

}  // namespace irslam::robot
