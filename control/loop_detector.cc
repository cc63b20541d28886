#include "control/loop_detector.h"

#include <algorithm>
#include <cmath>

namespace irslam::control {

options::Table<LoopOptions> LoopKeys() {
  using O = LoopOptions;
  static constexpr options::Key<O> kKeys[] = {
      {"loop_min_distance_m", &O::loop_min_distance_m, 0.1, 1000, "m",
       "wall following must cover this before a loop can close"},
      {"loop_close_radius_m", &O::loop_close_radius_m, 0.01, 10, "m",
       "the loop closes back within this of where steady following began"},
      {"loop_close_angle_rad", &O::loop_close_angle_rad, 0.01, 3.2, "rad",
       "... and within this of its heading"},
      {"loop_anchor_steady_s", &O::loop_anchor_steady_s, 0, 60, "s",
       "the loop's start is taken after this long of steady following"},
      {"loop_anchor_spacing_m", &O::loop_anchor_spacing_m, 0.1, 1000, "m",
       "... and another start every this much of steady following (a loop closes at any; 1000: the first only)"},
      {"loop_free_object_turn_rad", &O::loop_free_object_turn_rad, 0, 6.3, "rad",
       "a loop that turned more than this clockwise went round a free object"},
      {"loop_orbit_turn_rad", &O::loop_orbit_turn_rad, M_PI, 1000, "rad",
       "a net clockwise turn of this much, steady or not, went round a free object"},
  };
  return kKeys;
}

LoopEvent LoopDetector::Update(double t, bool steady, const Pose2& pose, double distance_m,
                               bool searching) {
  if (!have_heading_) {
    have_heading_ = true;
    heading_ = heading_peak_ = 0;
  } else {
    heading_ += NormalizeAngle(pose.theta - last_theta_);
  }
  last_theta_ = pose.theta;
  // Searching (no wall): the orbit check starts over from here.
  heading_peak_ = searching ? heading_ : std::max(heading_peak_, heading_);
  if (heading_peak_ - heading_ > options_.loop_orbit_turn_rad) {
    // Circled something clockwise without a steady anchor: a free object.
    anchors_.clear();
    follow_since_ = -1;
    heading_peak_ = heading_;
    return LoopEvent::kFreeObject;
  }
  if (!steady) {
    follow_since_ = -1;
  } else if (follow_since_ < 0) {
    follow_since_ = t;
  }
  if (follow_since_ >= 0 && t - follow_since_ >= options_.loop_anchor_steady_s &&
      (anchors_.empty() || distance_m - anchors_.back().distance >= options_.loop_anchor_spacing_m)) {
    AddAnchor(pose, distance_m);
  }
  // Back at an anchor (the oldest first: the longest loop).
  for (const Anchor& a : anchors_) {
    if (distance_m - a.distance <= options_.loop_min_distance_m) break;  // (and all after it)
    const double d = std::hypot(pose.x - a.pose.x, pose.y - a.pose.y);
    const double da = std::abs(NormalizeAngle(pose.theta - a.pose.theta));
    if (d >= options_.loop_close_radius_m || da >= options_.loop_close_angle_rad) continue;
    anchor_ = a;
    if (turned() < -options_.loop_free_object_turn_rad) {
      anchors_.clear();
      heading_peak_ = heading_;  // (the orbit check starts over too)
      return LoopEvent::kFreeObject;
    }
    return LoopEvent::kRoom;
  }
  return LoopEvent::kNone;
}

void LoopDetector::AddAnchor(const Pose2& pose, double distance_m) {
  if (anchors_.size() >= kMaxAnchors) anchors_.erase(anchors_.begin());  // (within the reserve)
  anchors_.push_back({pose, heading_, distance_m});
  if (anchors_.size() == 1) anchor_ = anchors_.front();
}

void LoopDetector::Rearm(const Pose2& pose, double distance_m) {
  anchors_.clear();
  AddAnchor(pose, distance_m);
}

}  // namespace irslam::control
