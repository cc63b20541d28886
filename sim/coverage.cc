#include "sim/coverage.h"

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace irslam::sim {

namespace {

bool InsideOutline(const std::vector<Vec2>& poly, double x, double y) {
  bool in = false;
  for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const auto& a = poly[i];
    const auto& b = poly[j];
    if ((a.y > y) != (b.y > y) && x < (b.x - a.x) * (y - a.y) / (b.y - a.y) + a.x) in = !in;
  }
  return in;
}

// The world's bounds rasterised at cell_m: the free floor, where the body's
// centre may be (radius from every wall and side), and the body-disc stamp.
class FloorGrid {
 public:
  using Cells = std::vector<uint8_t>;

  FloorGrid(const World& world, double radius_m, double cell_m)
      : r_(world.Bounds()),
        cell_m_(cell_m),
        radius_m_(radius_m),
        nx_(static_cast<int>(std::ceil((r_.xmax - r_.xmin) / cell_m))),
        ny_(static_cast<int>(std::ceil((r_.ymax - r_.ymin) / cell_m))),
        rc_(static_cast<int>(std::ceil(radius_m / cell_m))) {}

  bool empty() const { return nx_ <= 0 || ny_ <= 0; }
  size_t size() const { return Idx(0, ny_); }

  // The free floor (room minus furniture) and the centre cells.
  void Rasterise(const World& world) {
    const std::vector<Segment> segs = world.Segments();
    floor_.assign(size(), 0);
    centre_.assign(size(), 0);
    for (int j = 0; j < ny_; ++j) {
      for (int i = 0; i < nx_; ++i) {
        const double x = Cx(i), y = Cy(j);
        if (!InsideOutline(world.outline, x, y)) continue;
        bool in_object = false;
        for (const auto& b : world.objects) in_object = in_object || (x > b.xmin && x < b.xmax && y > b.ymin && y < b.ymax);
        if (in_object) continue;
        floor_[Idx(i, j)] = 1;
        double d = 1e9;
        Vec2 c;
        for (const auto& s : segs) d = std::min(d, PointSegmentDistance({x, y}, s, &c));
        centre_[Idx(i, j)] = d >= radius_m_;
      }
    }
  }

  // The centre cells reachable from the start (4-connected).
  Cells ReachableFrom(const Pose2& start) const {
    const int si = std::clamp(static_cast<int>((start.x - r_.xmin) / cell_m_), 0, nx_ - 1);
    const int sj = std::clamp(static_cast<int>((start.y - r_.ymin) / cell_m_), 0, ny_ - 1);
    Cells reach(size(), 0);
    std::vector<std::pair<int, int>> stack;
    // The start itself may sit a little inside the radius on a rasterised grid: take the nearest centre cell.
    int best_i = si, best_j = sj;
    double best = 1e9;
    for (int j = std::max(0, sj - 5); j <= std::min(ny_ - 1, sj + 5); ++j)
      for (int i = std::max(0, si - 5); i <= std::min(nx_ - 1, si + 5); ++i)
        if (centre_[Idx(i, j)] && std::hypot(i - si, j - sj) < best) best = std::hypot(i - si, j - sj), best_i = i, best_j = j;
    if (best < 1e9) {
      stack.push_back({best_i, best_j});
      reach[Idx(best_i, best_j)] = 1;
    }
    while (!stack.empty()) {
      const auto [i, j] = stack.back();
      stack.pop_back();
      const int di[4] = {1, -1, 0, 0}, dj[4] = {0, 0, 1, -1};
      for (int k = 0; k < 4; ++k) {
        const int a = i + di[k], b = j + dj[k];
        if (a < 0 || b < 0 || a >= nx_ || b >= ny_ || reach[Idx(a, b)] || !centre_[Idx(a, b)]) continue;
        reach[Idx(a, b)] = 1;
        stack.push_back({a, b});
      }
    }
    return reach;
  }

  // The floor the body discs at the given centre cells cover; *count: how many cells.
  Cells Swept(const Cells& centres, long* count) const {
    Cells out(size(), 0);
    for (int j = 0; j < ny_; ++j)
      for (int i = 0; i < nx_; ++i)
        if (centres[Idx(i, j)]) Stamp(&out, Cx(i), Cy(j), count, nullptr);
    return out;
  }

  // Marks the floor cells (only those in *only, if given) under the body disc at (x, y).
  void Stamp(Cells* grid, double x, double y, long* count, const Cells* only) const {
    const int i0 = static_cast<int>((x - r_.xmin) / cell_m_), j0 = static_cast<int>((y - r_.ymin) / cell_m_);
    for (int j = std::max(0, j0 - rc_); j <= std::min(ny_ - 1, j0 + rc_); ++j) {
      for (int i = std::max(0, i0 - rc_); i <= std::min(nx_ - 1, i0 + rc_); ++i) {
        const size_t k = Idx(i, j);
        if ((*grid)[k] || !floor_[k] || (only && !(*only)[k])) continue;
        if (std::hypot(Cx(i) - x, Cy(j) - y) > radius_m_) continue;
        (*grid)[k] = 1;
        if (count) ++*count;
      }
    }
  }

 private:
  size_t Idx(int i, int j) const {
    return static_cast<size_t>(j) * static_cast<size_t>(nx_) + static_cast<size_t>(i);
  }
  double Cx(int i) const { return r_.xmin + (i + 0.5) * cell_m_; }
  double Cy(int j) const { return r_.ymin + (j + 0.5) * cell_m_; }

  Box r_;
  double cell_m_, radius_m_;
  int nx_, ny_, rc_;
  Cells floor_, centre_;
};

}  // namespace

CoverageScore ScoreCoverage(const World& world, double radius_m, const std::vector<TimedPose>& truth,
                            double t0, double t1, double cell_m, std::vector<std::pair<double, double>>* curve,
                            double sample_s) {
  CoverageScore out;
  FloorGrid grid(world, radius_m, cell_m);
  if (grid.empty()) return out;
  grid.Rasterise(world);
  long n_target = 0;
  const FloorGrid::Cells target = grid.Swept(grid.ReachableFrom(world.start), &n_target);
  FloorGrid::Cells covered(grid.size(), 0);
  long n_covered = 0;
  double next_sample = t0;
  const TimedPose* last = nullptr;
  for (const auto& p : truth) {
    if (p.t < t0 || p.t > t1) continue;
    if (last) out.path_m += std::hypot(p.pose.x - last->pose.x, p.pose.y - last->pose.y);
    // Between samples farther apart than half a cell, fill in.
    const int steps = last ? std::max(1, static_cast<int>(std::hypot(p.pose.x - last->pose.x, p.pose.y - last->pose.y) /
                                                          (0.5 * cell_m)))
                           : 1;
    for (int k = 1; k <= steps; ++k) {
      const double f = static_cast<double>(k) / steps;
      const double x = last ? last->pose.x + f * (p.pose.x - last->pose.x) : p.pose.x;
      const double y = last ? last->pose.y + f * (p.pose.y - last->pose.y) : p.pose.y;
      grid.Stamp(&covered, x, y, &n_covered, &target);
    }
    last = &p;
    if (curve && p.t >= next_sample) {
      curve->emplace_back(p.t - t0, n_target ? static_cast<double>(n_covered) / n_target : 0);
      next_sample += sample_s;
    }
  }
  out.reachable_m2 = n_target * cell_m * cell_m;
  out.covered_m2 = n_covered * cell_m * cell_m;
  out.fraction = n_target ? static_cast<double>(n_covered) / n_target : 0;
  if (curve) curve->emplace_back(t1 - t0, out.fraction);
  return out;
}

}  // namespace irslam::sim
