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
// computed them (x and y stepped by repeated addition from the room's corner)
// and which cells are still unseen. Marking and counting visit only a window
// round a point that holds every centre within the range of it (two cells of
// slack on each side: the window only limits the loops; the tests themselves
// are the same distances as ever).
class CountGrid {
 public:
  CountGrid(const Box& r, double cell, double range)
      : xs_(Centres(r.xmin, r.xmax, cell)), ys_(Centres(r.ymin, r.ymax, cell)), cell_(cell), range_(range),
        nx_(static_cast<int>(xs_.size())), ny_(static_cast<int>(ys_.size())),
        unseen_(static_cast<size_t>(nx_) * static_cast<size_t>(ny_), 1) {
    // The cells within range of a cell are the same offsets everywhere (the
    // centres are a grid): offsets clearly inside the range by more than 1e-6 m
    // count without a distance; only those at its edge are measured.
    const int w = static_cast<int>(std::ceil(range / cell)) + 2;
    for (int di = -w; di <= w; ++di) {
      for (int dj = -w; dj <= w; ++dj) {
        const double d = cell * std::hypot(di, dj);
        if (d < range - 1e-6) inside_.emplace_back(di, dj);
        else if (d <= range + 1e-6) edge_.emplace_back(di, dj);
      }
    }
  }
  int nx() const { return nx_; }
  int ny() const { return ny_; }
  Eigen::Vector2d Centre(int i, int j) const { return {xs_[static_cast<size_t>(i)], ys_[static_cast<size_t>(j)]}; }
  void SetSeen(int i, int j) { unseen_[At(i, j)] = 0; }
  // Every cell within the range of trajectory point (px, py) was seen.
  void SeenFrom(double px, double py) {
    const double range2 = range_ * range_ * (1 + 1e-9);
    const auto [i0, i1] = Window(xs_, px);
    const auto [j0, j1] = Window(ys_, py);
    for (int i = i0; i <= i1; ++i) {
      for (int j = j0; j <= j1; ++j) {
        char& u = unseen_[At(i, j)];
        const double dx = px - xs_[static_cast<size_t>(i)], dy = py - ys_[static_cast<size_t>(j)];
        // (Clearly out of range by the square: the same answer without the hypot.)
        if (u && dx * dx + dy * dy <= range2 && std::hypot(dx, dy) < range_) u = 0;
      }
    }
  }
  // ... and within the range of an earlier survey point.
  void SeenFromSurvey(const Eigen::Vector2d& sp) {
    const auto [i0, i1] = Window(xs_, sp.x());
    const auto [j0, j1] = Window(ys_, sp.y());
    for (int i = i0; i <= i1; ++i) {
      for (int j = j0; j <= j1; ++j) {
        if ((Centre(i, j) - sp).norm() < range_) unseen_[At(i, j)] = 0;
      }
    }
  }
  // The unseen cells within the range of cell (ci, cj).
  int UnseenNear(int ci, int cj) const {
    int n = 0;
    for (const auto& [di, dj] : inside_) {
      const int i = ci + di, j = cj + dj;
      if (i >= 0 && j >= 0 && i < nx_ && j < ny_) n += unseen_[At(i, j)] != 0;
    }
    for (const auto& [di, dj] : edge_) {
      const int i = ci + di, j = cj + dj;
      if (i < 0 || j < 0 || i >= nx_ || j >= ny_ || !unseen_[At(i, j)]) continue;
      n += (Centre(i, j) - Centre(ci, cj)).norm() < range_;
    }
    return n;
  }

 private:
  static std::vector<double> Centres(double lo, double hi, double cell) {
    std::vector<double> out;
    for (double v = lo + 0.5 * cell; v < hi; v += cell) out.push_back(v);
    return out;
  }
  std::pair<int, int> Window(const std::vector<double>& c, double centre) const {
    if (c.empty()) return {0, -1};
    const int lo = static_cast<int>(std::floor((centre - range_ - c.front()) / cell_)) - 2;
    const int hi = static_cast<int>(std::ceil((centre + range_ - c.front()) / cell_)) + 2;
    return {std::max(0, lo), std::min(static_cast<int>(c.size()) - 1, hi)};
  }
  size_t At(int i, int j) const { return static_cast<size_t>(i) * static_cast<size_t>(ny_) + static_cast<size_t>(j); }

  std::vector<double> xs_, ys_;
  double cell_, range_;
  int nx_, ny_;
  std::vector<char> unseen_;
  std::vector<std::pair<int, int>> inside_, edge_;
};

}  // namespace

// The ranking is bounded by the room's cells times a window of about
// (2 range / cell)^2 cells: each trajectory point marks the cells it saw, and
// each candidate counts the unseen cells round it (issue 15: it used to
// compare every cell with every trajectory point and every candidate with
// every unseen cell, 26 ms in a 16 x 12 m room). The same points in the same
// order as before: the same centres, the same distance tests, the same
// candidate order.
std::vector<Eigen::Vector2d> Survey::RankedPoints(const Box& r, const std::vector<TimedPose>& traj,
                                                  const std::vector<ObjectModel>& objects) const {
  const auto& o = options_;
  const double cell = o.survey_cell_m;
  const double margin = o.survey_object_margin_m, wall = o.survey_wall_margin_m;
  CountGrid grid(r, cell, o.survey_range_m);
  // Cells of the room (map frame) not yet seen: farther than the range from
  // every trajectory point, and not inside a known object.
  std::vector<std::pair<int, int>> candidates;  // cells (i, j)
  for (int i = 0; i < grid.nx(); ++i) {
    for (int j = 0; j < grid.ny(); ++j) {
      const Eigen::Vector2d c = grid.Centre(i, j);
      const double x = c.x(), y = c.y();
      bool in_object = false;
      for (const auto& ob : objects) {
        in_object = in_object || (x > ob.box.xmin - margin && x < ob.box.xmax + margin &&
                                  y > ob.box.ymin - margin && y < ob.box.ymax + margin);
      }
      const bool clear_of_walls =
          x - r.xmin > wall && r.xmax - x > wall && y - r.ymin > wall && r.ymax - y > wall;
      if (!in_object && clear_of_walls) candidates.emplace_back(i, j);
      if (in_object) grid.SetSeen(i, j);
    }
  }
  for (size_t k = 0; k < traj.size(); k += static_cast<size_t>(o.survey_trajectory_stride))
    grid.SeenFrom(traj[k].pose.x, traj[k].pose.y);
  for (const auto& sp : points_) grid.SeenFromSurvey(sp);  // and what earlier surveys looked at
  // The points that would see most of the unseen room (ties: nearer the middle).
  const Eigen::Vector2d middle = Middle(r);
  std::vector<std::pair<double, Eigen::Vector2d>> ranked;
  for (const auto& [i, j] : candidates) {
    const int n = grid.UnseenNear(i, j);
    const Eigen::Vector2d c = grid.Centre(i, j);
    if (n * cell * cell >= o.survey_min_unseen_m2) ranked.emplace_back(n - 0.01 * (c - middle).norm(), c);
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
