// Clean, the cleaning behaviour (control/clean.h): driving a cell's route -
// following the lane, the goals tried when a route point cannot be planned to,
// and giving a point up. Its plan, cells and progress are in clean.cc.
#include "control/clean.h"

#include <algorithm>
#include <cmath>

namespace irslam::control {

namespace {
constexpr double kIntoCellMargin = 0.05;
}  // namespace

Eigen::Vector2d Clean::IntoCell(const Eigen::Vector2d& p) const {
  if (cell_ >= plan_.order.size()) return p;
  const CoverageCell& c = plan_.cells[static_cast<size_t>(plan_.order[cell_])];
  const Eigen::Vector2d q = plan_.swapped ? Eigen::Vector2d(p.y(), p.x()) : p;
  Eigen::Vector2d best = q;
  double best_d = 1e18;
  for (const Slab& s : c.slabs) {
    // A margin inside the slab: the planner judges a goal by its grid cell's
    // clearance (half a cell off), so a point right on the boundary can fail.
    const double mx = std::min(kIntoCellMargin, 0.5 * (s.x1 - s.x0));
    const double my = std::min(kIntoCellMargin, 0.5 * (s.yhi - s.ylo));
    const Eigen::Vector2d in(std::clamp(q.x(), s.x0 + mx, s.x1 - mx), std::clamp(q.y(), s.ylo + my, s.yhi - my));
    if ((in - q).norm() < best_d) {
      best_d = (in - q).norm();
      best = in;
    }
  }
  return plan_.swapped ? Eigen::Vector2d(best.y(), best.x()) : best;
}

void Clean::SkipPoint(bool counted) {
  // The segment to the point given up is not swept.
  const auto& r = plan_.routes[cell_];
  if (point_ >= 1 && point_ < r.size())
    progress_.unreachable_m2 += AreaShare((r[point_] - r[point_ - 1]).norm());
  if (counted) ++failures_;
  ++point_;
  if (failures_ >= options_.max_goal_failures || point_ >= plan_.routes[cell_].size()) {
    NextCell(true);
  } else {
    phase_ = Phase::kPlanGoal;
  }
}

Twist Clean::Follow(const Pose2& me, const RangeScan& scan, bool* blocked, bool* passed) {
  const auto& o = options_;
  const auto& r = plan_.routes[cell_];
  const Eigen::Vector2d a = r[point_ - 1], b = r[point_];
  const Eigen::Vector2d p(me.x, me.y);
  const Eigen::Vector2d d = b - a;
  const double len = d.norm();
  const Eigen::Vector2d u = len > 1e-9 ? Eigen::Vector2d(d / len) : Eigen::Vector2d(1, 0);
  const double along = (p - a).dot(u);
  const double cross = u.x() * (p - a).y() - u.y() * (p - a).x();  // > 0: left of the lane
  if (along >= len - o.waypoint_tolerance_m || (p - b).norm() < o.waypoint_tolerance_m) {
    *passed = true;
    return {0, 0};
  }
  const double want = std::atan2(u.y(), u.x()) - std::atan(o.k_cross * cross);
  const double err = NormalizeAngle(want - me.theta);
  if (std::abs(err) > o.turn_in_place_rad)
    return {0, std::clamp(o.k_heading * err, -o.max_rate_rad_s, o.max_rate_rad_s)};
  cross_sq_ += cross * cross;
  ++cross_n_;
  progress_.cross_track_max_m = std::max(progress_.cross_track_max_m, std::abs(cross));
  // Something ahead the map does not have, nearer than where this segment ends.
  const double rest = len - along;
  for (int i = 0; i < kNumIrSensors; ++i) {
    if (!scan.range_m[i]) continue;
    const auto [hx, hy] = HitPoint(mounts_[i], *scan.range_m[i]);
    if (hx > kAheadM && std::abs(hy) < radius_m_ && hx < radius_m_ + o.front_stop_m &&
        hx < rest + radius_m_ + std::min(o.clearance_m, o.edge_clearance_m) - 0.05)
      *blocked = true;
  }
  const double v = std::min(o.sweep_speed_mps * std::cos(err), o.approach_gain * rest + 0.03);
  return {std::max(0.0, v), std::clamp(o.k_heading * err, -o.max_rate_rad_s, o.max_rate_rad_s)};
}

Clean::Result Clean::Step(double t, const slam::Slam& slam, const RangeScan& raw_scan,
                          uint8_t bumpers, const BumpMemory& bumps, const WallFollower& follower) {
  if (planning()) {
    Plan(t);  // (the mission plans in its own step: this is only a fallback)
    return {};
  }
  const Pose2 me = slam.map_pose();
  grid_.Mark({me.x, me.y});
  const double rot = slam.map_rotation();
  // Stuck (turning on the spot, or planning and blocked in turn): give the route
  // point up, so nothing is retried forever.
  if ((Eigen::Vector2d(me.x, me.y) - progress_at_).norm() > 0.1) {
    progress_at_ = {me.x, me.y};
    progress_t_ = t;
  } else if (phase_ != Phase::kDone && t - progress_t_ > options_.stuck_s) {
    progress_t_ = t;
    SkipPoint();
    return {};
  }
  switch (phase_) {
    case Phase::kDone:
      return {Status::kDone, {}};
    case Phase::kPlanGoal:
      return StepPlanGoal(t, me, rot, slam, bumps);
    case Phase::kTransit: {
      const GoTo::Result r = go_to_.Step(t, slam, raw_scan, bumpers, bumps, follower);
      if (r.status == GoTo::Status::kDriving) return {Status::kCleaning, r.twist};
      if (r.status == GoTo::Status::kGiveUp) {
        SkipPoint();
        return {};
      }
      ++point_;
      failures_ = 0;
      phase_ = Phase::kSweep;
      if (point_ >= plan_.routes[cell_].size()) NextCell(false);
      return {};
    }
    case Phase::kSweep:
      break;
  }
  return StepSweep(me, slam, raw_scan, bumpers, bumps);
}

// The route point to go to next: reached already, or planned to (the point
// itself, moved along the route into the cell, or into the cell's free space:
// at most three plans), or given up.
Clean::Result Clean::StepPlanGoal(double t, const Pose2& me, double rot, const slam::Slam& slam,
                                  const BumpMemory& bumps) {
  // One plan per period at most.
  const Eigen::Vector2d goal = plan_.routes[cell_][point_];
  if ((goal - Eigen::Vector2d(me.x, me.y)).norm() < 2 * options_.waypoint_tolerance_m) {
    ++point_;
    failures_ = 0;
    phase_ = Phase::kSweep;
    if (point_ >= plan_.routes[cell_].size()) NextCell(false);
    return {};
  }
  const std::vector<Eigen::Vector2d> tries = GoalTries(goal);
  for (size_t k = 0; k < tries.size() && k < 3; ++k) {
    // At most three plans: the last is the one moved into the cell, if any.
    const Eigen::Vector2d& p = k == 2 ? tries.back() : tries[k];
    if (go_to_.TryGoal(t, RotateVector(p, -rot), 0, false, slam, bumps)) {
      go_to_.Begin(t);
      phase_ = Phase::kTransit;
      progress_t_ = t;  // stuck_s counts for this route point from now
      return {};
    }
  }
  // Not counted when the last point that could not be planned to was given up
  // from here too: the robot has not moved, so what failed is where it stands,
  // not this point; the next is tried (one a period, each at most three plans).
  const Eigen::Vector2d here(me.x, me.y);
  const bool same_spot =
      options_.no_plan_spot_m > 0 && no_plan_at_ && (here - *no_plan_at_).norm() < options_.no_plan_spot_m;
  no_plan_at_ = here;
  SkipPoint(!same_spot);
  return {};
}

std::vector<Eigen::Vector2d> Clean::GoalTries(const Eigen::Vector2d& goal) const {
  // A route point lies at the cleaning clearance, a little beyond the
  // planner's on its grid: if it cannot be planned to, try it moved along
  // the route into the cell.
  const auto& route = plan_.routes[cell_];
  const Eigen::Vector2d toward =
      point_ + 1 < route.size() ? route[point_ + 1] : (point_ > 0 ? route[point_ - 1] : goal);
  const Eigen::Vector2d dir =
      (toward - goal).norm() > 1e-6 ? Eigen::Vector2d((toward - goal).normalized()) : Eigen::Vector2d(0, 0);
  std::vector<Eigen::Vector2d> tries;
  for (double shift : {0.0, 0.06, 0.12}) {
    if (shift > 0 && shift > (toward - goal).norm() - 0.02) break;
    tries.push_back(goal + shift * dir);
  }
  // The last try: the point moved into the cell's free space, a margin
  // inside (a point of the pushed-out edge pass lies outside it, and a
  // contact remembered near a lane end can block the point itself).
  const Eigen::Vector2d in = IntoCell(goal);
  if ((in - goal).norm() > 1e-6) tries.push_back(in);
  return tries;
}

// Driving along the lane: a contact or an obstacle ahead turns it into a plan
// to the lane's next point (the go-to escapes first).
Clean::Result Clean::StepSweep(const Pose2& me, const slam::Slam& slam, const RangeScan& raw_scan, uint8_t bumpers,
                               const BumpMemory& bumps) {
  if (bumpers != 0) {
    phase_ = Phase::kPlanGoal;
    return {};
  }
  const RangeScan scan = bumps.Apply(raw_scan, slam.pose());
  bool blocked = false, passed = false;
  const Twist tw = Follow(me, scan, &blocked, &passed);
  if (passed) {
    failures_ = 0;
    if (++point_ >= plan_.routes[cell_].size()) NextCell(false);
    return {Status::kCleaning, tw};
  }
  if (blocked) {
    phase_ = Phase::kPlanGoal;
    return {};
  }
  return {Status::kCleaning, tw};
}

}  // namespace irslam::control
