#include "control/wall_follower.h"

#include <algorithm>
#include <cmath>

namespace irslam::control {
namespace {

// Sensor indices by mounting direction (config order: right ... left).
constexpr int kRight = 0;       // -90 deg
constexpr int kRightFront = 1;  // -45 deg
constexpr int kFrontRight = 2;  // -20 deg
constexpr int kFront = 3;       //   0 deg
constexpr int kFrontLeft = 4;   // +20 deg

}  // namespace

options::Table<WallFollowerOptions> WallFollowerKeys() {
  using O = WallFollowerOptions;
  static constexpr options::Key<O> kKeys[] = {
      {"follow_distance_m", &O::follow_distance_m, 0.1, 2.0, "m",
       "robot centre to the wall on the right"},
      {"cruise_speed_mps", &O::cruise_speed_mps, 0.01, 2.0, "m/s", "speed along a wall"},
      {"front_stop_m", &O::front_stop_m, 0.1, 2.0, "m",
       "obstacle this close ahead (from the centre): inner corner"},
      {"front_slow_m", &O::front_slow_m, 0.1, 3.0, "m", "slow down below this distance ahead"},
      {"k_distance", &O::k_distance, 0, 100, "rad/s/m", "turn rate per metre of distance error"},
      {"k_angle", &O::k_angle, 0, 100, "rad/s/rad", "turn rate per radian of wall angle"},
      {"max_turn_rate_rad_s", &O::max_turn_rate_rad_s, 0.05, 10, "rad/s",
       "turn rate limit while following"},
      {"turn_rate_rad_s", &O::turn_rate_rad_s, 0.05, 10, "rad/s",
       "in-place turns at inner corners"},
      {"lost_wall_margin_m", &O::lost_wall_margin_m, 0.05, 2.0, "m",
       "a wall farther than follow distance + this is lost"},
      {"outer_arc_speed_mps", &O::outer_arc_speed_mps, 0.01, 2.0, "m/s",
       "speed round outer corners"},
      {"backoff_speed_mps", &O::backoff_speed_mps, 0.01, 1.0, "m/s", "reverse speed after a bump"},
      {"backoff_time_s", &O::backoff_time_s, 0.0, 10.0, "s", "reverse for this long after a bump"},
      {"backoff_turn_rad", &O::backoff_turn_rad, 0.0, 3.2, "rad", "then turn left this much"},
      {"squeeze_distance_m", &O::squeeze_distance_m, 0.0, 2.0, "m",
       "boxed in (a whole inner-corner turn never clear ahead): drive out the most open way this far "
       "(0: never)"},
      {"squeeze_speed_mps", &O::squeeze_speed_mps, 0.01, 0.5, "m/s", "speed driving out when boxed in"},
      {"squeeze_stop_m", &O::squeeze_stop_m, 0.1, 1.0, "m",
       "driving out when boxed in ends this close ahead (from the centre)"},
  };
  return kKeys;
}

const char* ToString(FollowMode m) {
  switch (m) {
    case FollowMode::kFind:
      return "find_wall";
    case FollowMode::kAlign:
      return "align";
    case FollowMode::kFollow:
      return "follow";
    case FollowMode::kInnerCorner:
      return "inner_corner";
    case FollowMode::kOuterCorner:
      return "outer_corner";
    case FollowMode::kBackoff:
      return "backoff";
    case FollowMode::kLeave:
      return "leave";
    case FollowMode::kSqueeze:
      return "squeeze";
  }
  return "?";
}

WallFollower::WallFollower(WallFollowerOptions options,
                           const std::array<SensorMount, kNumIrSensors>& mounts,
                           double robot_radius_m)
    : options_(options), mounts_(mounts), robot_radius_m_(robot_radius_m) {}

void WallFollower::Reset() {
  mode_ = FollowMode::kFind;
  has_followed_ = false;
  turned_rad_ = 0;
}

void WallFollower::StartFollowing(double t) {
  mode_ = FollowMode::kFind;  // force a mode change
  Enter(FollowMode::kFollow, t);
  last_t_ = t;
}

void WallFollower::Leave(double t) {
  Enter(FollowMode::kLeave, t);
  has_followed_ = false;
}

void WallFollower::Enter(FollowMode m, double t) {
  if (m == mode_) return;
  mode_ = m;
  mode_since_ = t;
  turned_rad_ = 0;
  backoff_forward_ = false;
  corner_best_front_ = 0;
  corner_best_turn_ = 0;
  if (m == FollowMode::kFollow) has_followed_ = true;
}

std::optional<WallEstimate> WallFollower::RightWall(const RangeScan& scan) const {
  const auto& r0 = scan.range_m[kRight];
  const auto& r1 = scan.range_m[kRightFront];
  const double lost = options_.follow_distance_m + options_.lost_wall_margin_m;
  if (r0 && r1) {
    const BeamHit a = HitPoint(mounts_[kRight], *r0);
    const BeamHit b = HitPoint(mounts_[kRightFront], *r1);
    const double dx = b.x - a.x, dy = b.y - a.y;
    const double len = std::hypot(dx, dy);
    if (len > 1e-3) {
      // Distance from the centre (origin) to the line through a and b.
      const double d = std::abs(a.x * dy - a.y * dx) / len;
      const double ang = std::atan2(dy, dx);
      if (d < lost && std::abs(ang) < 1.3) return WallEstimate{d, ang};
    }
  }
  if (r0) {
    const BeamHit a = HitPoint(mounts_[kRight], *r0);
    if (-a.y < lost) return WallEstimate{-a.y, 0.0, !r1};
  }
  if (r1) {
    // Only the diagonal sensor: assume the wall is parallel.
    const BeamHit b = HitPoint(mounts_[kRightFront], *r1);
    if (-b.y < lost) return WallEstimate{-b.y, 0.0};
  }
  return std::nullopt;
}

std::optional<double> WallFollower::FrontDistance(const RangeScan& scan) const {
  // Only obstacles in the robot's swept corridor (and 5 cm beside it) count as "ahead".
  return FrontDistance(scan, robot_radius_m_ + 0.05);
}

std::optional<double> WallFollower::FrontDistance(const RangeScan& scan, double half_width_m) const {
  std::optional<double> best;
  for (int i : {kFrontRight, kFront, kFrontLeft}) {
    if (!scan.range_m[i]) continue;
    const BeamHit p = HitPoint(mounts_[i], *scan.range_m[i]);
    if (std::abs(p.y) > half_width_m || p.x <= 0) continue;
    if (!best || p.x < *best) best = p.x;
  }
  return best;
}

Twist WallFollower::Step(double t, const RangeScan& scan, bool bumped, const RangeScan* sensor_scan) {
  const double dt = std::clamp(t - last_t_, 0.0, 0.1);
  last_t_ = t;
  const auto front = FrontDistance(scan);
  const auto wall = RightWall(scan);
  body_front_ = FrontDistance(sensor_scan ? *sensor_scan : scan, robot_radius_m_);
  steady_ = false;
  if (bumped && mode_ != FollowMode::kBackoff) Enter(FollowMode::kBackoff, t);
  Twist out = StepMode(t, front, wall, bumped);
  // (A mode may have switched to following just now: follow at once.)
  if (mode_ == FollowMode::kFollow) out = Follow(t, front, wall);
  turned_rad_ += out.omega * dt;
  return out;
}

Twist WallFollower::StepMode(double t, std::optional<double> front,
                             const std::optional<WallEstimate>& wall, bool bumped) {
  const auto& o = options_;
  Twist out;
  switch (mode_) {
    case FollowMode::kBackoff: {
      const double age = t - mode_since_;
      if (age < o.backoff_time_s) {
        out = {backoff_forward_ ? o.backoff_speed_mps : -o.backoff_speed_mps, 0};
      } else if (turned_rad_ < o.backoff_turn_rad) {
        out = {0, o.turn_rate_rad_s};
      } else if (!bumped) {
        Enter(has_followed_ ? FollowMode::kFollow : FollowMode::kFind, t);
      } else {
        // Still in contact after backing off and turning: the contact is not
        // ahead (set down against a wall, or wedged), and waiting here held the
        // robot still for ever. Back off again, the other way.
        backoff_forward_ = !backoff_forward_;
        mode_since_ = t;
        turned_rad_ = 0;
        out = {backoff_forward_ ? o.backoff_speed_mps : -o.backoff_speed_mps, 0};
      }
      break;
    }
    case FollowMode::kLeave:
      if (turned_rad_ >= M_PI / 2) {
        Enter(FollowMode::kFind, t);
        out = {o.cruise_speed_mps, 0};
        break;
      }
      out = {0, o.turn_rate_rad_s};
      break;
    case FollowMode::kFind:
      if ((front && *front < o.follow_distance_m + 0.15) ||
          (wall && wall->distance_m < o.follow_distance_m + 0.1)) {
        Enter(FollowMode::kAlign, t);
        break;
      }
      out = {o.cruise_speed_mps, 0};
      if (front && *front < o.front_slow_m) out.v *= 0.5;
      break;
    case FollowMode::kAlign:
      // Turn left in place until the wall is on the right and nothing is ahead.
      if (wall && !front && std::abs(wall->angle_rad) < 0.25) {
        Enter(FollowMode::kFollow, t);
        break;
      }
      if (turned_rad_ > 2 * M_PI + 0.5) {  // a full turn and no wall: go and look elsewhere
        Enter(FollowMode::kFind, t);
        break;
      }
      out = {0, o.turn_rate_rad_s};
      break;
    case FollowMode::kInnerCorner:
      out = InnerCorner(t, front);
      break;
    case FollowMode::kSqueeze:
      out = Squeeze(t);
      break;
    case FollowMode::kOuterCorner:
      if (front && *front < o.front_stop_m) {
        Enter(FollowMode::kInnerCorner, t);
        out = {0, o.turn_rate_rad_s};
        break;
      }
      if (wall && wall->distance_m < o.follow_distance_m + 0.15 && turned_rad_ < -0.3) {
        Enter(FollowMode::kFollow, t);
        break;
      }
      if (turned_rad_ < -2 * M_PI) {  // circled without finding a wall: search again
        Enter(FollowMode::kFind, t);
        break;
      }
      out = {o.outer_arc_speed_mps, -o.outer_arc_speed_mps / o.follow_distance_m};
      break;
    case FollowMode::kFollow:
      break;
  }
  return out;
}

Twist WallFollower::InnerCorner(double t, std::optional<double> front) {
  // Turn left on the spot until the way ahead is clear.
  const auto& o = options_;
  if (!front || *front > o.front_stop_m + 0.15) {
    Enter(FollowMode::kFollow, t);
    return {};
  }
  if (turned_rad_ < 2 * M_PI) {
    // (Measured in the body's width: wedged between two legs, each a
    // centimetre beside the body, every heading has something within the
    // usual corridor's 5 cm margin.)
    const double ahead = body_front_.value_or(o.front_stop_m + 0.15);
    if (ahead > corner_best_front_) {
      corner_best_front_ = ahead;
      corner_best_turn_ = turned_rad_;
    }
  } else if (o.squeeze_distance_m > 0 && turned_rad_ >= 2 * M_PI + corner_best_turn_) {
    // A whole turn and never clear ahead: boxed in all round by things
    // nearer than the stop distance (a chair's legs; turning on went on
    // until the time limit, generated room 1070). It got in, so there is
    // a way out: drive the most open way seen, then follow again.
    Enter(FollowMode::kSqueeze, t);
    return {o.squeeze_speed_mps, 0};
  }
  return {0, o.turn_rate_rad_s};
}

Twist WallFollower::Squeeze(double t) {
  // Driving out the most open way: by the sensors' own readings (a remembered
  // contact may be the way out: it was touched turning, beside the way in).
  const auto& o = options_;
  if ((body_front_ && *body_front_ < o.squeeze_stop_m) ||
      (t - mode_since_) * o.squeeze_speed_mps >= o.squeeze_distance_m) {
    Enter(has_followed_ ? FollowMode::kFollow : FollowMode::kFind, t);
    return {};
  }
  return {o.squeeze_speed_mps, 0};
}

Twist WallFollower::Follow(double t, std::optional<double> front,
                           const std::optional<WallEstimate>& wall) {
  const auto& o = options_;
  Twist out;
  if (front && *front < o.front_stop_m) {
    Enter(FollowMode::kInnerCorner, t);
    out = {0, o.turn_rate_rad_s};
  } else if (!wall) {
    Enter(FollowMode::kOuterCorner, t);
    out = {o.outer_arc_speed_mps, 0};
  } else if (wall->corner && orbit_corners_) {
    // Only a corner beside the robot (a wall along the right would be seen by
    // the diagonal sensor too): go round it at the follow distance - the
    // curvature of that circle, corrected by the distance error - until the
    // next side comes into view. (Taken as a wall alongside, the corner drew
    // the robot into wide circles that never came close enough to see the
    // sides of a small box.)
    // Only farther than the follow distance, and fully from 5 cm beyond it:
    // the side sensor may still see the side's end short of the corner, and
    // turning then would cut the corner.
    const double v = o.outer_arc_speed_mps;
    const double err = wall->distance_m - o.follow_distance_m;
    const double omega =
        -v / o.follow_distance_m * std::clamp(err / 0.05, 0.0, 1.0) - o.k_distance * err;
    out = {v, std::clamp(omega, -o.max_turn_rate_rad_s, o.max_turn_rate_rad_s)};
  } else {
    steady_ =
        std::abs(wall->angle_rad) < 0.09 && std::abs(wall->distance_m - o.follow_distance_m) < 0.05;
    double omega =
        o.k_angle * wall->angle_rad - o.k_distance * (wall->distance_m - o.follow_distance_m);
    omega = std::clamp(omega, -o.max_turn_rate_rad_s, o.max_turn_rate_rad_s);
    double v = o.cruise_speed_mps * (1.0 - 0.6 * std::abs(omega) / o.max_turn_rate_rad_s);
    if (front && *front < o.front_slow_m) {
      const double f = (*front - o.front_stop_m) / (o.front_slow_m - o.front_stop_m);
      v *= std::clamp(0.3 + 0.7 * f, 0.3, 1.0);
    }
    out = {v, omega};
  }
  return out;
}

}  // namespace irslam::control
