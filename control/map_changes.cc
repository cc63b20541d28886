#include "control/map_changes.h"

#include <algorithm>
#include <cmath>

namespace irslam::control {

options::Table<MapChangeOptions> MapChangeKeys() {
  using O = MapChangeOptions;
  static constexpr options::Key<O> kKeys[] = {
      {"view_min_m", &O::view_min_m, 0, 2, "m",
       "a saved object's side is in view from this distance (moved-furniture check) ..."},
      {"view_max_m", &O::view_max_m, 0.05, 2, "m", "... up to this"},
      {"view_bearing_rad", &O::view_bearing_rad, 0.1, 3.15, "rad", "... and within this of the heading"},
      {"bin_m", &O::bin_m, 0.01, 1, "m", "a side's length is marked as passed in bins of this"},
      {"seen_fraction", &O::seen_fraction, 0.1, 1, "",
       "a side passed in view along this share of its length should have been seen again"},
      {"min_side_m", &O::min_side_m, 0, 10, "m", "shorter sides are not watched"},
      {"wall_margin_m", &O::wall_margin_m, 0, 2, "m",
       "the part of a side within this of a wall need not have been passed (the robot cannot go there)"},
      {"min_missing_sides", &O::min_missing_sides, 1, 4, "",
       "an object with this many sides not seen again where they were has moved or gone"},
      {"stretched_m", &O::stretched_m, 0, 10, "m",
       "a side the SLAM has lengthened by more than this is not where it was either (moved along it) ..."},
      {"corner_m", &O::corner_m, 0, 1, "m", "... if both its ends were within this of another line"},
      {"past_box_moves", &O::past_box_moves, 0, 0, "",
       "a complete object's side stretched more than stretched_m past its box has moved, without a second side"},
  };
  return kKeys;
}

void MapChanges::Reset(const std::vector<slam::LineFeature>& lines, const std::vector<TimedPose>& trajectory,
                       const EnvironmentModel& model, double axis_tolerance_rad) {
  sides_.clear();
  reported_.clear();
  const std::vector<room_geometry::Side> sides = room_geometry::ToSides(lines, trajectory, axis_tolerance_rad);
  for (const auto& o : model.objects) {
    for (int id : o.lines) {
      const auto s = std::find_if(sides.begin(), sides.end(), [&](const auto& x) { return x.id == id; });
      const auto l = std::find_if(lines.begin(), lines.end(), [&](const auto& x) { return x.id == id; });
      if (s == sides.end() || l == lines.end() || s->seen_from == 0) continue;
      if (s->a1 - s->a0 < options_.min_side_m) continue;
      Watched w;
      w.side = *s;
      w.object = o.id;
      w.observations = l->observations;
      w.passed.assign(static_cast<size_t>(std::ceil((s->a1 - s->a0) / options_.bin_m)), false);
      // Along the side, the walls across it (room frame: the model's room box).
      double lo = s->a0, hi = s->a1;
      if (model.room.box) {
        const Box& r = *model.room.box;
        lo = std::max(lo, (s->horizontal ? r.xmin : r.ymin) + options_.wall_margin_m);
        hi = std::min(hi, (s->horizontal ? r.xmax : r.ymax) - options_.wall_margin_m);
      }
      if (hi - lo < options_.min_side_m) continue;
      w.first = static_cast<size_t>(std::max(0.0, std::floor((lo - s->a0) / options_.bin_m)));
      w.last = std::min(w.passed.size(), static_cast<size_t>(std::ceil((hi - s->a0) / options_.bin_m)));
      const auto meets = [&](const Eigen::Vector2d& p) {
        return std::any_of(lines.begin(), lines.end(), [&](const slam::LineFeature& m) {
          // A corner: a line across it (a collinear piece beside it is the
          // same side seen in part, which grows when the pieces merge).
          if (m.id == id || std::abs(std::cos(m.theta - l->theta)) > 0.5) return false;
          const Eigen::Vector2d d = m.p1 - m.p0;
          const double u = std::clamp((p - m.p0).dot(d) / std::max(d.squaredNorm(), 1e-12), 0.0, 1.0);
          return (m.p0 + u * d - p).norm() <= options_.corner_m;
        });
      };
      w.bounded = meets(l->p0) && meets(l->p1);
      w.boxed = options_.past_box_moves && o.complete && o.box.xmax > o.box.xmin && o.box.ymax > o.box.ymin;
      w.box_lo = s->horizontal ? o.box.xmin : o.box.ymin;
      w.box_hi = s->horizontal ? o.box.xmax : o.box.ymax;
      sides_.push_back(std::move(w));
    }
  }
}

bool MapChanges::SeenAgain(const Watched& w, const slam::LineFeature* l) const {
  // Merged into another line (seen and joined): not missing.
  return l == nullptr || l->observations > w.observations;
}

bool MapChanges::Stretched(const Watched& w, const slam::LineFeature* l) const {
  return w.bounded && l != nullptr && (l->p1 - l->p0).norm() > w.side.a1 - w.side.a0 + options_.stretched_m;
}

bool MapChanges::PastItsBox(const Watched& w, const slam::LineFeature* l) const {
  if (!w.boxed || l == nullptr) return false;
  const double a = w.side.horizontal ? l->p0.x() : l->p0.y(), b = w.side.horizontal ? l->p1.x() : l->p1.y();
  return std::min(a, b) < w.box_lo - options_.stretched_m || std::max(a, b) > w.box_hi + options_.stretched_m;
}

int MapChanges::Missing(Watched* w, bool conclusive) {
  w->decided = true;
  w->missing = true;
  int missing = 0;
  for (const auto& o : sides_) missing += o.object == w->object && o.missing;
  if ((!conclusive && missing < options_.min_missing_sides) ||
      std::find(reported_.begin(), reported_.end(), w->object) != reported_.end())
    return 0;
  reported_.push_back(w->object);
  return w->object;
}

std::vector<int> MapChanges::Step(const Pose2& me, const std::vector<slam::LineFeature>& lines) {
  std::vector<int> moved;
  for (auto& w : sides_) {
    if (w.decided) continue;
    // The side's line now (nullptr: merged into another), looked up once.
    const auto found = std::find_if(lines.begin(), lines.end(), [&](const auto& x) { return x.id == w.side.id; });
    const slam::LineFeature* line = found == lines.end() ? nullptr : &*found;
    if (PastItsBox(w, line)) {
      if (const int id = Missing(&w, true)) moved.push_back(id);
      continue;
    }
    if (Stretched(w, line)) {
      if (const int id = Missing(&w)) moved.push_back(id);
      continue;
    }
    const room_geometry::Side& s = w.side;
    const double along = s.horizontal ? me.x : me.y;
    const double across = s.horizontal ? me.y : me.x;
    const double d = (across - s.c) * s.seen_from;  // > 0: on the side it was seen from
    const bool in_view = d >= options_.view_min_m && d <= options_.view_max_m && along >= s.a0 && along <= s.a1;
    if (in_view) {
      // Bearing of the side's foot point from the robot.
      const double foot = s.horizontal ? (s.seen_from > 0 ? -M_PI / 2 : M_PI / 2)
                                       : (s.seen_from > 0 ? M_PI : 0.0);
      if (std::abs(NormalizeAngle(foot - me.theta)) <= options_.view_bearing_rad) {
        const size_t bin = std::min(w.passed.size() - 1, static_cast<size_t>((along - s.a0) / options_.bin_m));
        w.passed[bin] = true;
      }
      continue;  // judged once the robot has left it (the window with it closed)
    }
    const auto first = w.passed.begin() + static_cast<std::ptrdiff_t>(w.first);
    const auto last = w.passed.begin() + static_cast<std::ptrdiff_t>(w.last);
    const double share = static_cast<double>(std::count(first, last, true)) /
                         static_cast<double>(std::max<size_t>(1, w.last - w.first));
    if (share < options_.seen_fraction) continue;
    // Passed in view along most of its length and left behind: seen again or missing.
    if (d > options_.view_max_m + 0.3 || d < 0 || along < s.a0 - 0.3 || along > s.a1 + 0.3) {
      if (SeenAgain(w, line)) {
        w.decided = true;
        continue;
      }
      if (const int id = Missing(&w)) moved.push_back(id);
    }
  }
  return moved;
}

}  // namespace irslam::control
