// Coverage planning (control/coverage.h): the sweep of one cell and the
// covered-floor grid. The cell decomposition is in coverage_cells.cc, the plan
// (the cells' tour, whole or in steps) in coverage_plan.cc.
#include "control/coverage.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "control/room_geometry.h"

namespace irslam::control {

options::Table<CleaningOptions> CleaningKeys() {
  using O = CleaningOptions;
  static constexpr options::Key<O> kKeys[] = {
      {"cleaning_width_m", &O::cleaning_width_m, 0.05, 2, "m", "floor width cleaned in one pass"},
      {"overlap_m", &O::overlap_m, 0, 1, "m", "neighbouring lanes overlap by this"},
      {"clearance_m", &O::clearance_m, 0, 1, "m",
       "lanes keep the robot radius plus this from walls and furniture"},
      {"edge_clearance_m", &O::edge_clearance_m, 0, 1, "m",
       "the edge pass keeps the robot radius plus this from walls and furniture (at most clearance_m)"},
      {"bump_block_m", &O::bump_block_m, 0, 1, "m",
       "a remembered contact blocks the robot radius plus this round it"},
      {"max_bump_obstacles", &O::max_bump_obstacles, 0, 1000, "",
       "at most this many contacts (the latest) go into the plan"},
      {"min_interval_m", &O::min_interval_m, 0.0001, 1, "m",
       "free intervals and overlaps narrower than this do not count"},
      {"both_directions", &O::both_directions, 0, 0, "",
       "plan lanes along y and along x and keep the shorter (false: along y)"},
      {"edge_pass", &O::edge_pass, 0, 0, "",
       "go round each cell along its walls and furniture before its lanes"},
      {"max_cells", &O::max_cells, 1, 10000, "", "cells of the decomposition at most"},
      {"two_opt_rounds", &O::two_opt_rounds, 0, 1000, "", "improvement passes over the tour"},
      {"plan_work_per_period", &O::plan_work_per_period, 1000, 1e9, "",
       "coverage planning done per control period at most (at least one step), in work units (a grid cell "
       "examined, about a third of a distance: 3-5 ns here); the robot holds still until the plan is complete"},
      {"sweep_speed_mps", &O::sweep_speed_mps, 0.01, 2, "m/s", "speed along a lane"},
      {"k_cross", &O::k_cross, 0, 100, "rad/m",
       "lane following: heading correction per metre off the lane"},
      {"k_heading", &O::k_heading, 0.1, 20, "rad/s/rad", "turn rate per radian of heading error"},
      {"max_rate_rad_s", &O::max_rate_rad_s, 0.05, 10, "rad/s", "turn rate limit on the lanes"},
      {"turn_in_place_rad", &O::turn_in_place_rad, 0.05, 3.2, "rad",
       "heading error beyond this: turn on the spot"},
      {"waypoint_tolerance_m", &O::waypoint_tolerance_m, 0.005, 1, "m",
       "a route point is passed within this"},
      {"approach_gain", &O::approach_gain, 0.01, 100, "1/s",
       "before a route point the speed is at most gain times distance plus 0.03 m/s"},
      {"front_stop_m", &O::front_stop_m, 0, 1, "m",
       "an unmapped obstacle ahead within the robot radius plus this: plan round it"},
      {"coverage_cell_m", &O::coverage_cell_m, 0.01, 0.5, "m", "grid of the covered-floor estimate"},
      {"resume_overlap", &O::resume_overlap, 0.5, 1, "",
       "resuming a cleaning: a cell of the new plan at least this share inside the cells done before is "
       "done (the plan may be cut differently: contacts and objects change)"},
      {"resume_same_model_m", &O::resume_same_model_m, 0, 0.5, "m",
       "resuming a cleaning: when the room and every object lie within this of where the stopped cleaning "
       "planned them, the plan is made again from the stopped plan's room, objects and contacts (the same "
       "cells); otherwise from the current model and contacts (0: always)"},
      {"stuck_s", &O::stuck_s, 1, 3600, "s",
       "no 0.1 m of progress for this long while cleaning: the route point is given up"},
      {"boxed_in_contacts_m", &O::boxed_in_contacts_m, 0, 2, "m",
       "cleaning: no way found with remembered contacts this close: plan again without them (0: never)"},
      {"under_body_contacts_m", &O::under_body_contacts_m, 0, 0.5, "m",
       "cleaning: plans leave out remembered contacts closer than this to the robot, under its body (0: never)"},
      {"boxed_in_corners", &O::boxed_in_corners, 0, 0, "",
       "cleaning: no way found: plan again with mapped sides that meet at a corner extended only to it"},
      {"boxed_in_trail_m", &O::boxed_in_trail_m, 0, 100, "m",
       "cleaning: still no way: plan again along the robot's own path of the last this many metres (0: never)"},
      {"max_goal_failures", &O::max_goal_failures, 1, 1000, "",
       "route points given up in a row in one cell before the rest of it is reported unreachable"},
      {"no_plan_spot_m", &O::no_plan_spot_m, 0, 1, "m",
       "a route point that cannot be planned to, given up within this of the last such: not counted as a failure (0: counted)"},
      {"max_time_s", &O::max_time_s, 1, 1e6, "s", "cleaning plus going home, robot time"},
      {"home_tolerance_m", &O::home_tolerance_m, 0.01, 1, "m", "home is reached within this"},
      {"home_attempts", &O::home_attempts, 1, 100, "", "plans home before giving up"},
  };
  return kKeys;
}

namespace {

// The interval of the cell at x (the narrowest where x is on a slab boundary).
std::pair<double, double> IntervalAt(const CoverageCell& c, double x) {
  double lo = -std::numeric_limits<double>::infinity(), hi = -lo;
  for (const auto& s : c.slabs) {
    if (x >= s.x0 - 1e-7 && x <= s.x1 + 1e-7) {
      lo = std::max(lo, s.ylo);
      hi = std::min(hi, s.yhi);
    }
  }
  if (hi < lo) hi = lo = 0.5 * (lo + hi);  // a step wider than the overlap: meet halfway
  return {lo, hi};
}

// Along the lower (top = false) or upper boundary from xa to xb (the end points'
// y from IntervalAt), with the staircase's steps.
void Boundary(const CoverageCell& c, double xa, double xb, bool top,
              std::vector<Eigen::Vector2d>* out) {
  const auto y_of = [&](double x) {
    const auto [lo, hi] = IntervalAt(c, x);
    return top ? hi : lo;
  };
  out->emplace_back(xa, y_of(xa));
  const bool right = xb > xa;
  const size_t n = c.slabs.size();
  for (size_t k = 0; k + 1 < n; ++k) {
    const size_t i = right ? k : n - 2 - k;  // the boundary between slabs i and i+1
    const double xbnd = c.slabs[i].x1;
    if (!(right ? (xbnd > xa + 1e-7 && xbnd < xb - 1e-7) : (xbnd < xa - 1e-7 && xbnd > xb + 1e-7)))
      continue;
    const Slab& before = right ? c.slabs[i] : c.slabs[i + 1];
    const Slab& after = right ? c.slabs[i + 1] : c.slabs[i];
    const double y0 = top ? before.yhi : before.ylo, y1 = top ? after.yhi : after.ylo;
    if (std::abs(y0 - y1) < 1e-9) continue;
    // The step lies on the edge of the box that makes it.
    out->emplace_back(xbnd, y0);
    out->emplace_back(xbnd, y1);
  }
  out->emplace_back(xb, y_of(xb));
}

// Drops repeated points and the middle of collinear runs.
std::vector<Eigen::Vector2d> Simplify(const std::vector<Eigen::Vector2d>& in) {
  std::vector<Eigen::Vector2d> out;
  for (const auto& p : in) {
    if (!out.empty() && (p - out.back()).norm() < 1e-6) continue;
    if (out.size() >= 2) {
      const Eigen::Vector2d a = out[out.size() - 1] - out[out.size() - 2], b = p - out.back();
      if (std::abs(a.x() * b.y() - a.y() * b.x()) < 1e-9 && a.dot(b) > 0) {
        out.back() = p;
        continue;
      }
    }
    out.push_back(p);
  }
  return out;
}

// The lower (top = false) or upper boundary from x0 to x1 (left to right), pushed
// out by d: each slab's y by d away from the cell, each step's x by d towards the
// box that makes it. Steps pushed past each other (a slab narrower than 2 d)
// meet halfway.
void PushedBoundary(const CoverageCell& c, double d, bool top, std::vector<Eigen::Vector2d>* out) {
  const size_t n = c.slabs.size();
  const auto y_of = [&](const Slab& s) { return top ? s.yhi + d : s.ylo - d; };
  std::vector<double> xs;
  std::vector<std::pair<double, double>> ys;  // before, after each step
  for (size_t i = 0; i + 1 < n; ++i) {
    const double y0 = top ? c.slabs[i].yhi : c.slabs[i].ylo;
    const double y1 = top ? c.slabs[i + 1].yhi : c.slabs[i + 1].ylo;
    if (std::abs(y0 - y1) < 1e-9) continue;
    // The box is on the right where the boundary steps into the cell.
    const bool box_right = top ? y1 < y0 : y1 > y0;
    xs.push_back(c.slabs[i].x1 + (box_right ? d : -d));
    ys.emplace_back(y_of(c.slabs[i]), y_of(c.slabs[i + 1]));
  }
  const double xa = c.slabs.front().x0 - d, xb = c.slabs.back().x1 + d;
  for (size_t k = 0; k < xs.size(); ++k) {
    const double lo = k == 0 ? xa : xs[k - 1];
    if (xs[k] < lo) xs[k] = k == 0 ? xa : (xs[k - 1] = 0.5 * (xs[k - 1] + xs[k]));
  }
  if (!xs.empty() && xs.back() > xb) xs.back() = xb;
  out->emplace_back(xa, y_of(c.slabs.front()));
  for (size_t k = 0; k < xs.size(); ++k) {
    out->emplace_back(xs[k], ys[k].first);
    out->emplace_back(xs[k], ys[k].second);
  }
  out->emplace_back(xb, y_of(c.slabs.back()));
}

CoverageCell Mirrored(const CoverageCell& c, bool mx, bool my) {
  CoverageCell m = c;
  m.slabs.clear();
  for (const auto& s : c.slabs) {
    Slab t = s;
    if (mx) {
      t.x0 = -s.x1;
      t.x1 = -s.x0;
    }
    if (my) {
      t.ylo = -s.yhi;
      t.yhi = -s.ylo;
    }
    m.slabs.push_back(t);
  }
  if (mx) std::reverse(m.slabs.begin(), m.slabs.end());
  return m;
}

}  // namespace

std::vector<Eigen::Vector2d> SweepRoute(const CoverageCell& cell, double spacing, bool mirror_x,
                                        bool mirror_y, bool edge_pass, double edge_out) {
  const CoverageCell c = Mirrored(cell, mirror_x, mirror_y);
  std::vector<Eigen::Vector2d> r;
  if (c.slabs.empty()) return r;
  const double d = edge_pass ? std::max(0.0, edge_out) : 0.0;
  const double x0 = c.slabs.front().x0, x1 = c.slabs.back().x1, w = x1 - x0;
  // Lanes over the width the edge pass spans (its sides pushed out by d).
  const int n = w < 1e-3 ? 1 : static_cast<int>(std::ceil((w + 2 * d) / spacing - 1e-9)) + 1;
  if (n == 1) {
    const double x = 0.5 * (x0 + x1);
    const auto [lo, hi] = IntervalAt(c, x);
    r = {{x, lo}, {x, lo - d}, {x, hi + d}};
  } else {
    const auto lane_x = [&](int k) {
      if (d <= 0) return x0 + w * k / (n - 1);
      return std::clamp(x0 - d + (w + 2 * d) * k / (n - 1), x0, x1);
    };
    int first = 0, last = n - 1;
    if (edge_pass && d > 0) {
      // Edge pass pushed out: from the cell's corner out to the pushed one,
      // round along the lower boundary, the right side, the upper boundary,
      // down the left side and back into the corner.
      r.emplace_back(x0, IntervalAt(c, x0).first);
      std::vector<Eigen::Vector2d> up;
      PushedBoundary(c, d, false, &r);
      PushedBoundary(c, d, true, &up);
      r.insert(r.end(), up.rbegin(), up.rend());
      r.emplace_back(x0 - d, c.slabs.front().ylo - d);
      first = 1;
      last = n - 2;
    } else if (edge_pass) {
      // Edge pass: along the lower boundary, up the last lane, back along the
      // upper boundary, down the first lane; then the lanes in between.
      Boundary(c, x0, x1, false, &r);
      Boundary(c, x1, x0, true, &r);
      first = 1;
      last = n - 2;
    }
    r.emplace_back(x0, IntervalAt(c, x0).first);
    // The lanes, up and down, joined along the boundaries.
    bool at_top = false;
    double x = x0;
    for (int k = first; k <= last; ++k) {
      const double xk = lane_x(k);
      if (k > 0) Boundary(c, x, xk, at_top, &r);
      const auto [lo, hi] = IntervalAt(c, xk);
      if (k == 0) r.emplace_back(xk, at_top ? hi : lo);
      r.emplace_back(xk, at_top ? lo : hi);
      at_top = !at_top;
      x = xk;
    }
  }
  r = Simplify(r);
  for (auto& p : r) {
    if (mirror_x) p.x() = -p.x();
    if (mirror_y) p.y() = -p.y();
  }
  return r;
}

void CoverageGrid::Init(const Box& room, const std::vector<Box>& rects, double r, double cell_m) {
  Reset(room, r, cell_m);
  for (const Box& b : rects) AddTarget(b);
}

void CoverageGrid::Reset(const Box& room, double r, double cell_m) {
  room_ = room;
  cell_m_ = cell_m;
  radius_m_ = r;
  // Bounded by the room's size (a room up to 50 m across at the finest cell).
  nx_ = std::clamp(static_cast<int>(std::ceil(room.width() / cell_m)), 0, 4000);
  ny_ = std::clamp(static_cast<int>(std::ceil(room.height() / cell_m)), 0, 4000);
  state_.assign(static_cast<size_t>(nx_) * static_cast<size_t>(ny_), 0);
  target_ = covered_ = 0;
}

void CoverageGrid::AddTarget(const Box& b) {
  const Box& room = room_;
  const double cell_m = cell_m_, r = radius_m_;
  const Slab s{b.xmin, b.xmax, b.ymin, b.ymax};
  const int i0 = std::max(0, static_cast<int>((s.x0 - r - room.xmin) / cell_m));
  const int i1 = std::min(nx_ - 1, static_cast<int>((s.x1 + r - room.xmin) / cell_m));
  const int j0 = std::max(0, static_cast<int>((s.ylo - r - room.ymin) / cell_m));
  const int j1 = std::min(ny_ - 1, static_cast<int>((s.yhi + r - room.ymin) / cell_m));
  for (int i = i0; i <= i1; ++i) {
    for (int j = j0; j <= j1; ++j) {
      const double x = room.xmin + (i + 0.5) * cell_m, y = room.ymin + (j + 0.5) * cell_m;
      const double dx = std::max({s.x0 - x, 0.0, x - s.x1});
      const double dy = std::max({s.ylo - y, 0.0, y - s.yhi});
      uint8_t& st = state_[static_cast<size_t>(j) * static_cast<size_t>(nx_) + static_cast<size_t>(i)];
      if (st == 0 && std::hypot(dx, dy) <= r) {
        st = 1;
        ++target_;
      }
    }
  }
}

void CoverageGrid::Mark(const Eigen::Vector2d& p) {
  if (nx_ == 0 || ny_ == 0) return;
  const double r = radius_m_;
  const int i0 = std::max(0, static_cast<int>((p.x() - r - room_.xmin) / cell_m_));
  const int i1 = std::min(nx_ - 1, static_cast<int>((p.x() + r - room_.xmin) / cell_m_));
  const int j0 = std::max(0, static_cast<int>((p.y() - r - room_.ymin) / cell_m_));
  const int j1 = std::min(ny_ - 1, static_cast<int>((p.y() + r - room_.ymin) / cell_m_));
  for (int i = i0; i <= i1; ++i) {
    for (int j = j0; j <= j1; ++j) {
      const double x = room_.xmin + (i + 0.5) * cell_m_, y = room_.ymin + (j + 0.5) * cell_m_;
      uint8_t& st = state_[static_cast<size_t>(j) * static_cast<size_t>(nx_) + static_cast<size_t>(i)];
      if (st == 1 && std::hypot(x - p.x(), y - p.y()) <= r) {
        st = 2;
        ++covered_;
      }
    }
  }
}

void CoverageGrid::MarkInside(const std::vector<Eigen::Vector2d>& polygon) {
  if (nx_ == 0 || ny_ == 0 || polygon.size() < 3) return;
  const Box b = room_geometry::PolygonBounds(polygon);
  const int i0 = std::max(0, static_cast<int>((b.xmin - room_.xmin) / cell_m_));
  const int i1 = std::min(nx_ - 1, static_cast<int>((b.xmax - room_.xmin) / cell_m_));
  const int j0 = std::max(0, static_cast<int>((b.ymin - room_.ymin) / cell_m_));
  const int j1 = std::min(ny_ - 1, static_cast<int>((b.ymax - room_.ymin) / cell_m_));
  for (int i = i0; i <= i1; ++i) {
    for (int j = j0; j <= j1; ++j) {
      uint8_t& st = state_[static_cast<size_t>(j) * static_cast<size_t>(nx_) + static_cast<size_t>(i)];
      const Eigen::Vector2d c(room_.xmin + (i + 0.5) * cell_m_, room_.ymin + (j + 0.5) * cell_m_);
      if (st == 1 && room_geometry::InsidePolygon(polygon, c)) {
        st = 2;
        ++covered_;
      }
    }
  }
}

}  // namespace irslam::control
