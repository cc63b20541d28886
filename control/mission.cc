// Why this file is long (~650 lines): it holds every row of the transition
// table in mission.h and nothing else - each behaviour (wall following, go-to,
// contour, survey, cleaning, relocalisation, map agreement, moved furniture) is
// its own class in its own file; splitting the rows apart would split the table.
#include "control/mission.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace irslam::control {

const char* ToString(MissionState s) {
  switch (s) {
    case MissionState::kIdle:
      return "idle";
    case MissionState::kWallFollow:
      return "wall_follow";
    case MissionState::kModel:
      return "model";
    case MissionState::kGoToP1:
      return "go_to_p1";
    case MissionState::kContourFollow:
      return "contour_follow";
    case MissionState::kDone:
      return "done";
    case MissionState::kFault:
      return "fault";
    case MissionState::kClean:
      return "clean";
    case MissionState::kReturnHome:
      return "return_home";
    case MissionState::kRelocalize:
      return "relocalize";
  }
  return "?";
}

options::Table<MissionOptions> MissionKeys() {
  using O = MissionOptions;
  static constexpr options::Key<O> kKeys[] = {
      {"max_time_s", &O::max_time_s, 1, 1e6, "s", "the whole mission ends after this (robot time)"},
      {"progress_timeout_s", &O::progress_timeout_s, 1, 1e6, "s",
       "no new distance covered for this long: give up"},
      {"max_accel_mps2", &O::max_accel_mps2, 0.01, 20, "m/s^2",
       "wheel acceleration limit of the command"},
      {"wall_follow_loops", &O::wall_follow_loops, 1, 100, "",
       "loops of the room before modelling it"},
      {"explore", &O::explore, 0, 0, "",
       "complete the objects after modelling (false: map the room only)"},
      {"progress_step_m", &O::progress_step_m, 0.001, 10, "m", "distance that counts as progress"},
      {"max_step_s", &O::max_step_s, 0.001, 10, "s",
       "longest control step the acceleration limit allows for"},
      {"mode", &O::mode, 0, 0, "",
       "explore: map the room; clean: map it, clean the floor, return to the start"},
      {"clean_at_time_limit", &O::clean_at_time_limit, 0, 0, "",
       "mode clean: at max_time_s with the room modelled, clean it as modelled (false: end)"},
      {"repeat_free_loop_m", &O::repeat_free_loop_m, 0, 10, "m",
       "a free-object loop closing this near an earlier one, the room's four walls mapped: model the "
       "room (0: always leave the object)"},
  };
  return kKeys;
}

Mission::Mission(MissionOptions options, WallFollowerOptions wall, ExploreOptions explore,
                 ModelOptions model, const slam::SlamOptions& slam)
    : options_(options),
      geometry_(slam.geometry),
      follow_distance_m_(wall.follow_distance_m),
      follower_(wall, slam.mounts, slam.geometry.radius_m),
      modeler_(model),
      bumps_(options.bump, slam.mounts, slam.geometry.radius_m),
      free_(options.pen, slam.mounts),
      radius_m_(slam.geometry.radius_m),
      loop_(options.loop),
      go_to_(explore.go_to, slam.geometry, slam.mounts),
      contour_(explore.contour, wall.follow_distance_m),
      survey_(explore.survey),
      clean_(options.cleaning, explore.go_to, slam.geometry, slam.mounts),
      home_go_to_(
          [&] {
            GoToOptions g = CleaningGoTo(explore.go_to, options.cleaning);
            g.goal_tolerance_m = options.cleaning.home_tolerance_m;
            return g;
          }(),
          slam.geometry, slam.mounts),
      clean_mode_(options.mode == "clean"),
      model_options_(model),
      reloc_(options.relocalize),
      agreement_(options.relocalize, slam.mounts),
      changes_(options.relocalize.changes) {}

void Mission::Enter(MissionState s, double t, std::string reason) {
  state_ = s;
  reason_ = std::move(reason);
  // The way out of a pen is that go_to_p1's alone: any other state (a time
  // limit, a stop) ends it, and a later go-to is an object's or a survey's.
  if (s != MissionState::kGoToP1) leaving_pen_ = false;
  // Relocalising follows walls too: from a fresh follower, also when the map
  // stopped agreeing in the middle of cleaning (the follower was last used
  // long before, elsewhere; it held the robot still).
  if (s == MissionState::kWallFollow || s == MissionState::kRelocalize) {
    follower_.Reset();
    follower_.SetOrbitCorners(false);
    loop_.Reset();
    progress_t_ = t;
  }
}

namespace {
bool CanStart(MissionState state, const std::string& reason, std::string* why) {
  if (state == MissionState::kFault) {
    *why = "cannot start while in fault: " + reason;
    return false;
  }
  if (state != MissionState::kIdle && state != MissionState::kDone) {
    *why = std::string("already running (") + ToString(state) + ")";
    return false;
  }
  return true;
}

std::vector<int> LineIds(const std::vector<slam::LineFeature>& lines) {
  std::vector<int> ids;
  ids.reserve(lines.size());
  for (const auto& l : lines) ids.push_back(l.id);
  return ids;
}
}  // namespace

void Mission::Reset(double t) {
  started_at_ = t;
  last_t_ = t;
  survey_.Reset();
  loops_done_ = 0;
  loop_times_.clear();
  home_set_ = false;
  clean_.Reset();
  checking_ = false;
  adoption_.reset();
  slam_reset_ = false;
  reloc_ran_ = false;
  reloc_.End();
  changes_.Clear();
  line_removals_.clear();
  checked_model_ = {};
  checked_lines_.clear();
  resume_cleaning_.reset();
  remodel_after_clean_ = false;
  explore_timed_out_ = false;
  free_.Reset();
  leaving_pen_ = false;
  pens_left_ = 0;
  free_loops_.clear();
}

void Mission::WatchChanges(const slam::Slam& slam, const std::vector<TimedPose>& trajectory) {
  changes_.Reset(slam.map_lines(), trajectory, modeler_.model(), model_options_.axis_tolerance_rad);
}

void Mission::StepChanges(const slam::Slam& slam) {
  // (In a saved map the SLAM's frame is the map's: its lines need no copy.)
  const std::vector<int> moved = slam.in_saved_map() ? changes_.Step(slam.map_pose(), slam.lines())
                                                     : changes_.Step(slam.map_pose(), slam.map_lines());
  for (int id : moved) {
    const auto& objects = modeler_.model().objects;
    const auto o = std::find_if(objects.begin(), objects.end(), [&](const auto& x) { return x.id == id; });
    if (o == objects.end()) continue;
    // As the saved map had it (its size is what the piece is found again by),
    // with every side the model has for it now (one stretched over the new
    // place included).
    ObjectModel was = *o;
    const auto& checked = checked_model_.objects;
    const auto c = std::find_if(checked.begin(), checked.end(), [&](const auto& x) { return x.id == id; });
    if (c != checked.end()) {
      was.box = c->box;
      for (int line : c->lines) {
        if (std::find(was.lines.begin(), was.lines.end(), line) == was.lines.end()) was.lines.push_back(line);
      }
    }
    ObjectMoved(was);
  }
}

void Mission::ObjectMoved(const ObjectModel& o) {
  changes_.Reported(o.id);
  // All its sides leave the map, also one the SLAM matched again: moved along
  // one of its sides, that side's new place is collinear with the old and
  // the SLAM extends the old line over both (the piece then modelled too long).
  line_removals_.insert(line_removals_.end(), o.lines.begin(), o.lines.end());
  auto& checked = checked_model_.objects;
  checked.erase(std::remove_if(checked.begin(), checked.end(), [&](const auto& x) { return x.id == o.id; }),
                checked.end());
  agreement_.Forget(o.id);
  modeler_.NoteMoved(o.id, o.box);
  reason_ += "; object " + std::to_string(o.id) + " is not where it was";
}

void Mission::LinesRemoved(const slam::Slam& slam) { modeler_.Update(slam.map_lines(), slam.map_trajectory()); }

bool Mission::Start(double t, std::string* why) {
  if (!CanStart(state_, reason_, why)) return false;
  Reset(t);
  Enter(MissionState::kWallFollow, t, "");
  return true;
}

bool Mission::StartInMap(double t, SavedMission saved, std::string* why) {
  if (!CanStart(state_, reason_, why)) return false;
  Reset(t);
  resume_cleaning_ = std::move(saved.cleaning);
  modeler_.Seed(saved.model, saved.map.trajectory);
  checked_model_ = saved.model;
  checked_lines_ = LineIds(saved.map.lines);
  survey_.Exhaust();  // the saved mission surveyed the room already
  reloc_.Begin(t, std::move(saved.map));
  reloc_ran_ = true;
  reloc_progress_ = {};
  reloc_progress_.started_t = t;
  reloc_progress_.attempts = 1;
  after_reloc_ = MissionState::kModel;
  reloc_bumps_from_ = bumps_.points().size();
  Enter(MissionState::kRelocalize, t, "relocalising in the saved map");
  return true;
}

bool Mission::StartKnown(double t, const slam::Slam& slam, std::string* why) {
  if (!CanStart(state_, reason_, why)) return false;
  std::optional<CleaningProgress> before;
  if (clean_.active()) before = clean_.progress();
  Reset(t);
  resume_cleaning_ = std::move(before);
  checked_model_ = modeler_.model();
  checked_lines_ = LineIds(slam.map_lines());
  agreement_.Reset(slam, checked_model_, checked_lines_);
  checking_ = true;
  WatchChanges(slam, slam.map_trajectory());
  survey_.Exhaust();  // the room was surveyed when it was modelled
  Enter(MissionState::kModel, t,
        "continuing in the map (" + std::to_string(slam.num_lines()) + " lines)");
  return true;
}

std::optional<Adoption> Mission::TakeAdoption() {
  std::optional<Adoption> a = std::move(adoption_);
  adoption_.reset();
  return a;
}

bool Mission::TakeSlamReset() { return std::exchange(slam_reset_, false); }

std::optional<RelocalizeProgress> Mission::relocalize() const {
  if (!reloc_ran_) return std::nullopt;
  RelocalizeProgress p = reloc_progress_;
  if (reloc_.active()) {
    p.committed = false;
    p.hypotheses = reloc_.hypotheses();
    p.best_score = reloc_.best_score();
    p.evidence_m = reloc_.evidence_m();
  }
  return p;
}

WheelCommand Mission::StepRelocalize(double t, double dt, const slam::Slam& slam,
                                     const RangeScan& raw_scan, bool bumped) {
  // Follow walls (leaving a free object circled, as in wall following) while
  // the local SLAM maps; the search runs on each closed window. The contacts
  // remembered before are in the map's frame, not the local SLAM's: only those
  // of this relocalisation are seen (else the robot, at the local origin, saw
  // contacts from elsewhere in the room all round it and turned on the spot).
  const Twist tw = follower_.Step(t, bumps_.Apply(raw_scan, slam.pose(), reloc_bumps_from_), bumped, &raw_scan);
  if (loop_.Update(t, follower_.steady(), slam.pose(), slam.distance_m(), follower_.searching()) == LoopEvent::kFreeObject)
    follower_.Leave(t);
  if (const std::optional<slam::PoseHypothesis> d = reloc_.Step(t, slam)) {
    reloc_progress_.committed = true;
    reloc_progress_.committed_t = t;
    reloc_progress_.hypotheses = reloc_.hypotheses();
    reloc_progress_.best_score = d->score;
    reloc_progress_.evidence_m = reloc_.evidence_m();
    adoption_ = Adoption{d->local_to_map, reloc_.map().lines};
    local_to_map_ = d->local_to_map;
    return Halt();
  }
  if (reloc_.TimedOut(t) && reloc_progress_.attempts > 1) {
    // Relocalising again (the map disagreed): the saved map is not given up
    // for a local one. Search again; after max_attempts, stop with the map as
    // it was before it disagreed (it is what gets saved).
    if (reloc_progress_.attempts < options_.relocalize.max_attempts) {
      ++reloc_progress_.attempts;
      reloc_.Begin(t, reloc_.map());
      slam_reset_ = true;
      reason_ = "still relocalising (attempt " + std::to_string(reloc_progress_.attempts) + ")";
      return ToWheels(tw, dt);
    }
    adoption_ = Adoption{Pose2{}, reloc_.map().lines, true};
    give_up_after_adoption_ = true;
    return Halt();
  }
  if (reloc_.TimedOut(t)) {
    // The saved map is given up: what the local SLAM made so far is a fresh
    // exploration's start (its own frame), and it goes on as one.
    reloc_.End();
    reloc_progress_.committed = false;
    modeler_ = Modeler(model_options_);
    checking_ = false;
    const int s = static_cast<int>(options_.relocalize.search.max_time_s);
    state_ = MissionState::kWallFollow;  // (not Enter: the follower keeps its wall)
    reason_ = "could not relocalise in the saved map in " + std::to_string(s) + " s: exploring afresh";
    home_in_local_ = false;
    loop_.Reset();
    return ToWheels(tw, dt);
  }
  return ToWheels(tw, dt);
}

void Mission::Adopted(double t, const slam::Slam& slam) {
  // The frame changed under the mission: what it kept in the local frame moves.
  if (home_set_ && home_in_local_) home_ = Compose(local_to_map_, home_);
  home_in_local_ = false;
  bumps_.TransformSince(reloc_bumps_from_, local_to_map_);
  if (reloc_progress_.attempts == 1) WatchChanges(slam, reloc_.map().trajectory);
  reloc_.End();
  agreement_.Reset(slam, checked_model_, checked_lines_);
  checking_ = true;
  if (give_up_after_adoption_) {
    give_up_after_adoption_ = false;
    checking_ = false;
    reloc_.End();
    if (clean_.active() && state_ != MissionState::kIdle) clean_.SetState(CleanState::kStopped, t, slam.distance_m());
    if (state_ != MissionState::kIdle)
      Enter(MissionState::kIdle, t, "lost: could not relocalise in the map again (it is kept as it was)");
    return;
  }
  const std::string how = "relocalised in the saved map (" +
                          std::to_string(reloc_progress_.hypotheses) + " hypotheses, score " +
                          std::to_string(static_cast<int>(std::lround(100 * reloc_progress_.best_score))) +
                          " %)";
  if (after_reloc_ == MissionState::kClean) {
    clean_.Interrupted(t);
    Enter(MissionState::kClean, t, how + ": cleaning on");
  } else if (after_reloc_ == MissionState::kReturnHome) {
    home_planned_ = false;
    home_retry_t_ = t;
    Enter(MissionState::kReturnHome, t, how + ": returning home");
  } else {
    Enter(MissionState::kModel, t, how);
  }
}

bool Mission::CheckAgreement(double t, const slam::Slam& slam, const RangeScan& scan) {
  if (!checking_) return true;
  if (agreement_.Step(slam, scan)) {
    // Its old sides' rays found nothing while the rest of the map agreed.
    for (const ObjectModel& o : agreement_.TakeMoved()) ObjectMoved(o);
    // Lines mapped from a wrong pose (a kidnap) that the map fell back to.
    for (int id : agreement_.TakeContradicted()) {
      line_removals_.push_back(id);
      reason_ += "; line " + std::to_string(id) + " is not there: removed";
    }
    return true;
  }
  const auto pct = [](double v) { return std::to_string(static_cast<int>(std::lround(100 * v))); };
  const std::string why = "the map disagrees (" + pct(agreement_.agreement()) + " % of recent lines matched, " +
                          pct(agreement_.scan_agreement()) + " % of IR rays)";
  if (reloc_progress_.attempts >= options_.relocalize.max_attempts) {
    checking_ = false;
    if (state_ == MissionState::kClean || state_ == MissionState::kReturnHome)
      clean_.SetState(CleanState::kStopped, t, slam.distance_m());
    Enter(MissionState::kIdle, t, why + ": giving up");
    return false;
  }
  // Relocalise again in the map as it was before it stopped agreeing, with a
  // fresh local SLAM (the core restarts it after this period).
  after_reloc_ = (state_ == MissionState::kClean || state_ == MissionState::kReturnHome)
                     ? state_
                     : MissionState::kModel;
  checking_ = false;
  slam_reset_ = true;
  reloc_.Begin(t, agreement_.checkpoint());
  reloc_ran_ = true;
  reloc_progress_.committed = false;
  reloc_progress_.started_t = t;
  ++reloc_progress_.attempts;
  reloc_bumps_from_ = bumps_.points().size();
  Enter(MissionState::kRelocalize, t, why + ": relocalising");
  return false;
}

void Mission::Stop(double t) {
  if (state_ == MissionState::kFault) resume_state_ = MissionState::kIdle;
  if (state_ == MissionState::kClean || state_ == MissionState::kReturnHome)
    clean_.SetState(CleanState::kStopped, t, last_distance_);
  RestoreMapOnEnd();
  if (state_ != MissionState::kFault) Enter(MissionState::kIdle, t, "stopped by request");
  last_cmd_ = {};
}

void Mission::SetFault(double /*t*/, const std::string& reason) {
  if (state_ != MissionState::kFault) {
    resume_state_ = state_;
    state_ = MissionState::kFault;
  }
  reason_ = reason;
  last_cmd_ = {};
}

void Mission::ClearFault(double t) {
  if (state_ != MissionState::kFault) return;
  state_ = resume_state_;
  reason_ = "resumed after: " + reason_;
  progress_t_ = t;
}

WheelCommand Mission::ToWheels(const Twist& tw, double dt) {
  const double half = 0.5 * geometry_.wheel_base_m;
  double l = tw.v - tw.omega * half;
  double r = tw.v + tw.omega * half;
  const double vmax = geometry_.max_wheel_speed_mps;
  const double over = std::max({std::abs(l) / vmax, std::abs(r) / vmax, 1.0});
  l /= over;
  r /= over;
  // Acceleration limit, so the wheels do not slip at every mode switch.
  const double dv = options_.max_accel_mps2 * std::max(dt, 1e-3);
  l = std::clamp(l, last_cmd_.left_mps - dv, last_cmd_.left_mps + dv);
  r = std::clamp(r, last_cmd_.right_mps - dv, last_cmd_.right_mps + dv);
  last_cmd_ = {l, r, true};
  return last_cmd_;
}

void Mission::RestoreMapOnEnd() {
  // Relocalising again, the SLAM holds only a local map: the mission ending
  // now must leave the saved map as it was before it disagreed (that is what
  // gets saved), not the local one.
  if (state_ != MissionState::kRelocalize || reloc_progress_.attempts < 2 || !reloc_.active()) return;
  adoption_ = Adoption{Pose2{}, reloc_.map().lines, true};
  give_up_after_adoption_ = true;
}

bool Mission::CleanAtTimeLimit(double t) {
  const bool exploring = state_ == MissionState::kModel || state_ == MissionState::kGoToP1 ||
                         state_ == MissionState::kContourFollow;
  if (!clean_mode_ || !options_.clean_at_time_limit || explore_timed_out_ || !exploring ||
      !modeler_.model().room.box)
    return false;
  explore_timed_out_ = true;
  for (const ObjectModel& o : modeler_.model().objects) {
    if (!o.complete && !o.given_up) modeler_.GiveUp(o.id, "mission time limit reached");
  }
  survey_.Exhaust();
  // StepModel, in this same period, plans the cleaning (Finish).
  Enter(MissionState::kModel, t, "mission time limit reached: cleaning the room as modelled");
  return true;
}

bool Mission::Watchdogs(double t, const slam::Slam& slam) {
  // (Relocalising again while cleaning, and modelling a moved piece after it,
  // count as cleaning: its own time limit.)
  const bool cleaning = state_ == MissionState::kClean || state_ == MissionState::kReturnHome ||
                        (state_ == MissionState::kRelocalize && after_reloc_ != MissionState::kModel) ||
                        remodel_after_clean_;
  if (cleaning ? t - clean_started_ > options_.cleaning.max_time_s
               : t - started_at_ > options_.max_time_s) {
    if (!cleaning && CleanAtTimeLimit(t)) return true;
    if (cleaning) clean_.SetState(CleanState::kStopped, t, slam.distance_m());
    RestoreMapOnEnd();
    Enter(MissionState::kIdle, t, cleaning ? "cleaning time limit reached" : "mission time limit reached");
    return false;
  }
  if (slam.distance_m() > progress_distance_ + options_.progress_step_m) {
    progress_distance_ = slam.distance_m();
    progress_t_ = t;
  } else if (t - progress_t_ > options_.progress_timeout_s) {
    RestoreMapOnEnd();
    Enter(
        MissionState::kIdle, t,
        "no progress for " + std::to_string(static_cast<int>(options_.progress_timeout_s)) + " s");
    return false;
  }
  return true;
}

WheelCommand Mission::Step(double t, const slam::Slam& slam, const RangeScan& scan,
                           uint8_t bumpers) {
  // Remember what was hit, so followers and planned paths keep away from it.
  bumps_.Record(slam.pose(), bumpers);
  last_distance_ = slam.distance_m();
  if (!home_set_ && state_ != MissionState::kIdle) {
    home_ = slam.pose();
    home_set_ = true;
    home_in_local_ = state_ == MissionState::kRelocalize;
  }
  const double dt = std::clamp(t - last_t_, 0.0, options_.max_step_s);
  last_t_ = t;
  switch (state_) {
    case MissionState::kIdle:
    case MissionState::kDone:
    case MissionState::kFault:
      return Halt();
    default:
      break;
  }
  if (!Watchdogs(t, slam)) return Halt();
  if (!CheckAgreement(t, slam, scan)) return Halt();
  if (checking_ && state_ != MissionState::kRelocalize) StepChanges(slam);
  switch (state_) {
    case MissionState::kRelocalize:
      return StepRelocalize(t, dt, slam, scan, bumpers != 0);
    case MissionState::kWallFollow:
      return StepWallFollow(t, dt, slam, scan, bumpers != 0);
    case MissionState::kModel:
      return StepModel(t, slam);
    case MissionState::kGoToP1:
      return StepGoTo(t, dt, slam, scan, bumpers);
    case MissionState::kContourFollow:
      return StepContour(t, dt, slam, scan, bumpers != 0);
    case MissionState::kClean:
      return StepClean(t, dt, slam, scan, bumpers);
    case MissionState::kReturnHome:
      return StepReturnHome(t, dt, slam, scan, bumpers);
    default:
      return Halt();
  }
}

WheelCommand Mission::StepWallFollow(double t, double dt, const slam::Slam& slam,
                                     const RangeScan& raw_scan, bool bumped) {
  const Twist tw = follower_.Step(t, bumps_.Apply(raw_scan, slam.pose()), bumped, &raw_scan);
  if (options_.pen.pen_check && !reloc_ran_) free_.Record(slam.pose(), raw_scan);
  switch (loop_.Update(t, follower_.steady(), slam.pose(), slam.distance_m(), follower_.searching())) {
    case LoopEvent::kNone:
      break;
    case LoopEvent::kFreeObject:
      // Walked clockwise round the outside of something: a free object, not
      // the room. Leave it and find a wall - unless leaving brought the robot
      // back to it along the room's walls: then the room is mapped already.
      if (RepeatedFreeLoop(slam)) {
        loop_times_.push_back(t);
        ++loops_done_;
        if (LeavePen(t, slam)) return Halt();
        return To(MissionState::kModel, t, "circled the same free object again, the room's walls mapped");
      }
      follower_.Leave(t);
      reason_ = "circled a free object; looking for a wall";
      break;
    case LoopEvent::kRoom:
      loop_times_.push_back(t);
      if (++loops_done_ < options_.wall_follow_loops) {
        // Another loop of the room was asked for: keep following from here.
        loop_.Rearm(slam.pose(), slam.distance_m());
        break;
      }
      // The room has been walked all round: model it (unless it was a pen).
      if (LeavePen(t, slam)) return Halt();
      return To(MissionState::kModel, t, "wall-following loop closed");
  }
  return ToWheels(tw, dt);
}

bool Mission::RepeatedFreeLoop(const slam::Slam& slam) {
  const double r = options_.repeat_free_loop_m;
  if (r <= 0) return false;
  const Pose2 p = slam.pose();
  const Eigen::Vector2d at(p.x, p.y);
  const bool again =
      std::any_of(free_loops_.begin(), free_loops_.end(), [&](const Eigen::Vector2d& q) { return (q - at).norm() < r; });
  if (free_loops_.size() < kMaxFreeLoops) free_loops_.push_back(at);
  if (!again) return false;
  const EnvironmentModel& m = modeler_.Update(slam.map_lines(), slam.map_trajectory());
  return m.room.box && std::all_of(m.room.walls.begin(), m.room.walls.end(),
                                   [](const auto& ids) { return !ids.empty(); });
}

bool Mission::LeavePen(double t, const slam::Slam& slam) {
  const PenOptions& o = options_.pen;
  if (!o.pen_check || reloc_ran_ || pens_left_ >= o.pen_max_escapes) return false;
  const std::vector<slam::LineFeature> lines = slam.map_lines();  // (a copy, turned: once)
  const EnvironmentModel& m = modeler_.Update(lines, slam.map_trajectory());
  if (!m.room.box) return false;
  const double rot = slam.map_rotation();
  RoomOutline room{*m.room.box, {}};
  for (size_t w = 0; w < 4; ++w) {
    for (const int id : m.room.walls[w]) {
      const auto l = std::find_if(lines.begin(), lines.end(), [&](const auto& x) { return x.id == id; });
      if (l == lines.end()) continue;
      const double a = w % 2 == 0 ? l->p0.x() : l->p0.y(), b = w % 2 == 0 ? l->p1.x() : l->p1.y();
      room.covered[w].emplace_back(std::min(a, b), std::max(a, b));
    }
  }
  const double open = free_.OutsideArea(room, rot, o.pen_margin_m);
  if (open < o.pen_open_area_m2) return false;
  // The seen-free points farthest beyond the box: the first one a path reaches.
  constexpr size_t kCandidates = 8;
  const std::vector<Eigen::Vector2d> out = free_.OutsidePoints(
      room, rot, o.pen_goal_margin_m, radius_m_ + o.pen_goal_clear_m, o.pen_goal_away_m, kCandidates);
  for (const Eigen::Vector2d& p : out) {
    if (!go_to_.TryGoal(t, p, slam.pose().theta, false, slam, bumps_, true)) continue;
    ++pens_left_;
    leaving_pen_ = true;
    pen_box_ = *m.room.box;
    pen_rotation_ = rot;
    pen_was_inside_ = false;
    pen_mouth_.reset();
    target_ = 0;
    const long cm2 = std::lround(open * 100);  // (m2 with two decimals, without <cstdio>)
    const std::string area = std::to_string(cm2 / 100) + "." + (cm2 % 100 < 10 ? "0" : "") +
                             std::to_string(cm2 % 100);
    Enter(MissionState::kGoToP1, t,
          "the loop went round a pen (" + area + " m2 of floor seen outside it): leaving it");
    go_to_.Begin(t);
    return true;
  }
  return false;
}

void Mission::TracePenExit(const Pose2& map_pose) {
  if (pen_mouth_) return;
  const Box& b = pen_box_;
  const Eigen::Vector2d p(map_pose.x, map_pose.y);
  if (p.x() >= b.xmin && p.x() <= b.xmax && p.y() >= b.ymin && p.y() <= b.ymax) {
    pen_was_inside_ = true;
    return;
  }
  if (pen_was_inside_) pen_mouth_ = p;
}

void Mission::ClosePenMouth() {
  if (!pen_mouth_) return;
  // The side of the box the way out crossed: the one its first point outside
  // lies beyond.
  const Box& b = pen_box_;
  const Eigen::Vector2d& o = *pen_mouth_;
  Eigen::Vector2d c = o;
  Eigen::Vector2d along(1, 0);
  if (o.x() < b.xmin || o.x() > b.xmax) {
    c.x() = o.x() < b.xmin ? b.xmin : b.xmax;
    along = {0, 1};
  } else {
    c.y() = o.y() < b.ymin ? b.ymin : b.ymax;
  }
  constexpr double kStepM = 0.05, kHalfWidthM = 0.8, kHitM = 0.1;
  for (const double sign : {1.0, -1.0}) {
    for (double d = sign > 0 ? 0 : kStepM; d <= kHalfWidthM; d += kStepM) {
      const Eigen::Vector2d q = RotateVector(c + sign * d * along, -pen_rotation_);
      if (free_.HitNear(q, kHitM)) break;
      bumps_.Mark(q);
    }
  }
}

WheelCommand Mission::StepModel(double t, const slam::Slam& slam) {
  // Paper §5: model the room from the line map, then complete what is incomplete.
  const EnvironmentModel& m = modeler_.Update(slam.map_lines(), slam.map_trajectory());
  if (!options_.explore) return Finish(t, slam, m, "room modelled (exploration off)");
  if (explore_timed_out_) return Finish(t, slam, m, "mission time limit reached: cleaning the room as modelled");
  if (m.pending() == 0 && survey_.Wanted(m) && StartSurvey(t, slam, m)) return Halt();
  if (m.pending() == 0) {
    int complete = 0;
    for (const auto& o : m.objects) complete += o.complete;
    return Finish(t, slam, m,
                  "room modelled: " + std::to_string(m.objects.size()) + " objects, " +
                      std::to_string(complete) + " complete");
  }
  return GoToObject(t, slam, m);
}

WheelCommand Mission::GoToObject(double t, const slam::Slam& slam, const EnvironmentModel& m) {
  // Step 2: the nearest incomplete object, and its line nearest the robot. (The
  // paper visits incomplete free objects; a wall-contact object seen only in
  // part from the wall-following loop - compound furniture, a side too far from
  // the loop - is visited too, and its free sides followed.)
  const Pose2 me = slam.map_pose();
  const ObjectModel* target = NearestPending(m, me);
  target_ = target->id;
  contour_.SetTarget(target_, target->kind == ObjectKind::kWallContact);
  const double rot = slam.map_rotation();
  for (const auto& s :
       ContourStarts(*target, slam.map_lines(), slam.map_trajectory(), me, follow_distance_m_)) {
    if (go_to_.TryGoal(t, RotateVector(s.p, -rot), NormalizeAngle(s.heading - rot), true, slam,
                       bumps_)) {
      Enter(MissionState::kGoToP1, t, "going to object " + std::to_string(target_));
      go_to_.Begin(t);
      return Halt();
    }
  }
  // No way to its sides: one facing a wall too near to go between is inferred.
  if (InferNearWall(slam)) {
    reason_ = "object " + std::to_string(target_) +
              " complete (P1 unreachable, the side facing the wall inferred)";
    return Halt();
  }
  modeler_.GiveUp(target_, "P1 unreachable");
  reason_ = "object " + std::to_string(target_) + ": P1 unreachable";
  return Halt();
}

bool Mission::InferNearWall(const slam::Slam& slam) {
  for (const auto& o : modeler_.model().objects) {
    if (o.id == target_) {
      return o.kind == ObjectKind::kFree &&
             modeler_.CloseNearWall(target_, slam.map_lines(), slam.map_trajectory());
    }
  }
  return false;
}

bool Mission::StartSurvey(double t, const slam::Slam& slam, const EnvironmentModel& m) {
  const Box& room = *m.room.box;
  const double rot = slam.map_rotation();
  const auto go = [&](const Eigen::Vector2d& p) {
    if (!go_to_.TryGoal(t, RotateVector(p, -rot), slam.pose().theta, false, slam, bumps_))
      return false;
    survey_.Accept(p);
    target_ = 0;
    Enter(MissionState::kGoToP1, t, "surveying the room (" + std::to_string(survey_.done()) + ")");
    go_to_.Begin(t);
    return true;
  };
  for (const auto& p : survey_.MiddlePoints(room)) {
    if (go(p)) return true;
  }
  for (const auto& p : survey_.RankedPoints(room, slam.map_trajectory(), m.objects)) {
    if (go(p)) return true;
  }
  survey_.Exhaust();
  return false;
}

WheelCommand Mission::AbandonGoTo(double t, const slam::Slam& slam, const std::string& why) {
  if (leaving_pen_) {
    leaving_pen_ = false;
    return To(MissionState::kModel, t, "leaving the pen: " + why);
  }
  if (target_ == 0) return To(MissionState::kModel, t, "survey point: " + why);
  if (InferNearWall(slam)) {
    return To(MissionState::kModel, t,
              "object " + std::to_string(target_) + " complete (P1: " + why +
                  ", the side facing the wall inferred)");
  }
  modeler_.GiveUp(target_, "P1: " + why);
  return To(MissionState::kModel, t, "object " + std::to_string(target_) + ", P1: " + why);
}

WheelCommand Mission::StepGoTo(double t, double dt, const slam::Slam& slam,
                               const RangeScan& raw_scan, uint8_t bumpers) {
  if (leaving_pen_) TracePenExit(slam.map_pose());
  const GoTo::Result r = go_to_.Step(t, slam, raw_scan, bumpers, bumps_, follower_);
  switch (r.status) {
    case GoTo::Status::kDriving:
      return ToWheels(r.twist, dt);
    case GoTo::Status::kGiveUp:
      return AbandonGoTo(t, slam, r.why);
    case GoTo::Status::kArrived:
      break;
  }
  if (leaving_pen_) {
    // Out of the pen: the room's walls are still to be found and followed.
    leaving_pen_ = false;
    loops_done_ = 0;
    ClosePenMouth();
    return To(MissionState::kWallFollow, t, "out of the pen: following walls again");
  }
  if (target_ == 0) {
    // The survey point: one full turn on the spot, then model again.
    Twist tw;
    if (survey_.TurnRound(slam.pose().theta, &tw))
      return To(MissionState::kModel, t, "survey done");
    return ToWheels(tw, dt);
  }
  // P1, heading along the side: follow the object's contour.
  follower_.StartFollowing(t);
  follower_.SetOrbitCorners(true);
  contour_.Start(t, slam.pose().theta, slam.stats().windows);
  Enter(MissionState::kContourFollow, t, "contour following object " + std::to_string(target_));
  return ToWheels({0, 0}, dt);
}

WheelCommand Mission::StepContour(double t, double dt, const slam::Slam& slam,
                                  const RangeScan& raw_scan, bool bumped) {
  const RangeScan scan = bumps_.Apply(raw_scan, slam.pose());
  const ContourFollow::Result r = contour_.Step(t, slam, scan, bumped, &follower_, &modeler_);
  const std::string object = "object " + std::to_string(target_);
  switch (r.status) {
    case ContourFollow::Status::kFollowing:
      return ToWheels(r.twist, dt);
    case ContourFollow::Status::kComplete:
      return To(MissionState::kModel, t, object + " complete");
    case ContourFollow::Status::kClosed:
      return To(MissionState::kModel, t, object + " complete (contour closed)");
    case ContourFollow::Status::kIncomplete:
      modeler_.GiveUp(target_, "contour followed all round, still incomplete");
      return To(MissionState::kModel, t, object + " incomplete after a full contour");
    case ContourFollow::Status::kFreeSidesDone:
      modeler_.GiveUp(target_, "free sides followed, still incomplete");
      return To(MissionState::kModel, t, object + " incomplete after following its free sides");
    case ContourFollow::Status::kTimedOut:
      modeler_.GiveUp(target_, "contour following timed out");
      return To(MissionState::kModel, t, object + ": contour following timed out");
  }
  return Halt();
}

WheelCommand Mission::Finish(double t, const slam::Slam& slam, const EnvironmentModel& m,
                             std::string reason) {
  if (!clean_mode_) return To(MissionState::kDone, t, std::move(reason));
  if (remodel_after_clean_) {
    remodel_after_clean_ = false;
    return ReturnHome(t, clean_summary_ + "; " + reason + "; returning home");
  }
  // Plan the coverage once, bounded by the room's size, a piece per period
  // (StepClean), and clean. A cleaning stopped before (not finished) goes on
  // with the cells it left.
  const bool resume = resume_cleaning_ && resume_cleaning_->state != CleanState::kDone &&
                      resume_cleaning_->state != CleanState::kNone;
  clean_.Begin(t, slam, m, bumps_, resume ? resume_cleaning_ : std::nullopt);
  clean_started_ = t;
  resume_cleaning_.reset();
  // This period's share (a room's whole plan, usually): cleaning starts next period.
  if (clean_.Plan(t)) return To(MissionState::kClean, t, CleaningReason());
  return To(MissionState::kClean, t, "planning the cleaning");
}

std::string Mission::CleaningReason() const {
  std::string what = "cleaning " + std::to_string(clean_.plan().cells.size()) + " cells";
  if (clean_.resumed_cells() > 0) {
    what += " (resumed: " + std::to_string(clean_.resumed_cells()) + " done before" +
            (clean_.replanned_same() ? ", same plan)" : ")");
  }
  if (explore_timed_out_) what += "; the room as modelled at the mission time limit";
  return what;
}

WheelCommand Mission::StepClean(double t, double dt, const slam::Slam& slam,
                                const RangeScan& raw_scan, uint8_t bumpers) {
  if (clean_.planning()) {
    // Holding still until the plan is complete.
    if (clean_.Plan(t)) reason_ = CleaningReason();
    return Halt();
  }
  const Clean::Result r = clean_.Step(t, slam, raw_scan, bumpers, bumps_, follower_);
  if (r.status == Clean::Status::kCleaning) return ToWheels(r.twist, dt);
  clean_.SetState(CleanState::kReturning, t, slam.distance_m());
  const CleaningProgress p = clean_.Progress(t, slam.distance_m());
  const auto one_decimal = [](double v) {
    const long k = std::lround(std::max(0.0, v) * 10);
    return std::to_string(k / 10) + "." + std::to_string(k % 10);
  };
  clean_summary_ = "cleaned " + std::to_string(p.cells_done) + " of " + std::to_string(p.cells_total) +
                   " cells, " + one_decimal(p.covered_m2) + " of " + one_decimal(p.total_m2) + " m2";
  // A piece of the saved map found moved: the model is made whole again (go
  // to P1, contour follow: paper §5) before going home, so that the map saved
  // at the end has the piece where it now stands.
  if (checking_ && modeler_.moved_unplaced() &&
      modeler_.Update(slam.map_lines(), slam.map_trajectory()).pending() > 0) {
    remodel_after_clean_ = true;
    return To(MissionState::kModel, t, clean_summary_ + "; modelling what moved");
  }
  return ReturnHome(t, clean_summary_ + "; returning home");
}

WheelCommand Mission::ReturnHome(double t, std::string reason) {
  home_planned_ = false;
  home_attempts_ = 0;
  home_retry_t_ = t;
  return To(MissionState::kReturnHome, t, std::move(reason));
}

WheelCommand Mission::StepReturnHome(double t, double dt, const slam::Slam& slam,
                                     const RangeScan& raw_scan, uint8_t bumpers) {
  if (!home_planned_) {
    // One plan per period, and after a failure not for a while.
    if (t < home_retry_t_) return Halt();
    home_retry_t_ = t + 2.0;
    if (home_go_to_.TryGoal(t, {home_.x, home_.y}, home_.theta, true, slam, bumps_)) {
      home_go_to_.Begin(t);
      home_planned_ = true;
    } else if (++home_attempts_ >= options_.cleaning.home_attempts) {
      clean_.SetState(CleanState::kDone, t, slam.distance_m());
      return To(MissionState::kDone, t, clean_summary_ + "; home: no way found");
    }
    return Halt();
  }
  const GoTo::Result r = home_go_to_.Step(t, slam, raw_scan, bumpers, bumps_, follower_);
  switch (r.status) {
    case GoTo::Status::kDriving:
      return ToWheels(r.twist, dt);
    case GoTo::Status::kGiveUp:
      home_planned_ = false;
      if (++home_attempts_ >= options_.cleaning.home_attempts) {
        clean_.SetState(CleanState::kDone, t, slam.distance_m());
        return To(MissionState::kDone, t, clean_summary_ + "; home: " + r.why);
      }
      return Halt();
    case GoTo::Status::kArrived:
      break;
  }
  clean_.SetState(CleanState::kDone, t, slam.distance_m());
  if (checking_) modeler_.Update(slam.map_lines(), slam.map_trajectory());  // what cleaning saw
  return To(MissionState::kDone, t, clean_summary_ + ", back home");
}

}  // namespace irslam::control
