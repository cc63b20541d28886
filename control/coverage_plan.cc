// Coverage planning (control/coverage.h), the plan: the cells of one
// orientation (coverage_cells.cc), their tour (greedy nearest neighbour, then
// 2-opt rounds) and each cell's sweep route (coverage.cc), whole
// (PlanCoverage) or in bounded steps (CoveragePlanner).
#include "control/coverage.h"

#include <algorithm>
#include <optional>

namespace irslam::control {

namespace {

double Gap(const Eigen::Vector2d& a, const Eigen::Vector2d& b) { return (a - b).norm(); }

Box Swap(const Box& b) { return {b.ymin, b.xmin, b.ymax, b.xmax}; }
Eigen::Vector2d Swap(const Eigen::Vector2d& p) { return {p.y(), p.x()}; }

// The plan's frame and constants and its cells, with lanes along y (swap: along
// x, by planning in the frame with x and y swapped; the routes are swapped back
// by EndRoutes). *start: the robot's place in that frame.
CoveragePlan DecomposeOriented(Box room, std::vector<Box> objects, std::vector<Eigen::Vector2d> bumps,
                               Eigen::Vector2d* start, double radius, const CleaningOptions& o, bool swap) {
  if (swap) {
    room = Swap(room);
    for (auto& b : objects) b = Swap(b);
    for (auto& p : bumps) p = Swap(p);
    *start = Swap(*start);
  }
  CoveragePlan plan;
  plan.swapped = swap;
  const double g = radius + o.clearance_m;
  plan.inflation_m = g;
  plan.edge_out_m = o.edge_pass ? std::max(0.0, o.clearance_m - o.edge_clearance_m) : 0.0;
  plan.lane_spacing_m = std::max(0.02, o.cleaning_width_m - o.overlap_m);
  plan.free = {room.xmin + g, room.ymin + g, room.xmax - g, room.ymax - g};
  std::vector<Box> obstacles;
  for (const auto& b : objects) obstacles.push_back({b.xmin - g, b.ymin - g, b.xmax + g, b.ymax + g});
  const double gb = radius + o.bump_block_m;
  for (size_t i = FirstPlannedContact(bumps.size(), o); i < bumps.size(); ++i) {
    const auto& p = bumps[i];
    obstacles.push_back({p.x() - gb, p.y() - gb, p.x() + gb, p.y() + gb});
  }
  plan.cells = Decompose(plan.free, obstacles, o);
  return plan;
}

// The tour over the cells' middles: greedy nearest neighbour from the robot ...
std::vector<Eigen::Vector2d> CellMiddles(const std::vector<CoverageCell>& cells) {
  std::vector<Eigen::Vector2d> mid(cells.size());
  for (size_t i = 0; i < cells.size(); ++i) {
    const auto& s = cells[i].slabs;
    mid[i] = {0.5 * (s.front().x0 + s.back().x1), 0.5 * (s[s.size() / 2].ylo + s[s.size() / 2].yhi)};
  }
  return mid;
}

std::vector<int> GreedyTour(const std::vector<Eigen::Vector2d>& mid, const Eigen::Vector2d& start) {
  const size_t n = mid.size();
  std::vector<int> order;
  std::vector<bool> used(n, false);
  Eigen::Vector2d at = start;
  for (size_t k = 0; k < n; ++k) {
    size_t best = n;
    for (size_t i = 0; i < n; ++i) {
      if (!used[i] && (best == n || Gap(at, mid[i]) < Gap(at, mid[best]))) best = i;
    }
    used[best] = true;
    order.push_back(static_cast<int>(best));
    at = mid[best];
  }
  return order;
}

// ... then 2-opt on the open path from the robot (segment reversals): one
// round; false if it found nothing better.
bool TwoOptRound(const std::vector<Eigen::Vector2d>& mid, const Eigen::Vector2d& start, std::vector<int>* order) {
  const auto pos = [&](int k) { return k < 0 ? start : mid[static_cast<size_t>((*order)[static_cast<size_t>(k)])]; };
  bool better = false;
  const int m = static_cast<int>(mid.size());
  for (int i = 0; i < m - 1; ++i) {
    for (int j = i + 1; j < m; ++j) {
      // Reverse order[i..j]: edges (i-1,i) and (j,j+1) become (i-1,j) and (i,j+1).
      double before = Gap(pos(i - 1), pos(i)), after = Gap(pos(i - 1), pos(j));
      if (j + 1 < m) {
        before += Gap(pos(j), pos(j + 1));
        after += Gap(pos(i), pos(j + 1));
      }
      if (after < before - 1e-9) {
        std::reverse(order->begin() + i, order->begin() + j + 1);
        better = true;
      }
    }
  }
  return better;
}

// The route of the tour's next cell, entered from the corner nearest *at
// (where the last route ended; moved to where this one ends).
void AddRoute(CoveragePlan* plan, int ci, const CleaningOptions& o, Eigen::Vector2d* at) {
  std::vector<Eigen::Vector2d> best;
  for (int corner = 0; corner < 4; ++corner) {
    auto r = SweepRoute(plan->cells[static_cast<size_t>(ci)], plan->lane_spacing_m, corner & 1, corner & 2,
                        o.edge_pass, plan->edge_out_m);
    if (best.empty() || Gap(*at, r.front()) < Gap(*at, best.front())) best = std::move(r);
  }
  plan->transit_length_m += Gap(*at, best.front());
  for (size_t k = 1; k < best.size(); ++k) plan->route_length_m += Gap(best[k - 1], best[k]);
  *at = best.back();
  plan->routes.push_back(std::move(best));
}

// The routes back in the map frame.
void EndRoutes(CoveragePlan* plan) {
  if (!plan->swapped) return;
  for (auto& r : plan->routes)
    for (auto& p : r) p = Swap(p);
}

// The whole plan of one orientation, in one go.
CoveragePlan PlanOriented(const Box& room, const std::vector<Box>& objects, const std::vector<Eigen::Vector2d>& bumps,
                          Eigen::Vector2d start, double radius, const CleaningOptions& o, bool swap) {
  CoveragePlan plan = DecomposeOriented(room, objects, bumps, &start, radius, o, swap);
  if (plan.cells.empty()) return plan;
  const std::vector<Eigen::Vector2d> mid = CellMiddles(plan.cells);
  std::vector<int> order = GreedyTour(mid, start);
  for (int round = 0; round < o.two_opt_rounds; ++round) {
    if (!TwoOptRound(mid, start, &order)) break;
  }
  Eigen::Vector2d at = start;
  for (int ci : order) AddRoute(&plan, ci, o, &at);
  plan.order = std::move(order);
  EndRoutes(&plan);
  return plan;
}

// Lanes along x (a) or along y (b): the shorter, ties to along y.
bool Shorter(const CoveragePlan& a, const CoveragePlan& b) {
  const auto cost = [](const CoveragePlan& p) { return p.route_length_m + p.transit_length_m; };
  return cost(a) < cost(b) - 1e-9;
}

}  // namespace

std::vector<Box> CoveragePlan::FreeRects() const {
  std::vector<Box> out;
  for (const auto& c : cells) {
    for (const auto& s : c.slabs) {
      const Box b{s.x0, s.ylo, s.x1, s.yhi};
      out.push_back(swapped ? Swap(b) : b);
    }
  }
  return out;
}

CoveragePlan PlanCoverage(const Box& room, const std::vector<Box>& objects,
                          const std::vector<Eigen::Vector2d>& bumps, const Eigen::Vector2d& start,
                          double radius, const CleaningOptions& o) {
  CoveragePlan along_y = PlanOriented(room, objects, bumps, start, radius, o, false);
  if (!o.both_directions) return along_y;
  CoveragePlan along_x = PlanOriented(room, objects, bumps, start, radius, o, true);
  return Shorter(along_x, along_y) ? along_x : along_y;
}

void CoveragePlanner::Start(const Box& room, const std::vector<Box>& objects,
                            const std::vector<Eigen::Vector2d>& bumps, const Eigen::Vector2d& start, double radius,
                            const CleaningOptions& o, std::optional<bool> lanes_along_x) {
  room_ = room;
  objects_ = objects;
  bumps_ = bumps;
  start_ = start;
  radius_m_ = radius;
  options_ = o;
  swap_ = lanes_along_x.value_or(false);
  one_orientation_ = lanes_along_x.has_value();
  plan_ = {};
  along_y_.reset();
  steps_ = 0;
  work_ = 0;
  stage_ = Stage::kDecompose;
}

bool CoveragePlanner::Step() {
  if (stage_ == Stage::kIdle || stage_ == Stage::kDone) return stage_ == Stage::kDone;
  ++steps_;
  const double n = static_cast<double>(plan_.cells.size());
  switch (stage_) {
    case Stage::kDecompose: {
      const double m =
          static_cast<double>(objects_.size() + bumps_.size() - FirstPlannedContact(bumps_.size(), options_));
      work_ += 3 * (2 + 2 * m) * (m + 1);  // the slabs' x-edges against every box
      oriented_start_ = start_;
      plan_ = DecomposeOriented(room_, objects_, bumps_, &oriented_start_, radius_m_, options_, swap_);
      if (plan_.cells.empty()) {
        EndOrientation();
      } else {
        mid_ = CellMiddles(plan_.cells);
        stage_ = Stage::kGreedy;
      }
      break;
    }
    case Stage::kGreedy:
      work_ += 3 * n * n;
      plan_.order = GreedyTour(mid_, oriented_start_);
      round_ = 0;
      stage_ = options_.two_opt_rounds > 0 ? Stage::kTwoOpt : Stage::kRoutes;
      next_ = 0;
      at_ = oriented_start_;
      break;
    case Stage::kTwoOpt:
      work_ += 6 * n * n;
      if (!TwoOptRound(mid_, oriented_start_, &plan_.order) || ++round_ >= options_.two_opt_rounds)
        stage_ = Stage::kRoutes;
      break;
    case Stage::kRoutes: {
      // Four candidate routes: their lanes, each looking its interval up in every slab.
      const CoverageCell& c = plan_.cells[static_cast<size_t>(plan_.order[next_])];
      const double lanes = (c.slabs.back().x1 - c.slabs.front().x0) / plan_.lane_spacing_m + 3;
      work_ += 4 * 6 * lanes * static_cast<double>(c.slabs.size());
      AddRoute(&plan_, plan_.order[next_], options_, &at_);
      if (++next_ >= plan_.order.size()) {
        EndRoutes(&plan_);
        EndOrientation();
      }
      break;
    }
    case Stage::kIdle:
    case Stage::kDone:
      break;
  }
  return stage_ == Stage::kDone;
}

void CoveragePlanner::EndOrientation() {
  if (!swap_ && options_.both_directions && !one_orientation_) {
    along_y_ = std::move(plan_);
    plan_ = {};
    swap_ = true;
    stage_ = Stage::kDecompose;
    return;
  }
  if (along_y_ && !Shorter(plan_, *along_y_)) plan_ = std::move(*along_y_);
  along_y_.reset();
  stage_ = Stage::kDone;
}

CoveragePlan CoveragePlanner::Take() {
  stage_ = Stage::kIdle;
  return std::move(plan_);
}

}  // namespace irslam::control
