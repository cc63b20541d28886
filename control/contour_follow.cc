#include "control/contour_follow.h"

#include <algorithm>
#include <cmath>

namespace irslam::control {

options::Table<ContourOptions> ContourKeys() {
  using O = ContourOptions;
  static constexpr options::Key<O> kKeys[] = {
      {"contour_timeout_s", &O::contour_timeout_s, 1, 3600, "s",
       "give up completing an object after this"},
      {"contour_leave_m", &O::contour_leave_m, 0.05, 10, "m",
       "a wall-contact object's free sides are done (a free one left along a wall) this much beyond the "
       "follow distance from it"},
      {"contour_loops", &O::contour_loops, 1, 10, "", "times round an object before giving it up"},
      {"contour_leave_after_s", &O::contour_leave_after_s, 0, 600, "s",
       "... checked only after following it this long"},
      {"contour_turn_margin_rad", &O::contour_turn_margin_rad, 0, 3.2, "rad",
       "all round an object: turned 2 pi plus this"},
      {"contour_trace_step_m", &O::contour_trace_step_m, 0.001, 1, "m",
       "the followed contour is recorded at this spacing"},
  };
  return kKeys;
}

const ObjectModel* NearestPending(const EnvironmentModel& m, const Pose2& me) {
  const ObjectModel* target = nullptr;
  double best = 1e18;
  for (const auto& o : m.objects) {
    if (o.complete || o.given_up) continue;
    const double d =
        std::hypot(0.5 * (o.box.xmin + o.box.xmax) - me.x, 0.5 * (o.box.ymin + o.box.ymax) - me.y);
    if (d < best) {
      best = d;
      target = &o;
    }
  }
  return target;
}

std::vector<ContourStart> ContourStarts(const ObjectModel& target,
                                        const std::vector<slam::LineFeature>& lines,
                                        const std::vector<TimedPose>& trajectory, const Pose2& me,
                                        double follow_distance_m) {
  std::vector<std::pair<double, const slam::LineFeature*>> sides;
  for (const auto& l : lines) {
    if (std::find(target.lines.begin(), target.lines.end(), l.id) == target.lines.end()) continue;
    const Eigen::Vector2d mid = 0.5 * (l.p0 + l.p1);
    sides.emplace_back(std::hypot(mid.x() - me.x, mid.y() - me.y), &l);
  }
  std::sort(sides.begin(), sides.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  // Beside the ends too only for a wall-contact object (see the header).
  const bool ends = target.kind == ObjectKind::kWallContact;
  std::vector<ContourStart> out, ahead, behind;
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
    const Eigen::Vector2d dir(n.y(), -n.x());
    const double heading = std::atan2(dir.y(), dir.x());
    out.push_back({mid + follow_distance_m * n, heading});
    if (!ends) continue;
    const bool p1_ahead = dir.dot(side->p1 - side->p0) > 0;
    ahead.push_back({(p1_ahead ? side->p1 : side->p0) + follow_distance_m * n, heading});
    behind.push_back({(p1_ahead ? side->p0 : side->p1) + follow_distance_m * n, heading});
  }
  out.insert(out.end(), ahead.begin(), ahead.end());
  out.insert(out.end(), behind.begin(), behind.end());
  return out;
}

void ContourFollow::Start(double t, double theta, int slam_windows) {
  since_ = t;
  turned_ = 0;
  loops_done_ = 0;
  away_ = false;
  trace_.clear();
  last_theta_ = theta;
  windows_seen_ = slam_windows;
}

bool ContourFollow::LeftTarget(const EnvironmentModel& m, const Pose2& here) const {
  for (const auto& o : m.objects) {
    if (o.id != target_) continue;
    const double dx = std::max({o.box.xmin - here.x, 0.0, here.x - o.box.xmax});
    const double dy = std::max({o.box.ymin - here.y, 0.0, here.y - o.box.ymax});
    if (std::hypot(dx, dy) > follow_distance_m_ + options_.contour_leave_m) return true;
  }
  return false;
}

ContourFollow::Result ContourFollow::Step(double t, const slam::Slam& slam, const RangeScan& scan,
                                          bool bumped, WallFollower* follower, Modeler* modeler) {
  const auto& o = options_;
  const Twist tw = follower->Step(t, scan, bumped);
  turned_ += NormalizeAngle(slam.pose().theta - last_theta_);
  last_theta_ = slam.pose().theta;
  const Pose2 here = slam.map_pose();
  if (trace_.empty() ||
      (trace_.back() - Eigen::Vector2d(here.x, here.y)).norm() > o.contour_trace_step_m) {
    trace_.emplace_back(here.x, here.y);
  }
  if (slam.stats().windows != windows_seen_) {
    // New lines may have completed the object.
    windows_seen_ = slam.stats().windows;
    const EnvironmentModel& m = modeler->Update(slam.map_lines(), slam.map_trajectory());
    for (const auto& obj : m.objects) {
      if (obj.id == target_ && obj.complete) return {Status::kComplete, {}};
    }
  }
  if (turned_ < -2 * M_PI - o.contour_turn_margin_rad) {
    // Walked all round it. With three sides mapped the fourth is where the robot
    // just went round: the model closes it; with fewer, go round again.
    if (modeler->CloseByContour(target_, trace_, slam.map_lines(), slam.map_trajectory())) {
      return {Status::kClosed, {}};
    }
    if (++loops_done_ < o.contour_loops) {
      // Round again: the sides of a small box are short, and a window of the
      // PDS may have cut one in pieces too short to map; the next time round
      // the windows fall elsewhere.
      turned_ = 0;
      return {Status::kFollowing, tw};
    }
    return {Status::kIncomplete, {}};
  }
  // A wall-contact object has no way round: its free sides have been followed
  // once the robot has left it along the wall.
  if (at_wall_ && t - since_ > o.contour_leave_after_s && LeftTarget(modeler->model(), here)) {
    // The side not mapped may be where the robot just went past (the model
    // infers it from the trace, as from a contour all round).
    if (modeler->CloseAlongWall(target_, trace_, slam.map_lines(), slam.map_trajectory())) {
      return {Status::kClosed, {}};
    }
    return {Status::kFreeSidesDone, {}};
  }
  // A free object near a wall: the robot met the wall in the gap beside it and
  // follows the wall away. The side facing the wall, where it cannot go, may be
  // inferred; or the one side not mapped, if the robot went past it before it
  // left (once each time it leaves; otherwise it goes on, and may come round).
  const bool away =
      !at_wall_ && t - since_ > o.contour_leave_after_s && LeftTarget(modeler->model(), here);
  if (away && !away_) {
    away_ = true;
    if (modeler->CloseNearWall(target_, slam.map_lines(), slam.map_trajectory()) ||
        modeler->CloseAlongWall(target_, trace_, slam.map_lines(), slam.map_trajectory())) {
      return {Status::kClosed, {}};
    }
  }
  if (!away) away_ = false;
  if (t - since_ > o.contour_timeout_s) return {Status::kTimedOut, {}};
  return {Status::kFollowing, tw};
}

}  // namespace irslam::control
