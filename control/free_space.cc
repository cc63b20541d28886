#include "control/free_space.h"

#include <algorithm>
#include <cmath>

namespace irslam::control {

options::Table<PenOptions> PenKeys() {
  using O = PenOptions;
  static constexpr options::Key<O> kKeys[] = {
      {"pen_check", &O::pen_check, 0, 1, "",
       "after the wall-following loop, floor seen free outside the room it encloses means it went round a "
       "pen of furniture: leave the pen and follow walls again"},
      {"pen_open_area_m2", &O::pen_open_area_m2, 0.01, 100, "m2",
       "... this much floor seen free outside the loop's room box"},
      {"pen_margin_m", &O::pen_margin_m, 0, 2, "m", "... counted this far beyond the box"},
      {"pen_goal_margin_m", &O::pen_goal_margin_m, 0, 2, "m",
       "the way out of a pen: a point seen free this far beyond the box, ..."},
      {"pen_goal_clear_m", &O::pen_goal_clear_m, 0, 1, "m",
       "... with nothing hit within this beyond the robot's radius, ..."},
      {"pen_goal_away_m", &O::pen_goal_away_m, 0, 5, "m", "... and this far from where the robot went"},
      {"pen_max_escapes", &O::pen_max_escapes, 0, 10, "", "pens left per mission; then the loop is taken as the room"},
      {"pen_free_range_m", &O::pen_free_range_m, 0.2, 1.5, "m", "a beam marks the floor free up to this, short of its hit"},
      {"pen_cell_m", &O::pen_cell_m, 0.05, 0.5, "m", "cells of the seen-free floor's grid"},
      {"pen_cover_margin_m", &O::pen_cover_margin_m, 0, 1, "m",
       "floor seen beyond a wall's mapped line, or this near its ends, is not counted (seen through the wall: drift)"},
  };
  return kKeys;
}

namespace {
constexpr double kHitMarginM = 0.1;  // the floor this short of a hit is not called free
constexpr double kMinRangeM = 0.2;   // nearer readings are not trusted (the sensors' near limit)
}  // namespace

int64_t FreeSpace::Key(double x, double y) const {
  const auto ix = static_cast<int32_t>(std::floor(x / options_.pen_cell_m));
  const auto iy = static_cast<int32_t>(std::floor(y / options_.pen_cell_m));
  return static_cast<int64_t>((static_cast<uint64_t>(static_cast<uint32_t>(ix)) << 32) |
                              static_cast<uint32_t>(iy));
}

Eigen::Vector2d FreeSpace::Centre(int64_t key) const {
  const auto u = static_cast<uint64_t>(key);
  const auto ix = static_cast<int32_t>(static_cast<uint32_t>(u >> 32));
  const auto iy = static_cast<int32_t>(static_cast<uint32_t>(u & 0xffffffffU));
  return {(ix + 0.5) * options_.pen_cell_m, (iy + 0.5) * options_.pen_cell_m};
}

void FreeSpace::Record(const Pose2& pose, const RangeScan& scan) {
  if (scan.t == last_scan_t_) return;
  last_scan_t_ = scan.t;
  if (cells_.size() < kMaxCells) cells_[Key(pose.x, pose.y)].visited = true;
  const double c = std::cos(pose.theta), s = std::sin(pose.theta);
  const double step = options_.pen_cell_m * 0.5;
  for (size_t i = 0; i < mounts_.size(); ++i) {
    const auto& r = scan.range_m[i];
    if (!r || *r < kMinRangeM) continue;  // no return: too far, or too near to tell
    const SensorMount& m = mounts_[i];
    const double ox = pose.x + c * m.x - s * m.y, oy = pose.y + s * m.x + c * m.y;
    const double bx = std::cos(pose.theta + m.theta), by = std::sin(pose.theta + m.theta);
    const double free = std::min(*r - kHitMarginM, options_.pen_free_range_m);
    for (double d = 0; d <= free; d += step) {
      if (cells_.size() >= kMaxCells) return;
      Cell& cell = cells_[Key(ox + d * bx, oy + d * by)];
      if (cell.free < UINT16_MAX) ++cell.free;
    }
    if (*r <= options_.pen_free_range_m + kHitMarginM && cells_.size() < kMaxCells) {
      Cell& cell = cells_[Key(ox + *r * bx, oy + *r * by)];
      if (cell.hit < UINT16_MAX) ++cell.hit;
    }
  }
}

template <typename F>
void FreeSpace::ForOutside(const RoomOutline& room, double rotation, double margin_m, F&& f) const {
  const double c = std::cos(rotation), s = std::sin(rotation);
  const Box& box = room.box;
  const auto covered = [&](size_t wall, double along) {
    for (const auto& [lo, hi] : room.covered[wall]) {
      if (along >= lo - options_.pen_cover_margin_m && along <= hi + options_.pen_cover_margin_m) return true;
    }
    return false;
  };
  for (const auto& [key, cell] : cells_) {
    if (cell.free == 0 || cell.hit > 0) continue;
    const Eigen::Vector2d p = Centre(key);
    const double mx = c * p.x() - s * p.y(), my = s * p.x() + c * p.y();
    // How far beyond each wall (bottom, right, top, left).
    const std::array<double, 4> beyond = {box.ymin - my, mx - box.xmax, my - box.ymax, box.xmin - mx};
    double out = 0;
    bool through_wall = false;
    for (size_t w = 0; w < 4; ++w) {
      if (beyond[w] <= margin_m) continue;
      out = std::max(out, beyond[w]);
      through_wall = through_wall || covered(w, w % 2 == 0 ? mx : my);
    }
    if (out > 0 && !through_wall) f(p, out);
  }
}

double FreeSpace::OutsideArea(const RoomOutline& room, double rotation, double margin_m) const {
  size_t n = 0;
  ForOutside(room, rotation, margin_m, [&](const Eigen::Vector2d&, double) { ++n; });
  return static_cast<double>(n) * options_.pen_cell_m * options_.pen_cell_m;
}

template <typename Pred>
bool FreeSpace::AnyNear(const Eigen::Vector2d& p, double r_m, Pred&& pred) const {
  const double cell = options_.pen_cell_m;
  const int k = static_cast<int>(std::ceil(r_m / cell));
  for (int i = -k; i <= k; ++i) {
    for (int j = -k; j <= k; ++j) {
      if (std::hypot(i * cell, j * cell) > r_m) continue;
      const auto it = cells_.find(Key(p.x() + i * cell, p.y() + j * cell));
      if (it != cells_.end() && pred(it->second)) return true;
    }
  }
  return false;
}

bool FreeSpace::HitNear(const Eigen::Vector2d& p, double r_m) const {
  return AnyNear(p, r_m, [](const Cell& c) { return c.hit > 0; });
}

bool FreeSpace::VisitedNear(const Eigen::Vector2d& p, double r_m) const {
  return AnyNear(p, r_m, [](const Cell& c) { return c.visited; });
}

std::vector<Eigen::Vector2d> FreeSpace::OutsidePoints(const RoomOutline& room, double rotation, double margin_m,
                                                      double clear_m, double away_m, size_t n) const {
  std::vector<std::pair<double, Eigen::Vector2d>> seen;
  ForOutside(room, rotation, margin_m, [&](const Eigen::Vector2d& p, double out) { seen.emplace_back(out, p); });
  const size_t k = std::min(kMaxChecked, seen.size());
  // (The cells' order in the hash map is not a rule: ties go by position.)
  std::partial_sort(seen.begin(), seen.begin() + static_cast<std::ptrdiff_t>(k), seen.end(),
                    [](const auto& a, const auto& b) {
                      if (a.first != b.first) return a.first > b.first;
                      if (a.second.x() != b.second.x()) return a.second.x() < b.second.x();
                      return a.second.y() < b.second.y();
                    });
  std::vector<Eigen::Vector2d> out;
  for (size_t i = 0; i < k && out.size() < n; ++i) {
    const Eigen::Vector2d& p = seen[i].second;
    if (!HitNear(p, clear_m) && !VisitedNear(p, away_m)) out.push_back(p);
  }
  return out;
}

}  // namespace irslam::control
