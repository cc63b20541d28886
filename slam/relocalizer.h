// Global relocalisation in a saved line map (issue 14). At a start with a
// saved map the robot does not know its pose: a fresh local SLAM maps what the
// robot sees as it follows a wall (its own frame, the odometry frame of the
// start); this class matches those local lines against the saved map's lines
// and finds the rigid transform local frame -> saved map frame.
//
// Method (a pose-hypothesis search over line correspondences in the spirit of
// Grimson & Lozano-Perez's interpretation trees and of Castellanos & Tardos,
// "Mobile Robot Localization and Map Building: A Multisensor Fusion
// Approach", 1999, ch. 6, specialised to the Manhattan line maps the
// constrained EKF makes, paper §4: every mapped line is parallel or
// orthogonal to line 1):
//  - rotation: four candidates (local line directions onto the map's axes);
//  - translation: for each rotation, x offsets from local lines orthogonal to
//    x matched to saved lines at the same angle and seen from the same side
//    (the side of the line the robot was on), y offsets likewise; each axis
//    is voted 1-D first and only the best few offsets per axis are combined;
//  - score of a hypothesis: the local evidence length that lies on saved
//    lines (same side, within tolerance, overlapping), minus the evidence
//    that contradicts the saved map (a local line in the saved map's free
//    space, the local trajectory crossing a saved line or leaving the room);
//  - hypotheses closer than `distinct_*` are one; several are kept while
//    ambiguous (a rectangular room alone has four); one is committed only when
//    it explains enough of enough evidence and clearly beats the runner-up.
// Bounded work per Update (the counts below), so it can run in the control
// tick. Pure: no clock, socket or file.
#ifndef IRSLAM_SLAM_RELOCALIZER_H_
#define IRSLAM_SLAM_RELOCALIZER_H_

#include <optional>
#include <vector>

#include "slam/slam.h"
#include "types/geometry.h"
#include "types/options.h"

namespace irslam::slam {

struct RelocalizeOptions {
  double min_evidence_m = 2.0;       // local line length needed before any commit
  double min_line_m = 0.25;          // shorter local lines are not evidence
  double line_tolerance_m = 0.08;    // offset of a transformed local line from a saved one
  double angle_tolerance_rad = 0.12; // direction of a local line from a map axis
  double commit_score = 0.75;        // best hypothesis explains at least this fraction ...
  double commit_margin = 0.2;        // ... and this much more than the runner-up
  double distinct_m = 0.25;          // hypotheses nearer than this (and distinct_rad) are one
  double distinct_rad = 0.2;
  int offsets_per_axis = 8;          // 1-D translation candidates kept per axis and rotation
  int max_hypotheses = 8;            // kept and reported, best first
  double max_time_s = 180;           // relocalising longer than this gives up (mission: fault)
};
options::Table<RelocalizeOptions> RelocalizeKeys();  // [relocalize]

struct PoseHypothesis {
  Pose2 local_to_map;     // a pose in the local frame -> the saved map frame
  double score = 0;       // explained_m - conflict_m, over the evidence length: <= 1
  double explained_m = 0; // evidence length lying on saved lines
  double conflict_m = 0;  // evidence contradicting the saved map
};

// The local SLAM's lines and trajectory (its internal frame) scored against a
// map, for a given transform (used by the search and, after commit, to check
// that the map still agrees).
PoseHypothesis ScoreHypothesis(const RelocalizeOptions& options, const Pose2& local_to_map,
                               const std::vector<LineFeature>& saved_lines,
                               const std::vector<TimedPose>& saved_trajectory,
                               const std::vector<LineFeature>& local_lines,
                               const std::vector<TimedPose>& local_trajectory);

class Relocalizer {
 public:
  // The saved map's lines and trajectory (its map frame; the trajectory tells
  // from which side each saved line was seen).
  Relocalizer(RelocalizeOptions options, std::vector<LineFeature> saved_lines,
              std::vector<TimedPose> saved_trajectory);

  // The evidence so far (the local SLAM's lines and trajectory, its internal
  // frame): regenerates and rescores the hypotheses. Bounded work.
  void Update(const std::vector<LineFeature>& local_lines,
              const std::vector<TimedPose>& local_trajectory);

  const std::vector<PoseHypothesis>& hypotheses() const { return hypotheses_; }  // best first
  // The hypothesis to commit to, when one is clearly best (see the options).
  std::optional<PoseHypothesis> Decision() const;
  double evidence_m() const { return evidence_m_; }
  const RelocalizeOptions& options() const { return options_; }

 private:
  RelocalizeOptions options_;
  std::vector<LineFeature> saved_lines_;
  std::vector<TimedPose> saved_trajectory_;
  std::vector<PoseHypothesis> hypotheses_;
  double evidence_m_ = 0;
};

}  // namespace irslam::slam

#endif  // IRSLAM_SLAM_RELOCALIZER_H_
