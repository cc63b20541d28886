#include "robot/robot_core.h"

#include <cmath>

namespace irslam::robot {

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
      ir_(options_.ir),
      slam_(options_.slam),
      mission_(options_.mission, options_.wall, options_.explore, options_.model, options_.slam),
      estop_(options_.safety.debounce_s),
      bump_left_(options_.safety.debounce_s),
      bump_right_(options_.safety.debounce_s) {}

void RobotCore::OnFrame(const can_frame& frame, double now_s) {
  const drivers::MotorClient::Event ev = motor_.Handle(frame, now_s);
  // Frames older than what SLAM has seen (reordered) are not fed back in time.
  if (ev.ticks && ev.ticks->t >= slam_.time()) slam_.AddWheelTicks(*ev.ticks);
  if (ev.ir_adc) slam_.AddRangeScan(ir_.Add(ev.ir_t, *ev.ir_adc));
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
    case MissionState::kContourFollow:
    case MissionState::kClean:
    case MissionState::kReturnHome:
    case MissionState::kRelocalize: return true;
    default: return false;
  }
}

bool RobotCore::StatusLed(double now_s) const {
  return control::LedOn(estop_latched_ ? MissionState::kFault : mission_.state(), now_s);
}

void RobotCore::UpdateFault(double now_s) {
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
}

std::vector<can_frame> RobotCore::Tick(double now_s) {
  // A slow host, not a dead controller: when the loop itself was stalled (more
  // than kStallPeriods periods since the last tick), the frames that came
  // meanwhile are still queued behind this tick, unread; judging the controller
  // now would blame it for the loop's delay. Its loss is judged at the next
  // tick, once the queue has been drained (a silent controller is then found
  // one period later). A silence while the loop keeps its period is judged as ever,
  // and so is one after a tick that was already given this grace (the queue was
  // read in between): a loop that stays slow cannot hide a dead controller.
  const bool stalled = last_tick_s_ >= 0 && now_s - last_tick_s_ > kStallPeriods * options_.period_s;
  last_tick_s_ = now_s;
  if (stalled && !graced_last_tick_) {
    ++loop_stalls_;
    graced_last_tick_ = true;
  } else {
    graced_last_tick_ = false;
    UpdateFault(now_s);
  }
  const uint8_t gpio_bumpers = static_cast<uint8_t>((bump_left_.Poll(now_s) ? kBumperLeft : 0) |
                                                    (bump_right_.Poll(now_s) ? kBumperRight : 0));
  last_cmd_ = mission_.Step(now_s, slam_, ir_.scan(), motor_.bumpers() | gpio_bumpers);
  // Issue 14: the mission committed to a pose in the saved map (the SLAM
  // adopts it), or the map disagreed (a fresh local SLAM for a new search).
  AdoptIfAsked(now_s);
  if (mission_.TakeSlamReset()) slam_.ForgetMap();
  if (const std::vector<int> gone = mission_.TakeLineRemovals(); !gone.empty()) {
    slam_.RemoveLines(gone);
    mission_.LinesRemoved(slam_);
  }
  std::vector<can_frame> out{motor_.MakeCommand(last_cmd_)};
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
    if (mission_.state() != MissionState::kIdle && mission_.state() != MissionState::kDone) {
      last_start_ = StartKind::kResumed;
      return true;
    }
  }
  if (mission_.state() != MissionState::kIdle && mission_.state() != MissionState::kDone)
    return mission_.Start(now_s, why);  // (refused: already running)
  const bool live = !forget_live_ && slam_.num_lines() > 0 && mission_.model().room.box.has_value();
  if (live) return Started(mission_.StartKnown(now_s, slam_, why), StartKind::kLiveMap);
  const bool in_map = saved_map_ && saved_map_->room.box.has_value() && !saved_map_->lines.empty();
  if (!in_map) {
    Renew(std::nullopt);
    forget_live_ = false;
    return Started(mission_.Start(now_s, why), StartKind::kNewMap);
  }
  Renew(saved_map_->calibration);
  forget_live_ = false;
  control::SavedMission saved;
  saved.map = {saved_map_->lines, saved_map_->trajectory};
  saved.model.room = saved_map_->room;
  saved.model.objects = saved_map_->objects;
  saved.cleaning = saved_map_->cleaning;
  return Started(mission_.StartInMap(now_s, std::move(saved), why), StartKind::kSavedMap);
}

bool RobotCore::Started(bool accepted, StartKind kind) {
  if (accepted) last_start_ = kind;
  return accepted;
}

void RobotCore::AdoptIfAsked(double now_s) {
  if (std::optional<control::Adoption> a = mission_.TakeAdoption()) {
    if (a->restore) slam_.ForgetMap();
    slam_.AdoptMap(a->local_to_map, a->lines);
    mission_.Adopted(now_s, slam_);
  }
}

void RobotCore::Renew(const std::optional<slam::CalibrationEstimate>& calibration) {
  // Nothing mapped since boot and no calibration to start from: the SLAM and
  // the mission are as new (kept as they are: the first mission of a process
  // starts exactly as it always did).
  if (slam_.num_lines() == 0 && !calibration) return;
  slam::SlamOptions o = options_.slam;
  if (calibration) o.initial_calibration = calibration;
  else o.initial_calibration = slam_.calibration();
  slam_ = slam::Slam(o);
  const bool clean = mission_.clean_mode();
  mission_ = Mission(options_.mission, options_.wall, options_.explore, options_.model, options_.slam);
  mission_.SetCleanMode(clean);
  if (work_clock_) mission_.SetWorkClock(work_clock_);
}

void RobotCore::Stop(double now_s) {
  mission_.Stop(now_s);
  AdoptIfAsked(now_s);
  last_cmd_ = {};
}

can_frame RobotCore::StopFrame() { return motor_.MakeCommand(WheelCommand{}); }

CoreStatus RobotCore::Status(double now_s) const {
  CoreStatus s;
  s.robot_time = now_s;
  s.mission = {mission_.state(), mission_.reason(), mission_.wall_follower().mode(), mission_.target_object()};
  const Eigen::Matrix3d cov = slam_.map_pose_cov();
  s.slam = {slam_.map_pose(),
            {std::sqrt(cov(0, 0)), std::sqrt(cov(1, 1)), std::sqrt(cov(2, 2))},
            slam_.distance_m(),
            slam_.num_lines(),
            slam_.stats(),
            slam_.calibration(),
            options_.slam.calibration.enabled};
  s.model = {mission_.model().objects.size(), mission_.model().pending()};
  s.ir = {ir_.scan(), ir_.last_adc()};
  s.command = last_cmd_;
  s.safety = {estop_.active(), estop_latched_, bump_left_.active(), bump_right_.active(), MotorEnable()};
  s.controller = {motor_.ControllerAlive(now_s), motor_.last_status()};
  s.frames = {motor_.counters(), ir_.counters()};
  if (mission_.clean().active()) s.cleaning = mission_.cleaning(now_s, slam_.distance_m());
  s.relocalize = mission_.relocalize();
  return s;
}

MapSnapshot RobotCore::Map() const {
  const control::EnvironmentModel& model = mission_.model();
  MapSnapshot m{mission_.state(),    slam_.map_pose(), slam_.map_pose_cov(),     slam_.map_lines(),
                model.room,          model.objects,    slam_.map_trajectory(), std::nullopt,
                options_.slam.calibration.enabled ? std::optional(slam_.calibration()) : std::nullopt,
                std::nullopt};
  if (mission_.clean().active()) m.cleaning = mission_.cleaning(slam_.time(), slam_.distance_m());
  if (const auto r = mission_.relocalize(); r && r->committed && slam_.in_saved_map())
    m.relocalized = MapSnapshot::Relocalized{r->committed_t, r->hypotheses};
  return m;
}

}  // namespace irslam::robot
