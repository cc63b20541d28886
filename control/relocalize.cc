#include "control/relocalize.h"

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

void MapAgreement::Reset(const slam::Slam& slam) {
  last_ = slam.stats();
  windows_.clear();
  checkpoints_.clear();
  checkpoints_.push_back({slam.map_lines(), slam.map_trajectory()});
  agreement_ = 1;
}

bool MapAgreement::Step(const slam::Slam& slam) {
  const slam::SlamStats& s = slam.stats();
  if (s.windows == last_.windows) return true;
  // Association outcome of the windows closed since the last call: matched
  // (EKF updates) against what the map did not explain (new lines, gate rejections).
  // Collinear pieces of mapped lines (tied or declined) are the map seen
  // again in part and are not counted against it; a line with no mapped line
  // near it, one the gate rejects, or one at an angle the map does not have is.
  const int plain_new = (s.insertions - last_.insertions) - (s.collinear_insertions - last_.collinear_insertions) -
                        (s.collinear_declined - last_.collinear_declined);
  windows_.push_back({s.updates - last_.updates,
                      plain_new + (s.rejected_gate - last_.rejected_gate) + (s.rejected_angle - last_.rejected_angle)});
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
  // check_windows windows ago (what a relocalisation falls back to).
  checkpoints_.push_back({slam.map_lines(), slam.map_trajectory()});
  while (checkpoints_.size() > keep + 1) checkpoints_.pop_front();
  return true;
}

}  // namespace irslam::control
