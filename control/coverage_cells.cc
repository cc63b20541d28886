// The boustrophedon cell decomposition of control/coverage.h (Decompose) and a
// cell's own geometry (area, outline); the sweep of a cell and the covered-floor
// grid are in coverage.cc, the plan (the cells' tour) in coverage_plan.cc.
#include "control/coverage.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace irslam::control {

double CoverageCell::area_m2() const {
  double a = 0;
  for (const auto& s : slabs) a += (s.x1 - s.x0) * (s.yhi - s.ylo);
  return a;
}

std::vector<Eigen::Vector2d> CoverageCell::Outline(double g) const {
  std::vector<Eigen::Vector2d> out;
  if (slabs.empty()) return out;
  // Lower boundary left to right, then the upper one right to left (a staircase).
  for (size_t i = 0; i < slabs.size(); ++i) {
    const double x0 = i == 0 ? slabs[i].x0 - g : slabs[i].x0;
    const double x1 = i + 1 == slabs.size() ? slabs[i].x1 + g : slabs[i].x1;
    out.emplace_back(x0, slabs[i].ylo - g);
    out.emplace_back(x1, slabs[i].ylo - g);
  }
  for (size_t k = slabs.size(); k-- > 0;) {
    const double x0 = k == 0 ? slabs[k].x0 - g : slabs[k].x0;
    const double x1 = k + 1 == slabs.size() ? slabs[k].x1 + g : slabs[k].x1;
    out.emplace_back(x1, slabs[k].yhi + g);
    out.emplace_back(x0, slabs[k].yhi + g);
  }
  return out;
}

std::vector<CoverageCell> Decompose(const Box& free, const std::vector<Box>& obstacles,
                                    const CleaningOptions& o) {
  std::vector<CoverageCell> cells;
  const double eps = 1e-9;
  if (free.width() <= eps || free.height() < 0) return cells;
  // The critical x positions: the free space's ends and every obstacle's x-edges within.
  std::vector<double> xs = {free.xmin, free.xmax};
  for (const auto& b : obstacles) {
    if (b.xmin > free.xmin && b.xmin < free.xmax) xs.push_back(b.xmin);
    if (b.xmax > free.xmin && b.xmax < free.xmax) xs.push_back(b.xmax);
  }
  std::sort(xs.begin(), xs.end());
  xs.erase(std::unique(xs.begin(), xs.end(), [](double a, double b) { return b - a < 1e-6; }),
           xs.end());
  struct Piece {
    double ylo, yhi;
    int cell;
  };
  std::vector<Piece> prev;
  for (size_t i = 0; i + 1 < xs.size(); ++i) {
    const double x0 = xs[i], x1 = xs[i + 1];
    if (x1 - x0 < 1e-6) continue;
    // Blocked y-intervals of this slab, then the free ones between them.
    std::vector<std::pair<double, double>> blocked;
    for (const auto& b : obstacles) {
      if (b.xmin < x1 - 1e-7 && b.xmax > x0 + 1e-7 && b.ymax > free.ymin && b.ymin < free.ymax)
        blocked.emplace_back(b.ymin, b.ymax);
    }
    std::sort(blocked.begin(), blocked.end());
    std::vector<Piece> pieces;
    double y = free.ymin;
    for (const auto& [lo, hi] : blocked) {
      if (lo - y >= o.min_interval_m) pieces.push_back({y, lo, -1});
      y = std::max(y, hi);
    }
    if (free.ymax - y >= o.min_interval_m) pieces.push_back({y, free.ymax, -1});
    // Connectivity with the last slab: a cell goes on only one-to-one.
    const auto overlap = [&](const Piece& a, const Piece& b) {
      return std::min(a.yhi, b.yhi) - std::max(a.ylo, b.ylo) >= o.min_interval_m;
    };
    std::vector<int> right(prev.size(), 0), left(pieces.size(), 0);
    for (size_t a = 0; a < prev.size(); ++a) {
      for (size_t b = 0; b < pieces.size(); ++b) {
        if (overlap(prev[a], pieces[b])) {
          ++right[a];
          ++left[b];
        }
      }
    }
    for (size_t b = 0; b < pieces.size(); ++b) {
      for (size_t a = 0; a < prev.size(); ++a) {
        if (!overlap(prev[a], pieces[b])) continue;
        if (right[a] == 1 && left[b] == 1) pieces[b].cell = prev[a].cell;
      }
      if (pieces[b].cell < 0) {
        pieces[b].cell = static_cast<int>(cells.size());
        CoverageCell c;
        c.id = pieces[b].cell + 1;
        cells.push_back(c);
        for (size_t a = 0; a < prev.size(); ++a) {
          if (!overlap(prev[a], pieces[b])) continue;
          cells[static_cast<size_t>(prev[a].cell)].neighbours.push_back(pieces[b].cell);
          cells.back().neighbours.push_back(prev[a].cell);
        }
      }
      cells[static_cast<size_t>(pieces[b].cell)].slabs.push_back(
          {x0, x1, pieces[b].ylo, pieces[b].yhi});
    }
    prev = pieces;
  }
  if (static_cast<int>(cells.size()) > o.max_cells) {
    // Bounded: keep the largest cells.
    std::stable_sort(cells.begin(), cells.end(), [](const CoverageCell& a, const CoverageCell& b) {
      return a.area_m2() > b.area_m2();
    });
    cells.resize(static_cast<size_t>(o.max_cells));
    for (auto& c : cells) c.neighbours.clear();
  }
  return cells;
}

}  // namespace irslam::control
