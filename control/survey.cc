#include "control/survey.h"

#include <algorithm>
#include <cmath>

namespace irslam::control {

options::Table<SurveyOptions> SurveyKeys() {
  using O = SurveyOptions;
  static constexpr options::Key<O> kKeys[] = {
      {"survey_centre", &O::survey_centre, 0, 0, "",
       "look round from inside the room, first from its middle"},
      {"max_surveys", &O::max_surveys, 0, 100, "", "... from at most this many points"},
      {"survey_range_m", &O::survey_range_m, 0.1, 5, "m",
       "room within this of the trajectory counts as seen"},
      {"survey_min_unseen_m2", &O::survey_min_unseen_m2, 0, 100, "m^2",
       "a survey point must see at least this much unseen room"},
      {"survey_middle_search_m", &O::survey_middle_search_m, 0, 10, "m",
       "the first survey point is searched this far round the middle"},
      {"survey_middle_step_m", &O::survey_middle_step_m, 0.01, 10, "m",
       "... on rings this far apart"},
      {"survey_cell_m", &O::survey_cell_m, 0.05, 2, "m", "grid cell of the unseen-room count"},
      {"survey_object_margin_m", &O::survey_object_margin_m, 0, 2, "m",
       "cells this close to a known object are not counted as room"},
      {"survey_wall_margin_m", &O::survey_wall_margin_m, 0, 2, "m",
       "survey points keep this from the walls"},
      {"survey_trajectory_stride", &O::survey_trajectory_stride, 1, 100, "",
       "every this-many trajectory points count as seen from"},
      {"survey_candidates", &O::survey_candidates, 1, 1000, "",
       "best survey points tried before giving up"},
      {"survey_turn_rate_rad_s", &O::survey_turn_rate_rad_s, 0.05, 10, "rad/s",
       "turn rate looking round"},
      {"survey_turn_margin_rad", &O::survey_turn_margin_rad, 0, 3.2, "rad",
       "looking round: a full turn plus this"},
  };
  return kKeys;
}

void Survey::Reset() {
  done_ = 0;
  points_.clear();
}

bool Survey::Wanted(const EnvironmentModel& m) const {
  return options_.survey_centre && done_ < options_.max_surveys && m.room.box.has_value();
}

namespace {

Eigen::Vector2d Middle(const Box& r) { return {0.5 * (r.xmin + r.xmax), 0.5 * (r.ymin + r.ymax)}; }

}  // namespace

std::vector<Eigen::Vector2d> Survey::MiddlePoints(const Box& room) const {
  std::vector<Eigen::Vector2d> out;
  if (done_ != 0) return out;
  const Eigen::Vector2d middle = Middle(room);
  for (double radius = 0; radius < options_.survey_middle_search_m;
       radius += options_.survey_middle_step_m) {
    for (int k = 0; k < (radius > 0 ? 8 : 1); ++k) {
      out.push_back(middle +
                    radius * Eigen::Vector2d(std::cos(k * M_PI / 4), std::sin(k * M_PI / 4)));
    }
  }
  return out;
}

namespace {

// The survey's count grid: the cell centres exactly as the ranking always
// computed them (x and y stepped by repeated addition from the room's corner),
// and the index window round a point that holds every centre within `range`
// of it (two cells of slack on each side: the window only limits the loops;
// the test itself is the same distance as ever).
struct CountGrid {
  std::vector<double> xs, ys;
  static std::vector<double> Centres(double lo, double hi, double cell) {
    std::vector<double> out;
    for (double v = lo + 0.5 * cell; v < hi; v += cell) out.push_back(v);
    return out;
  }
  static std::pair<int, int> Window(const std::vector<double>& c, double centre, double range, double cell) {
    if (c.empty()) return {0, -1};
    const int lo = static_cast<int>(std::floor((centre - range - c.front()) / cell)) - 2;
    const int hi = static_cast<int>(std::ceil((centre + range - c.front()) / cell)) + 2;
    return {std::max(0, lo), std::min(static_cast<int>(c.size()) - 1, hi)};
  }
};

}  // namespace

// The ranking is bounded by the room's cells times a window of (2 range / cell
// + 5)^2 cells: each trajectory point marks the cells it saw, and each candidate
// counts the unseen cells in its window (issue 15: it used to compare every
// cell with every trajectory point and every candidate with every unseen cell,
// 26 ms in a 16 x 12 m room). The same points in the same order as before: the
// same centres, the same distance tests, the same candidate order.
std::vector<Eigen::Vector2d> Survey::RankedPoints(const Box& r, const std::vector<TimedPose>& traj,
                                                  const std::vector<ObjectModel>& objects) const {
  const auto& o = options_;
  const double cell = o.survey_cell_m;
  const double range = o.survey_range_m;
  const double margin = o.survey_object_margin_m, wall = o.survey_wall_margin_m;
  const size_t stride = static_cast<size_t>(o.survey_trajectory_stride);
  CountGrid grid{CountGrid::Centres(r.xmin, r.xmax, cell), CountGrid::Centres(r.ymin, r.ymax, cell)};
  const int nx = static_cast<int>(grid.xs.size()), ny = static_cast<int>(grid.ys.size());
  const auto at = [ny](int i, int j) { return static_cast<size_t>(i) * static_cast<size_t>(ny) + static_cast<size_t>(j); };
  // Cells of the room (map frame) not yet seen: farther than the range from
  // every trajectory point, and not inside a known object.
  std::vector<char> unseen(static_cast<size_t>(nx) * static_cast<size_t>(ny), 1);
  std::vector<Eigen::Vector2d> candidates;
  for (int i = 0; i < nx; ++i) {
    for (int j = 0; j < ny; ++j) {
      const double x = grid.xs[static_cast<size_t>(i)], y = grid.ys[static_cast<size_t>(j)];
      bool in_object = false;
      for (const auto& ob : objects) {
        in_object = in_object || (x > ob.box.xmin - margin && x < ob.box.xmax + margin &&
                                  y > ob.box.ymin - margin && y < ob.box.ymax + margin);
      }
      const bool clear_of_walls =
          x - r.xmin > wall && r.xmax - x > wall && y - r.ymin > wall && r.ymax - y > wall;
      if (!in_object && clear_of_walls) candidates.emplace_back(x, y);
      if (in_object) unseen[at(i, j)] = 0;
    }
  }
  const double range2 = range * range * (1 + 1e-9);
  for (size_t k = 0; k < traj.size(); k += stride) {
    const double px = traj[k].pose.x, py = traj[k].pose.y;
    const auto [i0, i1] = CountGrid::Window(grid.xs, px, range, cell);
    const auto [j0, j1] = CountGrid::Window(grid.ys, py, range, cell);
    for (int i = i0; i <= i1; ++i) {
      for (int j = j0; j <= j1; ++j) {
        char& u = unseen[at(i, j)];
        const double dx = px - grid.xs[static_cast<size_t>(i)], dy = py - grid.ys[static_cast<size_t>(j)];
        // (Clearly out of range by the square: the same answer without the hypot.)
        if (u && dx * dx + dy * dy <= range2 && std::hypot(dx, dy) < range) u = 0;
      }
    }
  }
  for (const auto& sp : points_) {  // and what earlier surveys looked at
    const auto [i0, i1] = CountGrid::Window(grid.xs, sp.x(), range, cell);
    const auto [j0, j1] = CountGrid::Window(grid.ys, sp.y(), range, cell);
    for (int i = i0; i <= i1; ++i) {
      for (int j = j0; j <= j1; ++j) {
        const Eigen::Vector2d c(grid.xs[static_cast<size_t>(i)], grid.ys[static_cast<size_t>(j)]);
        if ((c - sp).norm() < range) unseen[at(i, j)] = 0;
      }
    }
  }
  // The points that would see most of the unseen room (ties: nearer the middle).
  const Eigen::Vector2d middle = Middle(r);
  std::vector<std::pair<double, Eigen::Vector2d>> ranked;
  for (const auto& c : candidates) {
    int n = 0;
    const auto [i0, i1] = CountGrid::Window(grid.xs, c.x(), range, cell);
    const auto [j0, j1] = CountGrid::Window(grid.ys, c.y(), range, cell);
    for (int i = i0; i <= i1; ++i) {
      for (int j = j0; j <= j1; ++j) {
        if (!unseen[at(i, j)]) continue;
        const Eigen::Vector2d u(grid.xs[static_cast<size_t>(i)], grid.ys[static_cast<size_t>(j)]);
        n += (u - c).norm() < range;
      }
    }
    if (n * cell * cell >= o.survey_min_unseen_m2)
      ranked.emplace_back(n - 0.01 * (c - middle).norm(), c);
  }
  std::sort(ranked.begin(), ranked.end(),
            [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<Eigen::Vector2d> out;
  for (size_t i = 0; i < ranked.size() && i < static_cast<size_t>(o.survey_candidates); ++i) {
    out.push_back(ranked[i].second);
  }
  return out;
}

void Survey::Accept(const Eigen::Vector2d& p) {
  ++done_;
  points_.push_back(p);
  turned_ = -1;
}

bool Survey::TurnRound(double theta, Twist* out) {
  if (turned_ < 0) {
    turned_ = 0;
    last_theta_ = theta;
  }
  turned_ += std::abs(NormalizeAngle(theta - last_theta_));
  last_theta_ = theta;
  if (turned_ > 2 * M_PI + options_.survey_turn_margin_rad) {
    turned_ = -1;
    return true;
  }
  *out = {0, options_.survey_turn_rate_rad_s};
  return false;
}

}  // namespace irslam::control
