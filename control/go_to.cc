#include "control/go_to.h"

#include <algorithm>
#include <limits>
#include <optional>

namespace irslam::control {

options::Table<GoToOptions> GoToKeys() {
  using O = GoToOptions;
  static constexpr options::Key<O> kKeys[] = {
      {"clearance_m", &O::clearance_m, 0, 1, "m",
       "planned paths keep the robot radius plus this from mapped lines"},
      {"goal_tolerance_m", &O::goal_tolerance_m, 0.01, 1, "m", "a go-to goal is reached within this"},
      {"heading_tolerance_rad", &O::heading_tolerance_rad, 0.01, 1, "rad",
       "heading reached at P1 within this"},
      {"cruise_speed_mps", &O::cruise_speed_mps, 0.01, 2, "m/s", "speed along a planned path"},
      {"lookahead_m", &O::lookahead_m, 0.05, 2, "m",
       "pure pursuit aims at the first path point this far"},
      {"k_heading", &O::k_heading, 0.1, 20, "rad/s/rad", "turn rate per radian of heading error"},
      {"replan_period_s", &O::replan_period_s, 0.1, 60, "s",
       "the path is planned again this often"},
      {"replan_backoff_s", &O::replan_backoff_s, 0, 60, "s",
       "blocked ahead and no path found: plan again after this, doubling each time up to replan_period_s "
       "(0: every period)"},
      {"replan_backoff_after", &O::replan_backoff_after, 1, 1000, "",
       "... once this many plans in a row failed (before, every period)"},
      {"plan_pops_per_period", &O::plan_pops_per_period, 0, 100000000, "",
       "A* queue pops per control period at most; a longer search goes on in the next periods (0: no bound)"},
      {"plan_cells_per_pop", &O::plan_cells_per_pop, 0, 100000, "",
       "clearance cells a plan computes that count as one pop against that budget (0: not counted)"},
      {"front_stop_m", &O::front_stop_m, 0.1, 2, "m",
       "something this close ahead: stop and plan around it"},
      {"go_to_timeout_s", &O::go_to_timeout_s, 1, 3600, "s",
       "give a goal up if not reached by then"},
      {"go_to_stuck_s", &O::go_to_stuck_s, 1, 3600, "s",
       "... or after this long without getting further"},
      {"go_to_progress_m", &O::go_to_progress_m, 0.01, 10, "m", "what counts as getting further"},
      {"same_contact_m", &O::same_contact_m, 0, 2, "m",
       "a contact this close to the last is the same one"},
      {"same_contact_escapes", &O::same_contact_escapes, 1, 100, "",
       "escapes from the same contact before it counts as a second one"},
      {"near_obstacle_m", &O::near_obstacle_m, 0, 1, "m",
       "a reading ahead within the robot radius plus this counts as in front"},
      {"near_obstacle_offset_m", &O::near_obstacle_offset_m, 0, 1, "m",
       "... at its distance plus this"},
      {"look_around_factor", &O::look_around_factor, 0, 10, "",
       "blocked with no path: turn at k_heading times this"},
      {"align_max_rate_rad_s", &O::align_max_rate_rad_s, 0.05, 10, "rad/s",
       "turn rate limit turning to P1's heading"},
      {"pursuit_stop_angle_rad", &O::pursuit_stop_angle_rad, 0.05, 3.2, "rad",
       "aim this far off the heading: turn on the spot"},
      {"pursuit_max_rate_rad_s", &O::pursuit_max_rate_rad_s, 0.05, 10, "rad/s",
       "turn rate limit along the path"},
      {"approach_gain", &O::approach_gain, 0.01, 100, "1/s",
       "near the goal the speed is at most gain times distance"},
      {"approach_min_speed_mps", &O::approach_min_speed_mps, 0, 1, "m/s", "... plus this"},
      {"line_extension_m", &O::line_extension_m, 0, 2, "m", "mapped sides are planned around extended by this"},
      {"hard_clearance_m", &O::hard_clearance_m, 0, 1, "m", "never plan closer than the robot radius plus this"},
      {"tight_clearance_m", &O::tight_clearance_m, 0, 1, "m",
       "a tight goal's plans (the way out of a pen) keep the robot radius plus this from the mapped sides"},
      {"keep_path_ratio", &O::keep_path_ratio, 1, 10, "",
       "keep the path being followed while at most this times the new one's length"},
      {"keep_path_slack_m", &O::keep_path_slack_m, 0, 10, "m", "... plus this"},
      {"keep_path_skip_m", &O::keep_path_skip_m, 0, 5, "m",
       "... and clear of obstacles beyond this from the robot"},
      {"escape_side_m", &O::escape_side_m, 0, 1, "m",
       "after a contact, a mapped side within the robot radius plus this is what was hit"},
      {"escape_max_s", &O::escape_max_s, 0.1, 60, "s",
       "an escape from a contact lasts at most this"},
      {"escape_heading_tolerance_rad", &O::escape_heading_tolerance_rad, 0.01, 3.2, "rad",
       "turned away from a contact within this"},
      {"escape_k_heading", &O::escape_k_heading, 0.1, 20, "rad/s/rad",
       "turn rate per radian turning away"},
      {"escape_max_rate_rad_s", &O::escape_max_rate_rad_s, 0.05, 10, "rad/s",
       "turn rate limit turning away"},
      {"escape_drive_s", &O::escape_drive_s, 0, 10, "s",
       "drive off for this long once turned away"},
      {"escape_speed_mps", &O::escape_speed_mps, 0, 1, "m/s", "speed driving off"},
      {"blocked_escape_s", &O::blocked_escape_s, 0, 600, "s",
       "blocked ahead this long with a path found: back off from what is ahead (0: never)"},
      {"boxed_in_contacts_m", &O::boxed_in_contacts_m, 0, 2, "m",
       "no way found with remembered contacts this close: plan again without them (0: never)"},
      {"under_body_contacts_m", &O::under_body_contacts_m, 0, 0.5, "m",
       "plans leave out remembered contacts closer than this, under the body (0: never)"},
  };
  return kKeys;
}

namespace {

// The most trajectory samples a plan along the robot's own path takes (a robot
// turning on the spot adds samples, not length).
constexpr size_t kMaxTrailPoints = 2000;

double Cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return a.x() * b.y() - a.y() * b.x(); }

// How far past end e (outward direction out, a unit vector) the side's line
// meets `other` at a corner: nullopt if it does not within `reach` of e and
// of other, or the two are within 30 deg of parallel.
std::optional<double> CornerAhead(const Eigen::Vector2d& e, const Eigen::Vector2d& out,
                                  const slam::LineFeature& other, double reach) {
  const Eigen::Vector2d d = other.p1 - other.p0;
  const double len = d.norm();
  if (len < 1e-9) return std::nullopt;
  const Eigen::Vector2d u = d / len;
  const double sin_angle = Cross(out, u);
  if (std::abs(sin_angle) < 0.5) return std::nullopt;
  // e + s out = other.p0 + r u
  const Eigen::Vector2d w = other.p0 - e;
  const double s = Cross(w, u) / sin_angle;
  const double r = Cross(w, out) / sin_angle;
  if (s < -reach || s > reach || r < -reach || r > len + reach) return std::nullopt;
  return std::max(0.0, s);
}

}  // namespace

void ExtendedSides(const std::vector<slam::LineFeature>& lines, double extension_m, bool to_corners,
                   std::vector<Obstacle>* sides) {
  for (size_t i = 0; i < lines.size(); ++i) {
    const slam::LineFeature& l = lines[i];
    const Eigen::Vector2d d = (l.p1 - l.p0).normalized();
    double ext0 = extension_m, ext1 = extension_m;
    for (size_t j = 0; to_corners && extension_m > 0 && j < lines.size(); ++j) {
      if (j == i) continue;
      if (auto s = CornerAhead(l.p0, -d, lines[j], extension_m)) ext0 = std::min(ext0, *s);
      if (auto s = CornerAhead(l.p1, d, lines[j], extension_m)) ext1 = std::min(ext1, *s);
    }
    sides->push_back({l.p0 - ext0 * d, l.p1 + ext1 * d});
  }
}

bool GoTo::TryGoal(double t, const Eigen::Vector2d& goal, double heading, bool align,
                   const slam::Slam& slam, const BumpMemory& bumps, bool tight) {
  p1_ = goal;
  tight_ = tight;
  p1_heading_ = heading;
  align_ = align;
  drop_contacts_ = false;
  to_corners_ = false;
  along_trail_ = false;
  PathPlanner::Progress p = Replan(t, slam, RangeScan{}, bumps);
  while (p == PathPlanner::Progress::kFailed && Loosen(slam, bumps)) p = Replan(t, slam, RangeScan{}, bumps);
  // Still searching: no path yet (not the last goal's either): Step waits for it.
  if (p == PathPlanner::Progress::kRunning) path_.clear();
  return p != PathPlanner::Progress::kFailed;
}

void GoTo::Begin(double t) {
  // A contact the last behaviour ended in is this go-to's first.
  since_ = t;
  bumps_ = 0;
  same_contact_escapes_ = 0;
  last_plan_ = t;
  arrived_ = false;
  last_plan_ok_ = true;
  plan_failures_ = 0;
  retry_at_ = -1e9;
  blocked_since_ = -1;
}

int64_t* GoTo::Budget(double t) {
  if (t != budget_t_) {
    budget_t_ = t;
    budget_left_ = options_.plan_pops_per_period > 0 ? options_.plan_pops_per_period
                                                     : std::numeric_limits<int64_t>::max();
  }
  return &budget_left_;
}

PathPlanner::Progress GoTo::ContinuePlan(double t) {
  const int64_t t0 = clock_ ? clock_() : 0;
  int64_t* left = Budget(t);
  int64_t pops = 0;
  const PathPlanner::Progress p = planner_.Continue(*left, &pops);
  *left -= pops;
  if (clock_) planning_ns_ += clock_() - t0;
  return Ended(p);
}

PathPlanner::Progress GoTo::Replan(double t, const slam::Slam& slam, const RangeScan& scan,
                                   const BumpMemory& bumps) {
  const auto& o = options_;
  std::vector<Obstacle>& obstacles = plan_obstacles_;
  obstacles.clear();
  // Mapped sides, extended at their ends (ExtendedSides).
  ExtendedSides(slam.lines(), o.line_extension_m, to_corners_ || tight_, &obstacles);
  const Pose2 me = slam.pose();
  for (const auto& b : bumps.points()) {
    if ((b - Eigen::Vector2d(me.x, me.y)).norm() < o.under_body_contacts_m) continue;
    if (!drop_contacts_ || !WithinDropped(b, drop_at_)) obstacles.push_back({b, b});
  }
  const size_t n_static = obstacles.size();
  // What the IR sensors see now, mapped or not. The contacts are above as
  // points; the bump memory's virtual readings of them (BumpMemory::Apply) would
  // put back those left out (under the body, boxing the robot in): Step passes
  // the raw readings when it may leave any out.
  for (int i = 0; i < kNumIrSensors; ++i) {
    if (!scan.range_m[i]) continue;
    const BeamHit h = HitPoint(mounts_[i], *scan.range_m[i]);
    const Eigen::Vector2d r(h.x, h.y);
    const Eigen::Vector2d w = Eigen::Vector2d(me.x, me.y) + RotateVector(r, me.theta);
    obstacles.push_back({w, w});
  }
  // The robot's own path, back from where it is, boxed_in_trail_m of it.
  trail_.clear();
  if (along_trail_) {
    trail_.push_back({me.x, me.y});
    const auto& traj = slam.trajectory();
    double len = 0;
    for (auto it = traj.rbegin(); it != traj.rend() && len < o.boxed_in_trail_m && trail_.size() < kMaxTrailPoints;
         ++it) {
      const Eigen::Vector2d q(it->pose.x, it->pose.y);
      len += (q - trail_.back()).norm();
      trail_.push_back(q);
    }
  }
  planner_.SetFreeTrail(trail_);
  PlannerOptions po = o.planner;
  po.inflation_m = radius_m_ + (tight_ ? o.tight_clearance_m : o.clearance_m);
  po.hard_m = radius_m_ + o.hard_clearance_m;
  plan_from_ = {me.x, me.y};
  const int64_t t0 = clock_ ? clock_() : 0;
  const PathPlanner::Progress p = planner_.Start(obstacles, plan_from_, p1_, po, n_static);
  if (clock_) planning_ns_ += clock_() - t0;
  if (o.plan_cells_per_pop > 0) *Budget(t) -= planner_.start_cells() / o.plan_cells_per_pop;
  return p == PathPlanner::Progress::kRunning ? ContinuePlan(t) : Ended(p);
}

bool GoTo::Loosen(const slam::Slam& slam, const BumpMemory& bumps) {
  if (DropNearContacts(slam, bumps)) return true;
  if (!to_corners_ && options_.boxed_in_corners) {
    to_corners_ = true;
    return true;
  }
  if (along_trail_ || options_.boxed_in_trail_m <= 0) return false;
  along_trail_ = true;
  return true;
}

bool GoTo::DropNearContacts(const slam::Slam& slam, const BumpMemory& bumps) {
  // Boxed in by contacts close by (a held bumper recorded at every heading while
  // turning on the spot; pose corrections move old contacts under the body): the
  // goal's plans leave them out from now on. Once per goal.
  if (drop_contacts_) return false;
  const Eigen::Vector2d at(slam.pose().x, slam.pose().y);
  const auto& pts = bumps.points();
  if (!std::any_of(pts.begin(), pts.end(), [&](const Eigen::Vector2d& b) { return WithinDropped(b, at); })) {
    return false;
  }
  drop_contacts_ = true;
  drop_at_ = at;
  return true;
}

bool GoTo::WithinDropped(const Eigen::Vector2d& contact, const Eigen::Vector2d& at) const {
  return (contact - at).norm() < options_.boxed_in_contacts_m;
}

PathPlanner::Progress GoTo::Ended(PathPlanner::Progress p) {
  if (p != PathPlanner::Progress::kFound) return p;
  const auto& o = options_;
  const std::vector<Eigen::Vector2d>& path = planner_.path();
  // Keep the path being followed while it is still clear and not much longer
  // than the new one: near a tight spot two ways round are often about as long,
  // and switching between them at every replan left the robot turning on the
  // spot from one to the other.
  if (!path_.empty() && (path_.back() - p1_).norm() < 1e-6) {
    std::vector<Eigen::Vector2d> rest = path_;
    rest.insert(rest.begin(), plan_from_);
    if (PathLength(rest) < o.keep_path_ratio * PathLength(path) + o.keep_path_slack_m &&
        PathClear(plan_obstacles_, rest, radius_m_ + o.hard_clearance_m, o.keep_path_skip_m)) {
      return p;
    }
  }
  path_ = path;
  return p;
}

void GoTo::Planned(double t, bool ok) {
  const auto& o = options_;
  last_plan_ok_ = ok;
  if (ok) {
    plan_failures_ = 0;
    retry_at_ = -1e9;
    return;
  }
  ++plan_failures_;
  const int over = plan_failures_ - std::max(1, o.replan_backoff_after);
  retry_at_ = o.replan_backoff_s <= 0 || over < 0
                  ? -1e9
                  : t + std::min(o.replan_period_s, o.replan_backoff_s * std::ldexp(1.0, std::min(over, 20)));
}

void GoTo::BeginEscape(double t, const slam::Slam& slam, double contact_bearing) {
  // Away from the contact, then turn to face away from it and drive off. (A
  // round robot can always turn on the spot; backing up would run into what is
  // behind.) The contact is the nearest mapped side if one is that close, else
  // its bearing from the bumper bits (left, right, both: ahead).
  const Pose2 me = slam.pose();
  const Eigen::Vector2d pos(me.x, me.y);
  escape_heading_ = NormalizeAngle(me.theta + contact_bearing + M_PI);
  double nearest = radius_m_ + options_.escape_side_m;
  // Only a side on the contact's side of the robot can be what it touched: away
  // from a side behind it (a dead end's wall) was straight into the contact.
  const Eigen::Vector2d toward(std::cos(me.theta + contact_bearing), std::sin(me.theta + contact_bearing));
  for (const auto& l : slam.lines()) {
    const Eigen::Vector2d away = pos - ClosestPoint({l.p0, l.p1}, pos);
    if (away.dot(toward) >= 0) continue;
    if (away.norm() < nearest && away.norm() > 1e-6) {
      nearest = away.norm();
      escape_heading_ = std::atan2(away.y(), away.x());
    }
  }
  escape_turned_ = false;
  backoff_until_ = t + options_.escape_max_s;  // at most; ends after the drive off
  last_plan_ = -1e9;                           // replan around what was hit once clear
}

Twist GoTo::Escape(double t, const Pose2& me) {
  const auto& o = options_;
  if (!escape_turned_) {
    const double err = NormalizeAngle(escape_heading_ - me.theta);
    if (std::abs(err) > o.escape_heading_tolerance_rad) {
      return {0, std::clamp(o.escape_k_heading * err, -o.escape_max_rate_rad_s,
                            o.escape_max_rate_rad_s)};
    }
    escape_turned_ = true;
    backoff_until_ = t + o.escape_drive_s;
  }
  return {o.escape_speed_mps, 0};
}

std::optional<GoTo::Hit> GoTo::NearestAhead(const RangeScan& scan) const {
  // Anything any sensor sees close ahead (not only the front ones: a box corner
  // can sit between the beams of the front sensors), or what the bumper found
  // there before (a chair leg the beams miss).
  std::optional<Hit> nearest;
  for (int i = 0; i < kNumIrSensors; ++i) {
    if (!scan.range_m[i]) continue;
    const auto [hx, hy] = HitPoint(mounts_[i], *scan.range_m[i]);
    // Ahead of the centre: the side sensors' beams (at +-90 degrees) have an x
    // of 1e-17 m from rounding and are not ahead (before 2026-12-03 they were:
    // a contact remembered beside the robot blocked it for good, docs/reliability.md).
    if (hx > kAheadM && std::hypot(hx, hy) < radius_m_ + options_.near_obstacle_m) {
      const double d = std::hypot(hx, hy) + options_.near_obstacle_offset_m;
      if (!nearest || d < nearest->distance) nearest = Hit{d, std::atan2(hy, hx)};
    }
  }
  return nearest;
}

std::optional<double> GoTo::Front(const RangeScan& scan, const WallFollower& follower) const {
  std::optional<double> front = follower.FrontDistance(scan);
  if (const auto hit = NearestAhead(scan); hit && (!front || hit->distance < *front))
    front = hit->distance;
  return front;
}

double GoTo::FrontBearing(const RangeScan& scan, const WallFollower& follower) const {
  const auto hit = NearestAhead(scan);
  const auto ahead = follower.FrontDistance(scan);
  return hit && (!ahead || hit->distance < *ahead) ? hit->bearing : 0.0;
}

Twist GoTo::Pursue(const Pose2& me, std::optional<double> front) {
  // Pure pursuit on the path: aim at the first path point beyond the lookahead.
  const auto& o = options_;
  const Eigen::Vector2d pos(me.x, me.y);
  Eigen::Vector2d aim = path_.empty() ? p1_ : path_.back();
  for (const auto& p : path_) {
    if ((p - pos).norm() > o.lookahead_m) {
      aim = p;
      break;
    }
  }
  // Drop the corners already passed.
  while (path_.size() > 1 && (path_.front() - pos).norm() < o.lookahead_m)
    path_.erase(path_.begin());
  const double err = NormalizeAngle(std::atan2(aim.y() - pos.y(), aim.x() - pos.x()) - me.theta);
  double v = o.cruise_speed_mps * std::max(0.0, std::cos(err));
  if (std::abs(err) > o.pursuit_stop_angle_rad) v = 0;
  v = std::min(v, o.approach_gain * (pos - p1_).norm() + o.approach_min_speed_mps);
  if (front && *front < o.front_stop_m) v = 0;
  return {v, std::clamp(o.k_heading * err, -o.pursuit_max_rate_rad_s, o.pursuit_max_rate_rad_s)};
}

bool GoTo::NoProgress(double t, const Pose2& p) {
  // Stuck (turning on the spot, no way found through what the beams see): after
  // go_to_stuck_s without getting go_to_progress_m further, give the goal up.
  const auto& o = options_;
  if (progress_t_ < since_ ||
      std::hypot(p.x - progress_at_.x(), p.y - progress_at_.y()) > o.go_to_progress_m) {
    progress_t_ = t;
    progress_at_ = {p.x, p.y};
    return false;
  }
  return t - progress_t_ > o.go_to_stuck_s && t >= backoff_until_;
}

bool GoTo::BlockedTooLong(double t, bool blocked) {
  if (!blocked || !last_plan_ok_ || path_.empty()) {
    blocked_since_ = -1;
    return false;
  }
  if (blocked_since_ < 0) blocked_since_ = t;
  if (options_.blocked_escape_s <= 0 || t - blocked_since_ <= options_.blocked_escape_s) return false;
  blocked_since_ = -1;
  return true;
}

bool GoTo::OnContact(double t, const slam::Slam& slam, double bearing) {
  // The same contact again (not got clear of it yet) is not a second one.
  const auto& o = options_;
  const Pose2 p = slam.pose();
  const bool same = bumps_ >= 1 &&
                    std::hypot(p.x - last_contact_.x(), p.y - last_contact_.y()) < o.same_contact_m &&
                    ++same_contact_escapes_ < o.same_contact_escapes;
  if (!same) same_contact_escapes_ = 0;
  last_contact_ = {p.x, p.y};
  if (bumps_ >= 1 && !same) return false;
  if (!same) ++bumps_;
  BeginEscape(t, slam, bearing);
  return true;
}

GoTo::Result GoTo::Step(double t, const slam::Slam& slam, const RangeScan& raw_scan,
                        uint8_t bumpers, const BumpMemory& bumps, const WallFollower& follower) {
  const auto& o = options_;
  if (t - since_ > o.go_to_timeout_s) return GiveUp("not reached in time");
  if (NoProgress(t, slam.pose())) return GiveUp("no way found");
  if (bumpers != 0 && t >= backoff_until_ && !OnContact(t, slam, bumps.ContactBearing(bumpers))) {
    // A second contact on the way: the way there is blocked by things the
    // beams miss (chair legs). Do not push on through them: give the goal up
    // (the next behaviour gets clear of the contact first).
    return GiveUp("the way is blocked by obstacles the sensors miss");
  }
  if (t < backoff_until_) return Drive(Escape(t, slam.pose()));
  const Pose2 me = slam.pose();
  const Eigen::Vector2d pos(me.x, me.y);
  // Something close ahead stops the robot and makes it plan around it.
  // Not the contacts under the body the plans leave out: read 0.09-0.10 m ahead,
  // they held the robot still on the path planned over them (docs/cleaning.md).
  const RangeScan scan = bumps.Apply(raw_scan, me, 0, o.under_body_contacts_m);
  const std::optional<double> front = Front(scan, follower);
  const bool blocked = front && *front < o.front_stop_m;
  // Blocked with a path found: the path leads past what is ahead closer than
  // front_stop_m lets the robot go (the plan keeps only the robot radius plus
  // clearance_m from a reading), and turning towards it did not clear the way.
  // Holding still would end in "no way found" (fig16 cleaning, CI 2026-12-03):
  // back off from it as from a contact, not counted as one, and plan again.
  if (BlockedTooLong(t, blocked)) {
    BeginEscape(t, slam, FrontBearing(scan, follower));
    return Drive(Escape(t, me));
  }
  // Blocked: replan at once, but after a failed plan only when the back-off
  // allows (a failed search floods the whole grid; every period was too much).
  // A search longer than a period's budget goes on in the next periods: the
  // robot holds still meanwhile if blocked or without a path yet (it looks
  // around if blocked after a failed plan, as it would have), else it follows
  // the path it has.
  // A go-to that may leave contacts out of its plans plans round the raw
  // readings: the bump memory's virtual readings would put those contacts back
  // (Replan). One that never does keeps planning round the readings it steers by,
  // as the exploring campaigns were measured with.
  const RangeScan& plan_scan = o.boxed_in_contacts_m > 0 || o.under_body_contacts_m > 0 ? raw_scan : scan;
  std::optional<PathPlanner::Progress> plan;
  if (planner_.running()) {
    plan = ContinuePlan(t);
  } else if ((blocked && t >= retry_at_) || t - last_plan_ > o.replan_period_s) {
    last_plan_ = t;
    plan = Replan(t, slam, plan_scan, bumps);
  }
  if (plan == PathPlanner::Progress::kRunning) {
    if (blocked && !last_plan_ok_) return Drive({0, o.k_heading * o.look_around_factor});  // as before
    return blocked || path_.empty() ? Drive({0, 0}) : Drive(Pursue(me, front));
  }
  if (plan) {
    while (*plan == PathPlanner::Progress::kFailed && Loosen(slam, bumps)) {
      // Boxed in by remembered contacts or extended sides (a search longer
      // than a period fails here, not in TryGoal; a replan on the way fails
      // here too): plan again leaving them out.
      plan = Replan(t, slam, plan_scan, bumps);
      if (*plan == PathPlanner::Progress::kRunning) {
        return blocked || path_.empty() ? Drive({0, 0}) : Drive(Pursue(me, front));
      }
    }
    if (*plan == PathPlanner::Progress::kFailed && path_.empty()) return GiveUp("no way found");
    Planned(t, *plan == PathPlanner::Progress::kFound);
    if (!last_plan_ok_ && blocked) return Drive({0, o.k_heading * o.look_around_factor});  // blocked: look around
  } else if (blocked && !last_plan_ok_) {
    return Drive({0, o.k_heading * o.look_around_factor});  // blocked, backing off: look around
  }
  if (arrived_ || (pos - p1_).norm() < o.goal_tolerance_m) {
    if (!align_) {
      arrived_ = true;
      return {Status::kArrived, {}, {}};
    }
    const double err = NormalizeAngle(p1_heading_ - me.theta);
    if (std::abs(err) < o.heading_tolerance_rad) return {Status::kArrived, {}, {}};
    return Drive(
        {0, std::clamp(o.k_heading * err, -o.align_max_rate_rad_s, o.align_max_rate_rad_s)});
  }
  return Drive(Pursue(me, front));
}

}  // namespace irslam::control
