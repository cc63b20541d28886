// Clean, the cleaning behaviour (control/clean.h): its plan (in bounded steps),
// cells, progress and resume. Driving a cell's route is in clean_sweep.cc.
#include "control/clean.h"

#include "control/room_geometry.h"

#include <algorithm>
#include <cmath>

namespace irslam::control {

const char* ToString(CleanState s) {
  switch (s) {
    case CleanState::kNone:
      return "none";
    case CleanState::kCleaning:
      return "cleaning";
    case CleanState::kReturning:
      return "returning";
    case CleanState::kDone:
      return "done";
    case CleanState::kStopped:
      return "stopped";
  }
  return "?";
}

GoToOptions CleaningGoTo(GoToOptions g, const CleaningOptions& c) {
  g.clearance_m = std::max(0.0, c.clearance_m - 0.02);
  // Below the clearance, so a start inside it can still be left.
  g.hard_clearance_m = std::min(g.hard_clearance_m, 0.5 * g.clearance_m);
  g.front_stop_m = 0.1;
  g.boxed_in_contacts_m = c.boxed_in_contacts_m;
  g.under_body_contacts_m = c.under_body_contacts_m;
  g.boxed_in_corners = c.boxed_in_corners;
  g.boxed_in_trail_m = c.boxed_in_trail_m;
  return g;
}

void Clean::Interrupted(double t) {
  if (phase_ != Phase::kDone) phase_ = Phase::kPlanGoal;
  progress_t_ = t;
}

void Clean::Reset() {
  progress_ = {};
  plan_ = {};
  grid_ = {};
  phase_ = Phase::kDone;
  stage_ = PlanStage::kNone;
  resume_.reset();
  resumed_cells_ = 0;
  replanned_same_ = false;
}

Clean::Clean(CleaningOptions options, GoToOptions go_to, const RobotGeometry& geometry,
             const std::array<SensorMount, kNumIrSensors>& mounts)
    : options_(options),
      radius_m_(geometry.radius_m),
      mounts_(mounts),
      go_to_(CleaningGoTo(go_to, options), geometry, mounts) {}

namespace {

// The orientation a saved cleaning was planned in, from its routes: the lanes
// are most of their length (none when no route was saved).
std::optional<bool> LanesAlongX(const CleaningProgress& p) {
  double along_x = 0, along_y = 0;
  for (const auto& c : p.cells) {
    for (size_t k = 1; k < c.route.size(); ++k) {
      along_x += std::abs(c.route[k].x() - c.route[k - 1].x());
      along_y += std::abs(c.route[k].y() - c.route[k - 1].y());
    }
  }
  if (along_x + along_y <= 0) return std::nullopt;
  return along_x > along_y;
}

// Edges of `a` each within tol of `b`'s.
bool NearBox(const Box& a, const Box& b, double tol) {
  return std::abs(a.xmin - b.xmin) <= tol && std::abs(a.xmax - b.xmax) <= tol && std::abs(a.ymin - b.ymin) <= tol &&
         std::abs(a.ymax - b.ymax) <= tol;
}

}  // namespace

bool SameModel(const CleaningProgress::PlanInputs& planned, const CleaningProgress::PlanInputs& now,
               double tolerance_m) {
  if (tolerance_m <= 0 || planned.objects.size() != now.objects.size()) return false;
  if (!NearBox(planned.room, now.room, tolerance_m)) return false;
  // Greedy one-to-one pairing (boxes of one model lie apart by more than any
  // sensible tolerance, so the first near one is the one); O(objects^2).
  std::vector<bool> taken(planned.objects.size(), false);
  for (const Box& b : now.objects) {
    bool found = false;
    for (size_t i = 0; i < planned.objects.size() && !found; ++i) {
      if (taken[i] || !NearBox(planned.objects[i], b, tolerance_m)) continue;
      taken[i] = true;
      found = true;
    }
    if (!found) return false;
  }
  return true;
}

void Clean::Begin(double t, const slam::Slam& slam, const EnvironmentModel& m, const BumpMemory& bumps,
                  std::optional<CleaningProgress> resume) {
  progress_ = {};
  progress_.state = CleanState::kCleaning;
  progress_.started_t = t;
  progress_.cleaning_width_m = options_.cleaning_width_m;
  plan_ = {};
  resume_ = std::move(resume);
  resumed_cells_ = 0;
  replanned_same_ = false;
  inputs_.reset();
  match_ = {};
  if (resume_) {
    // Until planned, the cells done before are the progress (a stop now keeps them).
    progress_.cells = resume_->cells;
    progress_.cells_done = resume_->cells_done;
    progress_.cells_total = resume_->cells_total;
    progress_.planned = resume_->planned;
  }
  stage_ = PlanStage::kCells;
  if (m.room.box) {
    const double rot = slam.map_rotation();
    CleaningProgress::PlanInputs in;
    in.room = *m.room.box;
    for (const auto& o : m.objects) in.objects.push_back(o.box);
    // The latest contacts, as many as the planner takes.
    const auto& points = bumps.points();
    for (size_t k = FirstPlannedContact(points.size(), options_); k < points.size(); ++k)
      in.contacts.push_back(RotateVector(points[k], rot));
    if (resume_ && resume_->planned && SameModel(*resume_->planned, in, options_.resume_same_model_m)) {
      in = *resume_->planned;  // nothing moved: the same cells as the plan stopped
      replanned_same_ = true;
    }
    const Pose2 me = slam.map_pose();
    room_ = in.room;
    planner_.Start(room_, in.objects, in.contacts, {me.x, me.y}, radius_m_, options_,
                   resume_ ? LanesAlongX(*resume_) : std::nullopt);
    inputs_ = std::move(in);  // the progress's once its cells are this plan's (kCells)
    stage_ = PlanStage::kCoverage;
  }
  cell_ = 0;
  point_ = 0;
  failures_ = 0;
  no_plan_at_.reset();
  start_distance_ = slam.distance_m();
  cross_sq_ = 0;
  cross_n_ = 0;
  phase_ = Phase::kDone;  // (planning)
  progress_t_ = t;
  progress_at_ = {slam.map_pose().x, slam.map_pose().y};
}

bool Clean::Plan(double t) {
  // Pieces until this period's share of the work is spent (at least one).
  double spent = 0;
  while (planning() && spent < options_.plan_work_per_period) spent += PlanStep(t);
  return !planning();
}

double Clean::PlanStep(double t) {
  switch (stage_) {
    case PlanStage::kNone:
      return 0;
    case PlanStage::kCoverage: {
      const double before = planner_.work();
      if (planner_.Step()) {
        plan_ = planner_.Take();
        free_rects_ = plan_.FreeRects();
        grid_.Reset(room_, 0.5 * options_.cleaning_width_m, options_.coverage_cell_m);
        stage_next_ = 0;
        stage_ = free_rects_.empty() ? PlanStage::kCells : PlanStage::kGrid;
      }
      return planner_.work() - before;
    }
    case PlanStage::kGrid: {
      // One free rectangle: the grid cells within the body's radius of it.
      const Box& b = free_rects_[stage_next_++];
      const double grow = 0.5 * options_.cleaning_width_m, c = options_.coverage_cell_m;
      grid_.AddTarget(b);
      if (stage_next_ >= free_rects_.size()) stage_ = PlanStage::kCells;
      return ((b.width() + 2 * grow) / c + 2) * ((b.height() + 2 * grow) / c + 2);
    }
    case PlanStage::kCells: {
      double work = 0;
      progress_.cells.clear();
      for (size_t i = 0; i < plan_.order.size(); ++i) {
        const CoverageCell& c = plan_.cells[static_cast<size_t>(plan_.order[i])];
        std::vector<Eigen::Vector2d> outline = c.Outline(0.5 * options_.cleaning_width_m);
        if (plan_.swapped) {
          for (auto& p : outline) p = Eigen::Vector2d(p.y(), p.x());
          std::reverse(outline.begin(), outline.end());  // counter-clockwise again
        }
        work += static_cast<double>(outline.size() + plan_.routes[i].size());
        progress_.cells.push_back({c.id, std::move(outline), plan_.routes[i], false, false});
      }
      progress_.cells_done = 0;
      progress_.cells_total = static_cast<int>(plan_.order.size());
      progress_.planned = inputs_;
      progress_.total_m2 = grid_.total_m2();
      stage_next_ = 0;
      if (resume_ && !progress_.cells.empty()) {
        stage_ = PlanStage::kResume;
      } else {
        Started(t);
      }
      return work;
    }
    case PlanStage::kResume: {
      // A cleaning stopped before (not finished) goes on with the cells it
      // left: each planned cell is matched against the cells done then (a
      // lattice column a step), then what each of those swept is marked (one a
      // step).
      if (stage_next_ < progress_.cells.size()) return ResumeStep(*resume_);
      const size_t k = stage_next_++ - progress_.cells.size();
      if (k >= resume_->cells.size()) {
        Started(t);
        return 1;
      }
      return resume_->cells[k].done ? MarkSwept(resume_->cells[k]) : 1;
    }
  }
  return 0;
}

void Clean::Started(double t) {
  stage_ = PlanStage::kNone;
  free_rects_.clear();
  resume_.reset();
  cell_ = 0;
  point_ = 0;
  failures_ = 0;
  SkipDone();
  progress_t_ = t;
}

void Clean::SetState(CleanState s, double t, double distance_m) {
  if (progress_.state == CleanState::kNone) return;
  if (progress_.state == CleanState::kCleaning) progress_.path_m = distance_m - start_distance_;
  progress_.state = s;
  if (s == CleanState::kReturning) progress_.swept_t = t;
  if (s == CleanState::kDone || s == CleanState::kStopped) progress_.finished_t = t;
}

double Clean::RemainingRoute() const {
  double rest = 0;
  for (size_t c = cell_; c < plan_.routes.size(); ++c) {
    const auto& r = plan_.routes[c];
    for (size_t k = (c == cell_ ? std::max<size_t>(point_, 1) : 1); k < r.size(); ++k)
      rest += (r[k] - r[k - 1]).norm();
  }
  return rest;
}

double Clean::AreaShare(double length_m) const {
  const auto& r = plan_.routes[cell_];
  double all = 0;
  for (size_t k = 1; k < r.size(); ++k) all += (r[k] - r[k - 1]).norm();
  const double area = plan_.cells[static_cast<size_t>(plan_.order[cell_])].area_m2();
  return all > 0 ? area * length_m / all : 0;
}

void Clean::NextCell(bool unreachable) {
  if (cell_ >= plan_.routes.size()) return;
  auto& pc = progress_.cells[cell_];
  if (unreachable) {
    // The rest of the route, not swept: its share of the cell's area.
    const auto& r = plan_.routes[cell_];
    for (size_t k = std::max<size_t>(point_, 1); k < r.size(); ++k)
      progress_.unreachable_m2 += AreaShare((r[k] - r[k - 1]).norm());
    pc.unreachable = true;
  } else {
    pc.done = true;
    ++progress_.cells_done;
  }
  ++cell_;
  point_ = 0;
  failures_ = 0;
  SkipDone();
}

void Clean::SkipDone() {
  while (cell_ < progress_.cells.size() && progress_.cells[cell_].done) ++cell_;
  phase_ = cell_ < plan_.routes.size() ? Phase::kPlanGoal : Phase::kDone;
}

namespace {

// Boxes that share some area.
bool Overlaps(const Box& a, const Box& b) {
  return room_geometry::Overlap1d(a.xmin, a.xmax, b.xmin, b.xmax) > 0 &&
         room_geometry::Overlap1d(a.ymin, a.ymax, b.ymin, b.ymax) > 0;
}

}  // namespace

double Clean::ResumeStep(const CleaningProgress& before) {
  // The plan may be cut differently from the one stopped (an object seen
  // again has changed, or a map saved without its plan's inputs): a cell is done when most of
  // it lies inside the cells done then, sampled on a lattice twice the
  // coverage grid's cell, a column of it per step.
  auto& pc = progress_.cells[stage_next_];
  if (match_.column == 0) {
    match_ = {};
    if (pc.polygon.size() < 3) {
      ++stage_next_;
      return 1;
    }
    match_.box = room_geometry::PolygonBounds(pc.polygon);
    match_.vertices = static_cast<double>(pc.polygon.size());
    for (const auto& b : before.cells) {
      if (!b.done || b.polygon.size() < 3) continue;
      if (!Overlaps(room_geometry::PolygonBounds(b.polygon), match_.box)) continue;
      match_.done.push_back(&b.polygon);
      match_.vertices += static_cast<double>(b.polygon.size());
    }
    if (match_.done.empty()) {
      ++stage_next_;
      return static_cast<double>(before.cells.size()) + 1;
    }
  }
  const double step = 2 * options_.coverage_cell_m;
  const Box& box = match_.box;
  const int nx = static_cast<int>(box.width() / step) + 1, ny = static_cast<int>(box.height() / step) + 1;
  const double x = box.xmin + (match_.column + 0.5) * step;
  for (int b = 0; b < ny; ++b) {
    const Eigen::Vector2d p(x, box.ymin + (b + 0.5) * step);
    if (!room_geometry::InsidePolygon(pc.polygon, p)) continue;
    ++match_.inside;
    match_.inside_done += std::any_of(match_.done.begin(), match_.done.end(),
                                      [&](const auto* d) { return room_geometry::InsidePolygon(*d, p); });
  }
  const double work = static_cast<double>(ny) * match_.vertices;
  if (++match_.column < nx) return work;
  if (match_.inside > 0 &&
      static_cast<double>(match_.inside_done) >= options_.resume_overlap * static_cast<double>(match_.inside)) {
    pc.done = true;
    ++progress_.cells_done;
    ++resumed_cells_;
  }
  match_ = {};
  ++stage_next_;
  return work;
}

double Clean::MarkSwept(const CleaningProgress::Cell& before) {
  // Its route counts as swept (the coverage estimate marks the body's path);
  // a cell saved without its route: its outline.
  const auto& r = before.route;
  if (r.size() < 2) {
    if (before.polygon.size() < 3) return 1;  // neither: nothing to mark
    grid_.MarkInside(before.polygon);
    const Box b = room_geometry::PolygonBounds(before.polygon);
    return (b.width() / options_.coverage_cell_m + 2) * (b.height() / options_.coverage_cell_m + 2) *
           static_cast<double>(before.polygon.size() + 1);
  }
  double len = 0;
  for (size_t k = 1; k < r.size(); ++k) {
    const double seg = (r[k] - r[k - 1]).norm();
    len += seg;
    const int n = std::max(1, static_cast<int>(seg / (0.25 * options_.cleaning_width_m)));
    for (int j = 0; j <= n; ++j) grid_.Mark(r[k - 1] + (r[k] - r[k - 1]) * (static_cast<double>(j) / n));
  }
  // A disc of grid cells every quarter of the cleaning width.
  const double disc = options_.cleaning_width_m / options_.coverage_cell_m + 2;
  return (len / (0.25 * options_.cleaning_width_m) + static_cast<double>(r.size())) * disc * disc;
}

CleaningProgress Clean::Progress(double t, double distance_m) const {
  CleaningProgress p = progress_;
  p.covered_m2 = grid_.covered_m2();
  p.fraction = p.total_m2 > 0 ? std::min(1.0, p.covered_m2 / p.total_m2) : 0;
  if (p.state == CleanState::kCleaning) {
    p.path_m = distance_m - start_distance_;
    p.eta_s = RemainingRoute() / options_.sweep_speed_mps;
  } else {
    p.path_m = progress_.path_m;
  }
  p.cross_track_rms_m = cross_n_ > 0 ? std::sqrt(cross_sq_ / static_cast<double>(cross_n_)) : 0;
  (void)t;
  return p;
}

}  // namespace irslam::control
