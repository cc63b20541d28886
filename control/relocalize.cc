#include "control/relocalize.h"

#include <algorithm>
#include <cmath>
#include <utility>

namespace irslam::control {

options::Table<RelocalizeOptions> RelocalizeKeys() {
  using O = RelocalizeOptions;
  static constexpr options::Key<O> kKeys[] = {
      {"check_windows", &O::check_windows, 2, 100, "",
       "after the commit, the map's agreement is judged over this many PDS windows"},
      {"min_lines_judged", &O::min_lines_judged, 1, 1000, "",
       "... once they hold at least this many extracted lines"},
      {"min_agreement", &O::min_agreement, 0, 1, "",
       "matched share of those lines below which the map disagrees (relocalise again)"},
      {"max_attempts", &O::max_attempts, 1, 100, "",
       "relocalisations in one mission before the saved map is given up"},
      {"scan_max_m", &O::scan_max_m, 0.1, 2, "m",
       "after the commit, IR rays whose mapped wall is within this are judged against the map ..."},
      {"scan_min_m", &O::scan_min_m, 0, 2, "m",
       "... and not nearer than this (below the IR sensors' range a reading is missing)"},
      {"scan_tolerance_m", &O::scan_tolerance_m, 0.01, 1, "m", "... a reading off by more (or missing) disagrees"},
      {"scan_rays", &O::scan_rays, 10, 100000, "", "... over this many recent judged rays"},
      {"scan_max_disagree", &O::scan_max_disagree, 0, 1, "",
       "... of which a larger share disagreeing means the map disagrees (relocalise again)"},
      {"moved_share", &O::moved_share, 0, 1, "",
       "... unless this share of the disagreeing rays is one object's finding nothing: its rays set aside"
       " (or finds nothing at lines this mission mapped: those lines dropped)"},
      {"moved_confirm_rays", &O::moved_confirm_rays, 1, 100000, "",
       "... and it is reported moved once this many more rays are judged ..."},
      {"moved_confirm_agree", &O::moved_confirm_agree, 0, 1, "",
       "... this share of them agreeing (fewer: the map disagrees)"},
      {"moved_confirm_s", &O::moved_confirm_s, 1, 3600, "s",
       "... within this time (or the map disagrees)"},
  };
  return kKeys;
}

void Relocalize::Begin(double t, SavedLines map) {
  map_ = std::move(map);
  search_.emplace(options_.search, map_.lines, map_.trajectory);
  started_t_ = t;
  windows_seen_ = -1;
}

std::optional<slam::PoseHypothesis> Relocalize::Step(double /*t*/, const slam::Slam& local) {
  if (!search_) return std::nullopt;
  // The search runs once per closed window (the local map only changes then).
  if (local.stats().windows == windows_seen_) return std::nullopt;
  windows_seen_ = local.stats().windows;
  search_->Update(local.lines(), local.trajectory());
  return search_->Decision();
}

double Relocalize::best_score() const {
  if (!search_ || search_->hypotheses().empty()) return 0;
  return search_->hypotheses().front().score;
}

void MapAgreement::Reset(const slam::Slam& slam, const EnvironmentModel& model, std::vector<int> saved_lines) {
  objects_ = model.objects;
  saved_lines_ = std::move(saved_lines);
  std::sort(saved_lines_.begin(), saved_lines_.end());
  contradicted_.clear();
  last_ = slam.stats();
  rays_.clear();
  rays_agreeing_ = 0;
  scan_agreement_ = 1;
  last_scan_t_ = -1;
  suspect_ = {};
  probation_rays_ = probation_agreeing_ = 0;
  moved_.clear();
  windows_.clear();
  checkpoints_.clear();
  checkpoints_.push_back({slam.map_lines(), slam.map_trajectory()});
  committed_ = checkpoints_.front().lines;
  agreement_ = 1;
}

SavedLines WithCommittedLines(SavedLines checkpoint, const std::vector<slam::LineFeature>& committed) {
  for (auto& l : checkpoint.lines) {
    const auto c = std::find_if(committed.begin(), committed.end(),
                                [&](const slam::LineFeature& x) { return x.id == l.id; });
    // Not a line that took other saved lines in since (their ids are kept in
    // its `merged`, and the wall it became is theirs too).
    if (c == committed.end() || c->merged != l.merged) continue;
    l.rho = c->rho;
    l.theta = c->theta;
    l.cov = c->cov;
    l.p0 = c->p0;
    l.p1 = c->p1;
  }
  return checkpoint;
}

SavedLines MapAgreement::checkpoint() const { return WithCommittedLines(checkpoints_.front(), committed_); }

namespace {
// Distance along the ray from o in direction d to segment ab (nullopt: missed).
std::optional<double> RayHit(const Eigen::Vector2d& o, const Eigen::Vector2d& d, const Eigen::Vector2d& a,
                             const Eigen::Vector2d& b) {
  const Eigen::Vector2d e = b - a;
  const double den = d.x() * e.y() - d.y() * e.x();
  if (std::abs(den) < 1e-9) return std::nullopt;
  const Eigen::Vector2d w = a - o;
  const double t = (w.x() * e.y() - w.y() * e.x()) / den;
  const double u = (w.x() * d.y() - w.y() * d.x()) / den;
  if (t <= 0 || u < 0 || u > 1) return std::nullopt;
  return t;
}

// The object of `objects` whose side line `id` is (0: none, a wall).
int ObjectOfLine(const std::vector<ObjectModel>& objects, int id) {
  for (const auto& o : objects) {
    if (std::find(o.lines.begin(), o.lines.end(), id) != o.lines.end()) return o.id;
  }
  return 0;
}

}  // namespace

bool MapAgreement::JudgeScan(const slam::Slam& slam, const RangeScan& scan) {
  if (scan.t == last_scan_t_) return true;
  last_scan_t_ = scan.t;
  const Pose2 me = slam.pose();  // internal frame, as the lines
  for (size_t i = 0; i < mounts_.size(); ++i) {
    const Pose2 ray = Compose(me, {mounts_[i].x, mounts_[i].y, mounts_[i].theta});
    const Eigen::Vector2d o(ray.x, ray.y), d(std::cos(ray.theta), std::sin(ray.theta));
    double expected = options_.scan_max_m;
    int line = 0;
    for (const auto& l : slam.lines()) {
      const auto hit = RayHit(o, d, l.p0, l.p1);
      if (hit && *hit < expected) {
        expected = *hit;
        line = l.id;
      }
    }
    if (line == 0 || expected < options_.scan_min_m) continue;
    const int object = ObjectOfLine(objects_, line);
    if (object != 0 && object == suspect_.id) continue;  // set aside
    const auto& m = scan.range_m[i];
    Ray r;
    r.agrees = m && std::abs(*m - expected) <= options_.scan_tolerance_m;
    r.absent = !r.agrees && (!m || *m > expected);
    r.object = object;
    if (!std::binary_search(saved_lines_.begin(), saved_lines_.end(), line)) r.own_line = line;
    rays_.push_back(r);
    rays_agreeing_ += r.agrees;
    if (suspect_.id != 0 && r.own_line == 0) {
      ++probation_rays_;
      probation_agreeing_ += r.agrees;
    }
    if (static_cast<int>(rays_.size()) > options_.scan_rays) {
      rays_agreeing_ -= rays_.front().agrees;
      rays_.pop_front();
    }
  }
  if (!Probation(scan.t)) return false;
  if (static_cast<int>(rays_.size()) < options_.scan_rays) return true;
  scan_agreement_ = static_cast<double>(rays_agreeing_) / static_cast<double>(rays_.size());
  if (1 - scan_agreement_ <= options_.scan_max_disagree) return true;
  return DropContradictedLines() || SetAsideAbsentObject(scan.t);
}

void MapAgreement::Forget(int object_id) {
  objects_.erase(std::remove_if(objects_.begin(), objects_.end(), [&](const auto& o) { return o.id == object_id; }),
                 objects_.end());
  if (suspect_.id == object_id) suspect_ = {};
}

bool MapAgreement::Probation(double t) {
  if (suspect_.id == 0) return true;
  if (probation_rays_ >= options_.moved_confirm_rays) {
    if (probation_agreeing_ < options_.moved_confirm_agree * probation_rays_) return false;
    // Its lines leave the map (Mission::ObjectMoved): nothing to set aside.
    moved_.push_back(suspect_);
    Forget(suspect_.id);
    return true;
  }
  return t - set_aside_t_ <= options_.moved_confirm_s;
}

template <typename Pred>
void MapAgreement::DropRays(Pred drop) {
  rays_.erase(std::remove_if(rays_.begin(), rays_.end(), drop), rays_.end());
  rays_agreeing_ = static_cast<int>(std::count_if(rays_.begin(), rays_.end(), [](const Ray& r) { return r.agrees; }));
}

bool MapAgreement::DropContradictedLines() {
  // Kidnapped, the robot maps what it sees from the pose it wrongly believes;
  // the map a relocalisation falls back to (check_windows windows back) may
  // still hold those lines, found nowhere once the robot is right again. Saved
  // walls and objects agreeing while rays find nothing at the mission's own
  // lines: the lines are wrong, not the pose (moved_share as for an object).
  struct Own {
    int line, rays, absent;
  };
  std::vector<Own> own;
  int disagreeing = 0;
  for (const Ray& r : rays_) {
    disagreeing += !r.agrees;
    if (r.own_line == 0) continue;
    auto it = std::find_if(own.begin(), own.end(), [&](const Own& o) { return o.line == r.own_line; });
    if (it == own.end()) it = own.insert(own.end(), {r.own_line, 0, 0});
    ++it->rays;
    it->absent += r.absent;
  }
  // A line is contradicted when most of its own rays found nothing there.
  std::vector<int> lines;
  int absent = 0;
  for (const Own& o : own) {
    if (2 * o.absent <= o.rays) continue;
    lines.push_back(o.line);
    absent += o.absent;
  }
  if (lines.empty() || absent < options_.moved_share * disagreeing) return false;
  DropRays([&](const Ray& r) { return std::find(lines.begin(), lines.end(), r.own_line) != lines.end(); });
  contradicted_.insert(contradicted_.end(), lines.begin(), lines.end());
  return true;
}

bool MapAgreement::SetAsideAbsentObject(double t) {
  // One at a time: a second disagreement on probation is the map's.
  if (suspect_.id != 0) return false;
  std::vector<std::pair<int, int>> absent;  // object, its rays finding nothing
  int disagreeing = 0;
  for (const Ray& r : rays_) {
    disagreeing += !r.agrees;
    if (!r.absent || r.object == 0) continue;
    auto it = std::find_if(absent.begin(), absent.end(), [&](const auto& a) { return a.first == r.object; });
    if (it == absent.end()) {
      absent.emplace_back(r.object, 1);
    } else {
      ++it->second;
    }
  }
  if (absent.empty()) return false;
  const auto most =
      std::max_element(absent.begin(), absent.end(), [](const auto& a, const auto& b) { return a.second < b.second; });
  if (most->second < options_.moved_share * disagreeing) return false;
  const int object = most->first;
  const auto o = std::find_if(objects_.begin(), objects_.end(), [&](const auto& x) { return x.id == object; });
  if (o == objects_.end()) return false;
  DropRays([&](const Ray& r) { return r.object == object; });
  suspect_ = *o;
  set_aside_t_ = t;
  probation_rays_ = probation_agreeing_ = 0;
  return true;
}

bool MapAgreement::Step(const slam::Slam& slam, const RangeScan& scan) {
  if (!JudgeScan(slam, scan)) return false;
  const slam::SlamStats& s = slam.stats();
  if (s.windows == last_.windows) return true;
  // Association outcome of the windows closed since the last call: matched
  // (EKF updates) against what the map did not explain (new lines, gate rejections).
  // Collinear pieces of mapped lines (tied or declined) are the map seen
  // again in part and are not counted against it; a line with no mapped line
  // near it, one the gate rejects, or one at an angle the map does not have is.
  // A new line merged into a saved one (Slam: merges_into_saved) is the map
  // seen again, found by the merge rather than the association: it counts as
  // matched, and no longer as unexplained.
  const int plain_new = (s.insertions - last_.insertions) - (s.collinear_insertions - last_.collinear_insertions) -
                        (s.collinear_declined - last_.collinear_declined);
  const int resaw = s.merges_into_saved - last_.merges_into_saved;
  windows_.push_back({s.updates - last_.updates + resaw,
                      std::max(0, plain_new + (s.rejected_gate - last_.rejected_gate) +
                                      (s.rejected_angle - last_.rejected_angle) - resaw)});
  last_ = s;
  const size_t keep = static_cast<size_t>(options_.check_windows);
  if (windows_.size() > keep) windows_.pop_front();
  int matched = 0, total = 0;
  for (const auto& w : windows_) {
    matched += w.matched;
    total += w.matched + w.unexplained;
  }
  agreement_ = total >= options_.min_lines_judged ? static_cast<double>(matched) / total : 1.0;
  if (agreement_ < options_.min_agreement) return false;
  // Healthy: this window's map becomes a checkpoint; the oldest kept is from
  // check_windows windows ago (what a relocalisation falls back to). Not on
  // probation: the map may be wrong then.
  if (suspect_.id != 0) return true;
  checkpoints_.push_back({slam.map_lines(), slam.map_trajectory()});
  while (checkpoints_.size() > keep + 1) checkpoints_.pop_front();
  return true;
}

}  // namespace irslam::control
