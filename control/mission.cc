#include "control/mission.h"

#include <algorithm>
#include <cmath>
#include <optional>

namespace irslam::control {

const char* ToString(MissionState s) {
  switch (s) {
    case MissionState::kIdle: return "idle";
    case MissionState::kWallFollow: return "wall_follow";
    case MissionState::kModel: return "model";
    case MissionState::kGoToP1: return "go_to_p1";
    case MissionState::kContourFollow: return "contour_follow";
    case MissionState::kDone: return "done";
    case MissionState::kFault: return "fault";
  }
  return "?";
}

Mission::Mission(MissionOptions options, WallFollowerOptions wall, ExploreOptions explore,
                 ModelOptions model, const slam::SlamOptions& slam)
    : options_(options),
      explore_(explore),
      geometry_(slam.geometry),
      mounts_(slam.mounts),
      follow_distance_m_(wall.follow_distance_m),
      follower_(wall, slam.mounts, slam.geometry.radius_m),
      modeler_(model) {}

void Mission::Enter(MissionState s, double t, std::string reason) {
  state_ = s;
  state_since_ = t;
  reason_ = std::move(reason);
  if (s == MissionState::kGoToP1) {
    // A contact the last behaviour ended in is this go-to's first.
    go_to_bumps_ = 0;
    same_contact_escapes_ = 0;
  }
  if (s == MissionState::kWallFollow) {
    follower_.Reset();
    follower_.SetOrbitCorners(false);
    have_anchor_ = false;
    progress_t_ = t;
  }
}

bool Mission::Start(double t, std::string* why) {
  if (state_ == MissionState::kFault) {
    *why = "cannot start while in fault: " + reason_;
    return false;
  }
  if (state_ != MissionState::kIdle && state_ != MissionState::kDone) {
    *why = std::string("already running (") + ToString(state_) + ")";
    return false;
  }
  started_at_ = t;
  last_t_ = t;
  surveys_done_ = 0;
  survey_points_.clear();
  loops_done_ = 0;
  loop_times_.clear();
  Enter(MissionState::kWallFollow, t, "");
  return true;
}

void Mission::Stop(double t) {
  if (state_ == MissionState::kFault) resume_state_ = MissionState::kIdle;
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

WheelCommand Mission::Step(double t, const slam::Slam& slam, const RangeScan& scan, uint8_t bumpers) {
  const bool bumped = bumpers != 0;
  bumpers_now_ = bumpers;
  if (bumped) {
    // Remember what was hit, so planned paths keep away from it: the contact is
    // at the body's edge, ahead-left, ahead-right or ahead.
    const Pose2 me = slam.pose();
    const bool left = bumpers & 1, right = bumpers & 2;
    const double a = me.theta + (left && !right ? 0.6 : right && !left ? -0.6 : 0.0);
    const double r = geometry_.radius_m + 0.02;
    const Eigen::Vector2d p(me.x + r * std::cos(a), me.y + r * std::sin(a));
    if (bump_points_.empty() || (bump_points_.back() - p).norm() > 0.03) bump_points_.push_back(p);
  }
  const double dt = std::clamp(t - last_t_, 0.0, 0.1);
  last_t_ = t;
  switch (state_) {
    case MissionState::kIdle:
    case MissionState::kDone:
    case MissionState::kFault:
      last_cmd_ = {};
      return {};
    default:
      break;
  }
  if (t - started_at_ > options_.max_time_s) {
    Enter(MissionState::kIdle, t, "mission time limit reached");
    last_cmd_ = {};
    return {};
  }
  if (slam.distance_m() > progress_distance_ + 0.05) {
    progress_distance_ = slam.distance_m();
    progress_t_ = t;
  } else if (t - progress_t_ > options_.progress_timeout_s) {
    Enter(MissionState::kIdle, t, "no progress for " +
                                      std::to_string(static_cast<int>(options_.progress_timeout_s)) +
                                      " s");
    last_cmd_ = {};
    return {};
  }

  switch (state_) {
    case MissionState::kWallFollow: return StepWallFollow(t, dt, slam, scan, bumped);
    case MissionState::kModel: return StepModel(t, slam);
    case MissionState::kGoToP1: return StepGoTo(t, dt, slam, scan, bumped);
    case MissionState::kContourFollow: return StepContour(t, dt, slam, scan, bumped);
    default: return Halt();
  }
}

RangeScan Mission::WithBumpMemory(const RangeScan& scan, const Pose2& me) const {
  // What the bumper found (a chair leg between the beams, a corner of a box the
  // beams miss) is seen from then on by every beam whose path the robot's body
  // would sweep into it: the follower steers round it instead of driving into the
  // same obstacle again.
  RangeScan out = scan;
  const double c = std::cos(me.theta), s = std::sin(me.theta);
  for (const auto& b : bump_points_) {
    if (std::hypot(b.x() - me.x, b.y() - me.y) > 1.0) continue;
    for (int i = 0; i < kNumIrSensors; ++i) {
      const auto& m = mounts_[static_cast<size_t>(i)];
      const Eigen::Vector2d sensor(me.x + c * m.x - s * m.y, me.y + s * m.x + c * m.y);
      const Eigen::Vector2d v = b - sensor;
      const double dir = me.theta + m.theta;
      const double along = v.x() * std::cos(dir) + v.y() * std::sin(dir);
      const double across = -v.x() * std::sin(dir) + v.y() * std::cos(dir);
      if (along <= 0 || std::abs(across) > 0.5 * geometry_.radius_m) continue;
      auto& r = out.range_m[static_cast<size_t>(i)];
      if (!r || along < *r) r = std::max(along, 0.05);
    }
  }
  return out;
}

WheelCommand Mission::StepWallFollow(double t, double dt, const slam::Slam& slam,
                                     const RangeScan& raw_scan, bool bumped) {
    const RangeScan scan = WithBumpMemory(raw_scan, slam.pose());
    const Twist tw = follower_.Step(t, scan, bumped);
    // The loop's anchor: a pose after 1.5 s of steady following, so it lies on
    // the path the robot will come back along.
    if (!follower_.steady()) {
      follow_since_ = -1;
    } else if (follow_since_ < 0) {
      follow_since_ = t;
    }
    if (follow_since_ >= 0 && t - follow_since_ >= 1.5 && !have_anchor_) {
      have_anchor_ = true;
      anchor_ = slam.pose();
      last_pose_ = anchor_;
      turned_since_anchor_ = 0;
      anchor_distance_ = slam.distance_m();
    }
    if (have_anchor_) {
      turned_since_anchor_ += NormalizeAngle(slam.pose().theta - last_pose_.theta);
      last_pose_ = slam.pose();
    }
    if (have_anchor_ && slam.distance_m() - anchor_distance_ > options_.loop_min_distance_m) {
      const Pose2& p = slam.pose();
      const double d = std::hypot(p.x - anchor_.x, p.y - anchor_.y);
      const double a = std::abs(NormalizeAngle(p.theta - anchor_.theta));
      if (d < options_.loop_close_radius_m && a < options_.loop_close_angle_rad) {
        if (turned_since_anchor_ < -M_PI) {
          // With the wall on the right, the room's inside is walked counter-
          // clockwise (+2 pi) and a free object's outside clockwise (-2 pi): this
          // was a free object, not the room. Leave it and find a wall.
          ++objects_left_;
          have_anchor_ = false;
          follower_.Leave(t);
          reason_ = "circled a free object; looking for a wall";
        } else if (++loops_done_ < options_.wall_follow_loops) {
          // Another loop of the room was asked for: keep following from here.
          loop_times_.push_back(t);
          anchor_ = slam.pose();
          anchor_distance_ = slam.distance_m();
          turned_since_anchor_ = 0;
        } else {
          // The room has been walked all round: model it. (Exploration builds on this.)
          loop_times_.push_back(t);
          Enter(MissionState::kModel, t, "wall-following loop closed");
          last_cmd_ = {};
          return {};
        }
      }
    }
    return ToWheels(tw, dt);
}

namespace {

Eigen::Vector2d Rotate(const Eigen::Vector2d& v, double a) {
  return {std::cos(a) * v.x() - std::sin(a) * v.y(), std::sin(a) * v.x() + std::cos(a) * v.y()};
}

}  // namespace

void Mission::BeginEscape(double t, const slam::Slam& slam) {
  // Away from the contact, then turn to face away from it and drive off. (A
  // round robot can always turn on the spot; backing up would run into what is
  // behind.) The contact is the nearest mapped side if one is that close, else
  // its bearing from the bumper bits (left, right, both: ahead).
  const Pose2 me = slam.pose();
  const Eigen::Vector2d pos(me.x, me.y);
  const bool left = bumpers_now_ & 1, right = bumpers_now_ & 2;
  const double contact = left && !right ? 0.6 : right && !left ? -0.6 : 0.0;
  escape_heading_ = NormalizeAngle(me.theta + contact + M_PI);
  double nearest = geometry_.radius_m + 0.08;
  for (const auto& l : slam.lines()) {
    const Eigen::Vector2d away = pos - ClosestPoint({l.p0, l.p1}, pos);
    if (away.norm() < nearest && away.norm() > 1e-6) {
      nearest = away.norm();
      escape_heading_ = std::atan2(away.y(), away.x());
    }
  }
  escape_turned_ = false;
  backoff_until_ = t + 6.0;  // at most; ends after the drive off
  last_plan_ = -1e9;         // replan around what was hit once clear
}

WheelCommand Mission::Escape(double t, double dt, const Pose2& me) {
  if (!escape_turned_) {
    const double err = NormalizeAngle(escape_heading_ - me.theta);
    if (std::abs(err) > 0.25) return ToWheels({0, std::clamp(2.0 * err, -0.9, 0.9)}, dt);
    escape_turned_ = true;
    backoff_until_ = t + 1.0;  // drive off for 1 s
  }
  return ToWheels({0.08, 0}, dt);
}

WheelCommand Mission::StepModel(double t, const slam::Slam& slam) {
  // Paper §5: model the room from the line map, then complete what is incomplete.
  const EnvironmentModel& m = modeler_.Update(slam.map_lines(), slam.map_trajectory());
  if (!options_.explore) {
    Enter(MissionState::kDone, t, "room modelled (exploration off)");
    return Halt();
  }
  if (m.pending() == 0 && explore_.survey_centre && surveys_done_ < explore_.max_surveys && m.room.box) {
    // Furniture far from every wall is never within range of the wall-following
    // loop: look round from the room's middle, then from the free points that
    // see most of what no trajectory point came within survey_range_m of, until
    // little is left unseen.
    if (StartSurvey(t, slam, m)) return Halt();
  }
  if (m.pending() == 0) {
    int complete = 0;
    for (const auto& o : m.objects) complete += o.complete;
    Enter(MissionState::kDone, t,
          "room modelled: " + std::to_string(m.objects.size()) + " objects, " +
              std::to_string(complete) + " complete");
    return Halt();
  }
  // Step 2: the nearest incomplete object, and its line nearest the robot. (The
  // paper visits incomplete free objects; a wall-contact object seen only in
  // part from the wall-following loop - compound furniture, a side too far from
  // the loop - is visited too, and its free sides followed.)
  const Pose2 me = slam.map_pose();
  const ObjectModel* target = nullptr;
  double best = 1e18;
  for (const auto& o : m.objects) {
    if (o.complete || o.given_up) continue;
    const double d = std::hypot(0.5 * (o.box.xmin + o.box.xmax) - me.x, 0.5 * (o.box.ymin + o.box.ymax) - me.y);
    if (d < best) {
      best = d;
      target = &o;
    }
  }
  // Try its sides nearest first: P1 at the contour-following distance from the
  // side's centre, on the side it was seen from (the outside), heading along it
  // with the object on the right.
  target_ = target->id;
  target_at_wall_ = target->kind == ObjectKind::kWallContact;
  const auto lines = slam.map_lines();
  const auto trajectory = slam.map_trajectory();
  std::vector<std::pair<double, const slam::LineFeature*>> sides;
  for (const auto& l : lines) {
    if (std::find(target->lines.begin(), target->lines.end(), l.id) == target->lines.end()) continue;
    const Eigen::Vector2d mid = 0.5 * (l.p0 + l.p1);
    sides.emplace_back(std::hypot(mid.x() - me.x, mid.y() - me.y), &l);
  }
  std::sort(sides.begin(), sides.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  const double rot = slam.map_rotation();
  for (const auto& [d, side] : sides) {
    const Eigen::Vector2d mid = 0.5 * (side->p0 + side->p1);
    Eigen::Vector2d n(std::cos(side->theta), std::sin(side->theta));
    double nearest = 1e18;
    Eigen::Vector2d seen_from = mid + n;
    for (const auto& p : trajectory) {
      const double dd = std::hypot(p.pose.x - mid.x(), p.pose.y - mid.y());
      if (dd < nearest) {
        nearest = dd;
        seen_from = {p.pose.x, p.pose.y};
      }
    }
    if (n.dot(seen_from - mid) < 0) n = -n;
    const Eigen::Vector2d p1_map = mid + follow_distance_m_ * n;
    const Eigen::Vector2d dir(n.y(), -n.x());
    p1_ = Rotate(p1_map, -rot);
    p1_heading_ = NormalizeAngle(std::atan2(dir.y(), dir.x()) - rot);
    if (Replan(slam, RangeScan{})) {
      Enter(MissionState::kGoToP1, t, "going to object " + std::to_string(target_));
      last_plan_ = t;
      return Halt();
    }
  }
  modeler_.GiveUp(target_, "P1 unreachable");
  reason_ = "object " + std::to_string(target_) + ": P1 unreachable";
  return Halt();
}

bool Mission::StartSurvey(double t, const slam::Slam& slam, const EnvironmentModel& m) {
  const Box& r = *m.room.box;
  const double rot = slam.map_rotation();
  const Eigen::Vector2d middle(0.5 * (r.xmin + r.xmax), 0.5 * (r.ymin + r.ymax));
  const auto go = [&](const Eigen::Vector2d& p) {
    p1_ = Rotate(p, -rot);
    p1_heading_ = slam.pose().theta;
    if (!Replan(slam, RangeScan{})) return false;
    ++surveys_done_;
    survey_points_.push_back(p);
    target_ = 0;
    survey_turned_ = -1;
    Enter(MissionState::kGoToP1, t, "surveying the room (" + std::to_string(surveys_done_) + ")");
    last_plan_ = t;
    return true;
  };
  if (surveys_done_ == 0) {
    // First from the middle of the room (the reachable point nearest it).
    for (double radius = 0; radius < 1.2; radius += 0.2) {
      for (int k = 0; k < (radius > 0 ? 8 : 1); ++k) {
        if (go(middle + radius * Eigen::Vector2d(std::cos(k * M_PI / 4), std::sin(k * M_PI / 4)))) return true;
      }
    }
  }
  constexpr double kCell = 0.2;
  const double range = explore_.survey_range_m;
  // Cells of the room (map frame) not yet seen: farther than the range from
  // every trajectory point, and not inside a known object.
  const auto traj = slam.map_trajectory();
  std::vector<Eigen::Vector2d> unseen, candidates;
  for (double x = r.xmin + 0.5 * kCell; x < r.xmax; x += kCell) {
    for (double y = r.ymin + 0.5 * kCell; y < r.ymax; y += kCell) {
      const Eigen::Vector2d c(x, y);
      bool in_object = false;
      for (const auto& o : m.objects) {
        in_object = in_object || (x > o.box.xmin - 0.35 && x < o.box.xmax + 0.35 && y > o.box.ymin - 0.35 &&
                                  y < o.box.ymax + 0.35);
      }
      const bool clear_of_walls = x - r.xmin > 0.4 && r.xmax - x > 0.4 && y - r.ymin > 0.4 && r.ymax - y > 0.4;
      if (!in_object && clear_of_walls) candidates.push_back(c);
      bool seen = in_object;
      for (size_t k = 0; k < traj.size() && !seen; k += 2) {
        seen = std::hypot(traj[k].pose.x - x, traj[k].pose.y - y) < range;
      }
      if (!seen) unseen.push_back(c);
    }
  }
  for (const auto& sp : survey_points_) {  // and what earlier surveys looked at
    unseen.erase(std::remove_if(unseen.begin(), unseen.end(),
                                [&](const Eigen::Vector2d& c) { return (c - sp).norm() < range; }),
                 unseen.end());
  }
  // Then from the points that would see most of the unseen room (ties: nearer
  // the middle).
  std::vector<std::pair<double, Eigen::Vector2d>> ranked;
  for (const auto& c : candidates) {
    int n = 0;
    for (const auto& u : unseen) n += (u - c).norm() < range;
    if (n * kCell * kCell >= explore_.survey_min_unseen_m2) ranked.emplace_back(n - 0.01 * (c - middle).norm(), c);
  }
  std::sort(ranked.begin(), ranked.end(), [](const auto& a, const auto& b) { return a.first > b.first; });
  for (size_t i = 0; i < ranked.size() && i < 8; ++i) {
    if (go(ranked[i].second)) return true;
  }
  surveys_done_ = explore_.max_surveys;  // nothing left worth a look, or nowhere to look from
  return false;
}

bool Mission::Replan(const slam::Slam& slam, const RangeScan& scan) {
  std::vector<Obstacle> obstacles;
  // Mapped sides are seen shorter than they are (their ends are passed on
  // corner arcs): plan around them extended by 15 cm at each end.
  for (const auto& l : slam.lines()) {
    const Eigen::Vector2d d = (l.p1 - l.p0).normalized();
    obstacles.push_back({l.p0 - 0.15 * d, l.p1 + 0.15 * d});
  }
  for (const auto& b : bump_points_) obstacles.push_back({b, b});
  // What the IR sensors see now, mapped or not.
  const Pose2 me = slam.pose();
  for (int i = 0; i < kNumIrSensors; ++i) {
    if (!scan.range_m[i]) continue;
    const auto& m = mounts_[i];
    const Eigen::Vector2d r(m.x + *scan.range_m[i] * std::cos(m.theta), m.y + *scan.range_m[i] * std::sin(m.theta));
    const Eigen::Vector2d w = Eigen::Vector2d(me.x, me.y) + Rotate(r, me.theta);
    obstacles.push_back({w, w});
  }
  PlannerOptions po;
  po.inflation_m = geometry_.radius_m + explore_.clearance_m;
  po.hard_m = geometry_.radius_m + 0.02;
  auto path = PlanPath(obstacles, {me.x, me.y}, p1_, po);
  if (!path) return false;
  // Keep the path being followed while it is still clear and not much longer
  // than the new one: near a tight spot two ways round are often about as long,
  // and switching between them at every replan left the robot turning on the
  // spot from one to the other.
  if (!path_.empty() && (path_.back() - p1_).norm() < 1e-6) {
    std::vector<Eigen::Vector2d> rest = path_;
    rest.insert(rest.begin(), Eigen::Vector2d(me.x, me.y));
    if (PathLength(rest) < 1.25 * PathLength(*path) + 0.2 && PathClear(obstacles, rest, po.hard_m, 0.3)) {
      return true;
    }
  }
  path_ = *path;
  return true;
}

WheelCommand Mission::AbandonGoTo(double t, const std::string& why) {
  if (target_ == 0) {
    survey_turned_ = -1;
    Enter(MissionState::kModel, t, "survey point: " + why);
    return Halt();
  }
  modeler_.GiveUp(target_, "P1: " + why);
  Enter(MissionState::kModel, t, "object " + std::to_string(target_) + ", P1: " + why);
  return Halt();
}

WheelCommand Mission::StepGoTo(double t, double dt, const slam::Slam& slam, const RangeScan& raw_scan,
                               bool bumped) {
  if (t - state_since_ > explore_.go_to_timeout_s) return AbandonGoTo(t, "not reached in time");
  // Stuck (turning on the spot, no way found through what the beams see): after
  // go_to_stuck_s without getting 0.3 m further, give the goal up.
  {
    const Pose2 p = slam.pose();
    if (go_progress_t_ < state_since_ || std::hypot(p.x - go_progress_at_.x(), p.y - go_progress_at_.y()) > 0.3) {
      go_progress_t_ = t;
      go_progress_at_ = {p.x, p.y};
    } else if (t - go_progress_t_ > explore_.go_to_stuck_s && t >= backoff_until_) {
      return AbandonGoTo(t, "no way found");
    }
  }
  if (bumped && t >= backoff_until_) {
    // The same contact again (not got clear of it yet) is not a second one.
    const Pose2 p = slam.pose();
    const bool same = go_to_bumps_ >= 1 && std::hypot(p.x - last_contact_.x(), p.y - last_contact_.y()) < 0.15 &&
                      ++same_contact_escapes_ < 5;
    if (!same) same_contact_escapes_ = 0;
    last_contact_ = {p.x, p.y};
    if (go_to_bumps_ >= 1 && !same) {
      // A second contact on the way: the way there is blocked by things the
      // beams miss (chair legs). Do not push on through them: give the goal up
      // (the next behaviour gets clear of the contact first).
      return AbandonGoTo(t, "the way is blocked by obstacles the sensors miss");
    }
    if (!same) ++go_to_bumps_;
    BeginEscape(t, slam);
  }
  if (t < backoff_until_) return Escape(t, dt, slam.pose());
  const Pose2 me = slam.pose();
  const Eigen::Vector2d pos(me.x, me.y);
  // Anything any sensor sees close ahead (not only the front ones: a box corner
  // can sit between the beams of the front sensors), or what the bumper found
  // there before (a chair leg the beams miss), stops the robot and makes it plan
  // around it.
  const RangeScan scan = WithBumpMemory(raw_scan, me);
  std::optional<double> front = follower_.FrontDistance(scan);
  for (int i = 0; i < kNumIrSensors; ++i) {
    if (!scan.range_m[i]) continue;
    const auto& m = mounts_[i];
    const double hx = m.x + *scan.range_m[i] * std::cos(m.theta);
    const double hy = m.y + *scan.range_m[i] * std::sin(m.theta);
    if (hx > 0 && std::hypot(hx, hy) < geometry_.radius_m + 0.12) {
      const double d = std::hypot(hx, hy) + 0.1;
      if (!front || d < *front) front = d;
    }
  }
  if ((front && *front < explore_.front_stop_m) || t - last_plan_ > explore_.replan_period_s) {
    last_plan_ = t;
    if (!Replan(slam, scan) && front && *front < explore_.front_stop_m) {
      return ToWheels({0, explore_.k_heading * 0.3}, dt);  // blocked: look around
    }
  }
  if (target_ == 0 && (survey_turned_ >= 0 || (pos - p1_).norm() < explore_.goal_tolerance_m)) {
    // The survey point: one full turn on the spot, then model again.
    if (survey_turned_ < 0) {
      survey_turned_ = 0;
      last_theta_ = me.theta;
    }
    survey_turned_ += std::abs(NormalizeAngle(me.theta - last_theta_));
    last_theta_ = me.theta;
    if (survey_turned_ > 2 * M_PI + 0.3) {
      survey_turned_ = -1;
      Enter(MissionState::kModel, t, "survey done");
      return Halt();
    }
    return ToWheels({0, 0.5}, dt);
  }
  if ((pos - p1_).norm() < explore_.goal_tolerance_m) {
    const double err = NormalizeAngle(p1_heading_ - me.theta);
    if (std::abs(err) < explore_.heading_tolerance_rad) {
      follower_.StartFollowing(t);
      follower_.SetOrbitCorners(true);
      contour_turned_ = 0;
      contour_loops_done_ = 0;
      contour_loop_.clear();
      last_theta_ = me.theta;
      windows_seen_ = slam.stats().windows;
      Enter(MissionState::kContourFollow, t, "contour following object " + std::to_string(target_));
      return ToWheels({0, 0}, dt);
    }
    return ToWheels({0, std::clamp(explore_.k_heading * err, -0.8, 0.8)}, dt);
  }
  // Pure pursuit on the path: aim at the first path point beyond the lookahead.
  Eigen::Vector2d aim = path_.empty() ? p1_ : path_.back();
  for (const auto& p : path_) {
    if ((p - pos).norm() > explore_.lookahead_m) {
      aim = p;
      break;
    }
  }
  // Drop the corners already passed.
  while (path_.size() > 1 && (path_.front() - pos).norm() < explore_.lookahead_m) path_.erase(path_.begin());
  const double err = NormalizeAngle(std::atan2(aim.y() - pos.y(), aim.x() - pos.x()) - me.theta);
  double v = explore_.cruise_speed_mps * std::max(0.0, std::cos(err));
  if (std::abs(err) > 0.8) v = 0;
  v = std::min(v, 0.6 * (pos - p1_).norm() + 0.03);
  if (front && *front < explore_.front_stop_m) v = 0;
  return ToWheels({v, std::clamp(explore_.k_heading * err, -1.0, 1.0)}, dt);
}

WheelCommand Mission::StepContour(double t, double dt, const slam::Slam& slam, const RangeScan& raw_scan,
                                  bool bumped) {
  const RangeScan scan = WithBumpMemory(raw_scan, slam.pose());
  const Twist tw = follower_.Step(t, scan, bumped);
  contour_turned_ += NormalizeAngle(slam.pose().theta - last_theta_);
  last_theta_ = slam.pose().theta;
  const Pose2 here = slam.map_pose();
  if (contour_loop_.empty() || (contour_loop_.back() - Eigen::Vector2d(here.x, here.y)).norm() > 0.05) {
    contour_loop_.emplace_back(here.x, here.y);
  }
  if (slam.stats().windows != windows_seen_) {
    // New lines may have completed the object.
    windows_seen_ = slam.stats().windows;
    const EnvironmentModel& m = modeler_.Update(slam.map_lines(), slam.map_trajectory());
    for (const auto& o : m.objects) {
      if (o.id == target_ && o.complete) {
        Enter(MissionState::kModel, t, "object " + std::to_string(target_) + " complete");
        return Halt();
      }
    }
  }
  if (contour_turned_ < -2 * M_PI - 0.3) {
    // Walked all round it. With three sides mapped the fourth is where the robot
    // just went round: the model closes it; with fewer, say so and carry on.
    if (modeler_.CloseByContour(target_, contour_loop_, slam.map_lines(), slam.map_trajectory())) {
      Enter(MissionState::kModel, t, "object " + std::to_string(target_) + " complete (contour closed)");
      return Halt();
    }
    if (++contour_loops_done_ < explore_.contour_loops) {
      // Round again: the sides of a small box are short, and a window of the
      // PDS may have cut one in pieces too short to map; the next time round
      // the windows fall elsewhere.
      contour_turned_ = 0;
      return ToWheels(tw, dt);
    }
    modeler_.GiveUp(target_, "contour followed all round, still incomplete");
    Enter(MissionState::kModel, t, "object " + std::to_string(target_) + " incomplete after a full contour");
    return Halt();
  }
  if (target_at_wall_ && t - state_since_ > 5.0) {
    // A wall-contact object has no way round: its free sides have been followed
    // once the robot has left it along the wall.
    const EnvironmentModel& m = modeler_.model();
    for (const auto& o : m.objects) {
      if (o.id != target_) continue;
      const double dx = std::max({o.box.xmin - here.x, 0.0, here.x - o.box.xmax});
      const double dy = std::max({o.box.ymin - here.y, 0.0, here.y - o.box.ymax});
      if (std::hypot(dx, dy) > follow_distance_m_ + explore_.contour_leave_m) {
        modeler_.GiveUp(target_, "free sides followed, still incomplete");
        Enter(MissionState::kModel, t, "object " + std::to_string(target_) + " incomplete after following its free sides");
        return Halt();
      }
    }
  }
  if (t - state_since_ > explore_.contour_timeout_s) {
    modeler_.GiveUp(target_, "contour following timed out");
    Enter(MissionState::kModel, t, "object " + std::to_string(target_) + ": contour following timed out");
    return Halt();
  }
  return ToWheels(tw, dt);
}

}  // namespace irslam::control
