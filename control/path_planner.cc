#include "control/path_planner.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <functional>
#include <limits>
#include <span>

namespace irslam::control {
namespace {

double SegmentDistance(const Eigen::Vector2d& p, const Obstacle& o) {
  return (p - ClosestPoint(o, p)).norm();
}

}  // namespace

options::Table<PlannerOptions> PlannerKeys() {
  using O = PlannerOptions;
  static constexpr options::Key<O> kKeys[] = {
      {"planner_resolution_m", &O::resolution_m, 0.01, 1, "m",
       "cell size of the go-to's planning grid"},
      {"planner_margin_m", &O::margin_m, 0, 10, "m",
       "the planning grid extends this far beyond the obstacles"},
  };
  return kKeys;
}

Eigen::Vector2d ClosestPoint(const Obstacle& o, const Eigen::Vector2d& p) {
  const Eigen::Vector2d d = o.b - o.a;
  const double l2 = d.squaredNorm();
  const double u = l2 > 0 ? std::clamp((p - o.a).dot(d) / l2, 0.0, 1.0) : 0.0;
  return o.a + u * d;
}

namespace {

// The planning grid: cells of resolution_m from lo, nx by ny.
struct Grid {
  Eigen::Vector2d lo;
  int nx = 0, ny = 0;
  double res = 0;
  Eigen::Vector2d Centre(int ix, int iy) const {
    return Eigen::Vector2d(lo.x() + ix * res, lo.y() + iy * res);
  }
  std::pair<int, int> Cell(const Eigen::Vector2d& p) const {
    return {static_cast<int>(std::lround((p.x() - lo.x()) / res)),
            static_cast<int>(std::lround((p.y() - lo.y()) / res))};
  }
};

// The cells of row iy that may lie within r of obstacle o: [x0, x1] (empty if
// x0 > x1). The points within r of a segment form a capsule, which is convex,
// so a row meets it in one interval: the hull of the row's intervals through
// the two end discs and the band between them, widened by a cell each side.
std::pair<int, int> RowSpan(const Obstacle& o, const Grid& grid, int iy, double r) {
  const double y = grid.lo.y() + iy * grid.res;
  double lo = 1e300, hi = -1e300;
  for (const Eigen::Vector2d& c : {o.a, o.b}) {  // the discs
    const double dy = y - c.y();
    if (std::abs(dy) > r) continue;
    const double w = std::sqrt(r * r - dy * dy);
    lo = std::min(lo, c.x() - w);
    hi = std::max(hi, c.x() + w);
  }
  const Eigen::Vector2d d = o.b - o.a;
  const double len = d.norm();
  if (len > 1e-12) {
    // The band: |cross(u, p - a)| <= r and 0 <= dot(u, p - a) <= len, u = d / len,
    // each linear in x on the row (or constant: then all x or none).
    const Eigen::Vector2d u = d / len;
    double blo = -1e300, bhi = 1e300;
    const auto clip = [&](double k, double c0, double lim_lo, double lim_hi) {  // lim_lo <= k x + c0 <= lim_hi
      if (std::abs(k) < 1e-12) {
        if (c0 < lim_lo || c0 > lim_hi) blo = 1e300;
        return;
      }
      const double x0 = (lim_lo - c0) / k, x1 = (lim_hi - c0) / k;
      blo = std::max(blo, std::min(x0, x1));
      bhi = std::min(bhi, std::max(x0, x1));
    };
    const double ry = y - o.a.y();
    clip(-u.y(), u.x() * ry + u.y() * o.a.x(), -r, r);  // cross(u, p - a) = u.x ry - u.y (x - ax)
    clip(u.x(), u.y() * ry - u.x() * o.a.x(), 0, len);  // dot(u, p - a) = u.x (x - ax) + u.y ry
    if (blo <= bhi) {
      lo = std::min(lo, blo);
      hi = std::max(hi, bhi);
    }
  }
  if (lo > hi) return {1, 0};
  return {static_cast<int>(std::floor((lo - grid.lo.x()) / grid.res)) - 1,
          static_cast<int>(std::ceil((hi - grid.lo.x()) / grid.res)) + 1};
}

// Clearance of each cell: the distance to the nearest obstacle, up to the
// inflation (*out holds the clearances so far, lowered here where these
// obstacles are nearer). Each obstacle visits the cells of its bounding box row by row,
// only where the row can come within the inflation (RowSpan): the same minimum
// as over the whole box (a cell farther off keeps the inflation either way),
// without the distance of every cell of a long diagonal wall's box.
int64_t AddClearances(std::span<const Obstacle> obstacles, const Grid& grid, double inflation_m,
                      std::vector<float>* out) {
  int64_t cells = 0;
  const int nx = grid.nx, ny = grid.ny;
  std::vector<float>& clear = *out;
  for (const auto& ob : obstacles) {
    // Only cells near the obstacle's bounding box can be blocked by it.
    const Eigen::Vector2d a = ob.a.cwiseMin(ob.b).array() - inflation_m;
    const Eigen::Vector2d b = ob.a.cwiseMax(ob.b).array() + inflation_m;
    const auto [x0, y0] = grid.Cell(a);
    const auto [x1, y1] = grid.Cell(b);
    for (int iy = std::max(0, y0); iy <= std::min(ny - 1, y1); ++iy) {
      const auto [s0, s1] = RowSpan(ob, grid, iy, inflation_m);
      const int lo = std::max({0, x0, s0}), hi = std::min({nx - 1, x1, s1});
      for (int ix = lo; ix <= hi; ++ix) {
        auto& c = clear[static_cast<size_t>(iy * nx + ix)];
        c = std::min(c, static_cast<float>(SegmentDistance(grid.Centre(ix, iy), ob)));
      }
      cells += std::max(0, hi - lo + 1);
    }
  }
  return cells;
}

bool SameObstacles(std::span<const Obstacle> a, const std::vector<Obstacle>& b) {
  if (a.size() != b.size()) return false;
  for (size_t i = 0; i < a.size(); ++i) {
    if (a[i].a != b[i].a || a[i].b != b[i].b) return false;
  }
  return true;
}

}  // namespace

// hypot(dx, dy) exactly as the search always computed it (hypot takes absolute
// values, so the table by |dx|, |dy| gives the same numbers), computed once.
double PathPlanner::H(int dx, int dy) {
  const int ax = std::abs(dx), ay = std::abs(dy);
  double& h = hypot_[Tiled(ax, ay, hypot_tiles_x_)];
  if (h == 0) h = std::hypot(dx, dy);  // (0 at 0, 0 is recomputed: also 0)
  return h;
}

// A* (8-connected) from cell s_ = (sx_, sy_) to goal_i_ = (gx_, gy_): each
// cell's predecessor and cost in cells_ (From, G). The same search as
// ever; the open list (control/quad_heap.h) gives up its (f, cell) pairs in
// the order std::priority_queue with std::greater did, so cells come off it in
// the same order. Runs at most max_pops pops; true once the
// search has ended (the goal popped or the queue empty).
bool PathPlanner::SearchSome(int64_t max_pops, int64_t* pops) {
  const PlannerOptions& o = o_;
  const int nx = geo_.nx, ny = geo_.ny;
  const int sx = sx_, sy = sy_, gx = gx_, gy = gy_, goal_i = goal_i_;
  const auto h = [&](int i) { return H(i % nx - gx, i / nx - gy); };
  const int dx[8] = {1, -1, 0, 0, 1, 1, -1, -1}, dy[8] = {0, 0, 1, -1, 1, -1, 1, -1};
  // The clearances are floats, those beyond the inflation stored as the float
  // nearest it, which may lie below the double (0.19 does): compared as floats.
  const float inflation = static_cast<float>(o.inflation_m);
  for (int64_t popped = 0; !open_.empty(); ++popped) {
    if (popped >= max_pops) return false;
    const auto [f, i] = open_.pop();
    ++stats_.pops;
    ++search_pops_;
    ++*pops;
    if (i == goal_i) return true;
    const int ix = i % nx, iy = i / nx;
    const double gi = G(ix, iy);
    if (f > gi + h(i) + 1e-9) continue;
    for (int k = 0; k < 8; ++k) {
      const int jx = ix + dx[k], jy = iy + dy[k];
      if (jx < 0 || jy < 0 || jx >= nx || jy >= ny) continue;
      const int j = jy * nx + jx;
      // Cells within the inflation may be crossed only near the start, to get out
      // of a tight spot; within hard_m only moving away from the obstacle (the
      // robot may stand that close to where a mapped side is assumed to go on).
      const float cj = clear_[static_cast<size_t>(j)];
      if (cj < inflation && !OnTrail(j)) {
        if (H(jx - sx, jy - sy) * o.resolution_m > o.inflation_m + o.resolution_m) continue;
        if (cj < o.hard_m && cj < clear_[static_cast<size_t>(i)]) continue;
      }
      const double c = gi + (k < 4 ? 1.0 : M_SQRT2);
      CellState& cj_state = Cell(jx, jy);
      if (c < (cj_state.stamp == gen_ ? cj_state.g : 1e18)) {
        cj_state = {c, i, gen_};
        open_.push({c + h(j), j});
      }
    }
  }
  return true;
}

std::optional<std::vector<Eigen::Vector2d>> PathPlanner::Plan(
    const std::vector<Obstacle>& obstacles, const Eigen::Vector2d& start,
    const Eigen::Vector2d& goal, const PlannerOptions& o) {
  int64_t pops = 0;
  Progress p = Start(obstacles, start, goal, o);
  if (p == Progress::kRunning) p = Continue(std::numeric_limits<int64_t>::max(), &pops);
  if (p != Progress::kFound) return std::nullopt;
  return path_;
}

// The distance table covers offsets up to nx, ny.
void PathPlanner::GrowHypot(int nx, int ny) {
  if (nx <= hypot_nx_ && ny <= hypot_ny_) return;
  // Grown with slack, the distances computed so far kept: a grid a cell
  // larger (the robot moved, a line grew) neither reallocates nor recomputes.
  const int new_nx = std::max(nx + nx / 4, hypot_nx_), new_ny = std::max(ny + ny / 4, hypot_ny_);
  const int new_tiles_x = Tiles(new_nx);
  LazyArray<double> grown;
  grown.Reserve(static_cast<size_t>(new_tiles_x) * static_cast<size_t>(Tiles(new_ny)) << (2 * kTileBits));
  // Only the distances computed are copied: the rest of the new table stays
  // untouched (reading the old one's untouched pages makes nothing resident).
  for (int ay = 0; ay < hypot_ny_; ++ay) {
    for (int ax = 0; ax < hypot_nx_; ++ax) {
      const double h = hypot_[Tiled(ax, ay, hypot_tiles_x_)];
      if (h != 0) grown[Tiled(ax, ay, new_tiles_x)] = h;
    }
  }
  hypot_ = std::move(grown);
  hypot_nx_ = new_nx;
  hypot_ny_ = new_ny;
  hypot_tiles_x_ = new_tiles_x;
}

// The clearances: those of the static obstacles (the first n_static) kept
// while they and the grid are the same, the transient ones (what the sensors
// see now) added to a copy. The minimum over all obstacles, as one pass over
// them all gives it, number for number. A grid first made for new static
// obstacles is made in one pass over all of them; the static part alone is
// made (and kept) at the next call that needs it, so that a new grid's page
// faults fall in two calls, not one. start_cells_ counts the work: the cells
// filled and evaluated, and twice the cells newly allocated (a fresh page
// costs about as much as computing its cells twice over).
void PathPlanner::UpdateClearances(const std::vector<Obstacle>& obstacles, size_t n_static,
                                   const Geometry& geo, double inflation_m) {
  const Grid grid{geo.lo, geo.nx, geo.ny, geo.res};
  const size_t n = static_cast<size_t>(geo.nx) * static_cast<size_t>(geo.ny);
  const float fill = static_cast<float>(inflation_m);
  const auto fresh = [&](const std::vector<float>& v) {
    return n > v.capacity() ? 2 * static_cast<int64_t>(n - v.capacity()) : 0;
  };
  const size_t n_fixed = std::min(n_static, obstacles.size());
  const std::span<const Obstacle> fixed(obstacles.data(), n_fixed);
  const std::span<const Obstacle> transient(obstacles.data() + n_fixed, obstacles.size() - n_fixed);
  const bool same_fixed = geo == geo_ && clear_inflation_m_ == inflation_m && SameObstacles(fixed, obstacles_);
  if (same_fixed && SameObstacles(transient, transient_)) {
    ++stats_.clearance_reused;
    return;
  }
  failed_valid_ = false;
  transient_.assign(transient.begin(), transient.end());
  if (!same_fixed) {
    geo_ = geo;
    clear_inflation_m_ = inflation_m;
    obstacles_.assign(fixed.begin(), fixed.end());
    fixed_valid_ = false;
    start_cells_ += fresh(clear_) + static_cast<int64_t>(n);
    clear_.assign(n, fill);
    start_cells_ += AddClearances(obstacles, grid, inflation_m, &clear_);
    return;
  }
  if (fixed_valid_) {
    ++stats_.static_clearance_reused;
  } else {
    start_cells_ += fresh(fixed_clear_) + static_cast<int64_t>(n);
    fixed_clear_.assign(n, fill);
    start_cells_ += AddClearances(fixed, grid, inflation_m, &fixed_clear_);
    fixed_valid_ = true;
  }
  start_cells_ += fresh(clear_);
  clear_ = fixed_clear_;
  start_cells_ += AddClearances(transient, grid, inflation_m, &clear_);
}

PathPlanner::Progress PathPlanner::Start(const std::vector<Obstacle>& obstacles,
                                         const Eigen::Vector2d& start, const Eigen::Vector2d& goal,
                                         const PlannerOptions& o, size_t n_static) {
  ++stats_.plans;
  running_ = false;
  start_cells_ = 0;
  Eigen::Vector2d lo = start.cwiseMin(goal), hi = start.cwiseMax(goal);
  for (const auto& ob : obstacles) {
    lo = lo.cwiseMin(ob.a).cwiseMin(ob.b);
    hi = hi.cwiseMax(ob.a).cwiseMax(ob.b);
  }
  lo.array() -= o.margin_m;
  hi.array() += o.margin_m;
  Geometry geo;
  geo.lo = lo;
  geo.res = o.resolution_m;
  geo.nx = static_cast<int>(std::ceil((hi.x() - lo.x()) / o.resolution_m)) + 1;
  geo.ny = static_cast<int>(std::ceil((hi.y() - lo.y()) / o.resolution_m)) + 1;
  const int nx = geo.nx, ny = geo.ny;
  if (static_cast<long>(nx) * ny > 4'000'000) {
    ++stats_.failed;
    return Progress::kFailed;
  }
  UpdateClearances(obstacles, n_static, geo, o.inflation_m);
  const Grid grid{geo.lo, nx, ny, geo.res};
  GrowHypot(nx, ny);
  const auto [sx, sy] = grid.Cell(start);
  const auto [gx, gy] = grid.Cell(goal);
  if (gx < 0 || gy < 0 || gx >= nx || gy >= ny ||
      clear_[static_cast<size_t>(gy * nx + gx)] < static_cast<float>(o.inflation_m)) {
    ++stats_.failed;
    return Progress::kFailed;
  }
  const int s = sy * nx + sx, goal_i = gy * nx + gx;
  // (A new trail invalidates it: SetFreeTrail.)
  if (failed_valid_ && failed_start_ == s && failed_hard_m_ == o.hard_m && G(gx, gy) >= 1e18) {
    // The last search from here visited every cell that can be reached: not this one.
    ++stats_.failed;
    ++stats_.known_unreachable;
    return Progress::kFailed;
  }
  ++stats_.searches;
  failed_valid_ = false;  // the costs are about to be overwritten
  sx_ = sx, sy_ = sy, gx_ = gx, gy_ = gy, s_ = s, goal_i_ = goal_i;
  o_ = o;
  start_ = start;
  goal_ = goal;
  tiles_x_ = Tiles(nx);
  cells_.Reserve(static_cast<size_t>(tiles_x_) * static_cast<size_t>(Tiles(ny)) << (2 * kTileBits));
  if (++gen_ == 0) {  // wrapped: no stamp may look current
    for (size_t k = 0; k < cells_.n; ++k) cells_[k].stamp = 0;
    gen_ = 1;
  }
  MarkTrail();
  open_.clear();
  Cell(sx, sy) = {0, -1, gen_};
  open_.push({H(sx - gx, sy - gy), s});
  search_pops_ = 0;
  running_ = true;
  return Progress::kRunning;
}

void PathPlanner::SetFreeTrail(const std::vector<Eigen::Vector2d>& trail, double max_step_m) {
  if (trail.empty() && trail_.empty()) return;
  trail_.clear();
  for (size_t k = 0; k < trail.size(); ++k) {
    if (k > 0 && (trail[k] - trail[k - 1]).norm() > max_step_m)
      trail_.push_back(Eigen::Vector2d::Constant(std::numeric_limits<double>::quiet_NaN()));
    trail_.push_back(trail[k]);
  }
  failed_valid_ = false;  // a failed search's reach says nothing about one along another trail
}

void PathPlanner::MarkTrail() {
  if (trail_.empty()) return;
  const Grid grid{geo_.lo, geo_.nx, geo_.ny, geo_.res};
  const size_t n = static_cast<size_t>(geo_.nx) * static_cast<size_t>(geo_.ny);
  if (trail_mark_.size() < n) trail_mark_.assign(n, 0);
  if (gen_ == 1) std::fill(trail_mark_.begin(), trail_mark_.end(), 0u);  // the stamps wrapped
  const auto mark = [&](const Eigen::Vector2d& p) {
    const auto [cx, cy] = grid.Cell(p);
    for (int y = std::max(0, cy - 1); y <= std::min(geo_.ny - 1, cy + 1); ++y)
      for (int x = std::max(0, cx - 1); x <= std::min(geo_.nx - 1, cx + 1); ++x)
        trail_mark_[static_cast<size_t>(y) * static_cast<size_t>(geo_.nx) + static_cast<size_t>(x)] = gen_;
  };
  for (size_t k = 0; k < trail_.size(); ++k) {
    if (std::isnan(trail_[k].x())) continue;
    if (k == 0 || std::isnan(trail_[k - 1].x())) {
      mark(trail_[k]);
      continue;
    }
    // The segment from the previous point, every half cell.
    const Eigen::Vector2d a = trail_[k - 1], d = trail_[k] - a;
    const int steps = std::max(1, static_cast<int>(std::ceil(d.norm() / (0.5 * geo_.res))));
    for (int i = 1; i <= steps; ++i) mark(a + d * (static_cast<double>(i) / steps));
  }
  start_cells_ += static_cast<int64_t>(trail_.size()) * 9 * 2;
}

PathPlanner::Progress PathPlanner::Continue(int64_t max_pops, int64_t* pops) {
  if (!running_) return Progress::kFailed;
  if (!SearchSome(max_pops, pops)) return Progress::kRunning;
  running_ = false;
  stats_.max_pops = std::max(stats_.max_pops, search_pops_);
  return Finish();
}

PathPlanner::Progress PathPlanner::Finish() {
  const int nx = geo_.nx, s = s_, goal_i = goal_i_;
  if (From(goal_i) < 0 && goal_i != s) {
    failed_valid_ = true;
    failed_start_ = s;
    failed_hard_m_ = o_.hard_m;
    ++stats_.failed;
    return Progress::kFailed;
  }
  std::vector<Eigen::Vector2d> cells;
  for (int i = goal_i; i != -1; i = From(i))
    cells.push_back(Eigen::Vector2d(geo_.lo.x() + (i % nx) * geo_.res, geo_.lo.y() + (i / nx) * geo_.res));
  std::reverse(cells.begin(), cells.end());
  // Keep the corners only.
  path_ = {start_};
  for (size_t i = 1; i + 1 < cells.size(); ++i) {
    const Eigen::Vector2d d0 = cells[i] - cells[i - 1], d1 = cells[i + 1] - cells[i];
    if ((d0 - d1).norm() > 1e-9) path_.push_back(cells[i]);
  }
  path_.push_back(goal_);
  return Progress::kFound;
}

std::optional<std::vector<Eigen::Vector2d>> PlanPath(const std::vector<Obstacle>& obstacles,
                                                     const Eigen::Vector2d& start,
                                                     const Eigen::Vector2d& goal,
                                                     const PlannerOptions& o) {
  PathPlanner planner;
  return planner.Plan(obstacles, start, goal, o);
}

bool PathClear(const std::vector<Obstacle>& obstacles, const std::vector<Eigen::Vector2d>& path,
               double clearance_m, double skip_m) {
  double along = 0;
  for (size_t i = 0; i + 1 < path.size(); ++i) {
    const Eigen::Vector2d d = path[i + 1] - path[i];
    const double len = d.norm();
    for (double u = 0; u <= len; u += 0.05) {
      if (along + u >= skip_m) {
        const Eigen::Vector2d p = path[i] + (len > 0 ? u / len : 0.0) * d;
        for (const auto& ob : obstacles) {
          if (SegmentDistance(p, ob) < clearance_m) return false;
        }
      }
    }
    along += len;
  }
  return true;
}

double PathLength(const std::vector<Eigen::Vector2d>& path) {
  double l = 0;
  for (size_t i = 0; i + 1 < path.size(); ++i) l += (path[i + 1] - path[i]).norm();
  return l;
}

}  // namespace irslam::control
