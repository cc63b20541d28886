#include "control/bump_memory.h"

#include <algorithm>
#include <cmath>

namespace irslam::control {

options::Table<BumpMemoryOptions> BumpMemoryKeys() {
  using O = BumpMemoryOptions;
  static constexpr options::Key<O> kKeys[] = {
      {"bump_contact_angle_rad", &O::bump_contact_angle_rad, 0, 1.6, "rad",
       "bearing of a contact when only one bumper is pressed"},
      {"bump_contact_offset_m", &O::bump_contact_offset_m, 0, 0.5, "m",
       "a contact is remembered this far beyond the body's edge"},
      {"bump_min_spacing_m", &O::bump_min_spacing_m, 0, 1, "m",
       "a contact this close to the last one is not new"},
      {"bump_reach_m", &O::bump_reach_m, 0, 10, "m",
       "remembered contacts farther than this are ignored"},
      {"bump_beam_half_width", &O::bump_beam_half_width, 0, 2, "",
       "a beam sees a contact within this many robot radii of its axis"},
      {"bump_min_range_m", &O::bump_min_range_m, 0, 1, "m",
       "shortest virtual reading of a contact"},
  };
  return kKeys;
}

double BumpMemory::ContactBearing(uint8_t bumpers) const {
  const bool left = bumpers & 1, right = bumpers & 2;
  return left && !right   ? options_.bump_contact_angle_rad
         : right && !left ? -options_.bump_contact_angle_rad
                          : 0.0;
}

void BumpMemory::Record(const Pose2& me, uint8_t bumpers) {
  if (bumpers == 0) return;
  // The contact is at the body's edge, ahead-left, ahead-right or ahead.
  const double a = me.theta + ContactBearing(bumpers);
  const double r = radius_m_ + options_.bump_contact_offset_m;
  const Eigen::Vector2d p(me.x + r * std::cos(a), me.y + r * std::sin(a));
  if (points_.empty() || (points_.back() - p).norm() > options_.bump_min_spacing_m)
    points_.push_back(p);
}

RangeScan BumpMemory::Apply(const RangeScan& scan, const Pose2& me, size_t from, double skip_within_m) const {
  // What the bumper found is seen from then on by every beam whose path the
  // robot's body would sweep into it: the follower steers round it instead of
  // driving into the same obstacle again.
  RangeScan out = scan;
  const double c = std::cos(me.theta), s = std::sin(me.theta);
  for (size_t k = from; k < points_.size(); ++k) {
    const Eigen::Vector2d& b = points_[k];
    const double d = std::hypot(b.x() - me.x, b.y() - me.y);
    if (d > options_.bump_reach_m || d < skip_within_m) continue;
    for (int i = 0; i < kNumIrSensors; ++i) {
      const auto& m = mounts_[static_cast<size_t>(i)];
      const Eigen::Vector2d sensor(me.x + c * m.x - s * m.y, me.y + s * m.x + c * m.y);
      const Eigen::Vector2d v = b - sensor;
      const double dir = me.theta + m.theta;
      const double along = v.x() * std::cos(dir) + v.y() * std::sin(dir);
      const double across = -v.x() * std::sin(dir) + v.y() * std::cos(dir);
      if (along <= 0 || std::abs(across) > options_.bump_beam_half_width * radius_m_) continue;
      auto& r = out.range_m[static_cast<size_t>(i)];
      if (!r || along < *r) r = std::max(along, options_.bump_min_range_m);
    }
  }
  return out;
}

void BumpMemory::TransformSince(size_t from, const Pose2& t) {
  for (size_t i = from; i < points_.size(); ++i) {
    const auto [x, y] = ToParent(t, points_[i].x(), points_[i].y());
    points_[i] = {x, y};
  }
}

}  // namespace irslam::control
