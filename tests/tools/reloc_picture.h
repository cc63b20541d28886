// One picture of relocalisation's pose hypotheses (issue 14, docs/relocalization.md):
// a saved map made by one exploration mission, then a start from another pose
// in it; at the last search before the commit that still kept several
// hypotheses, each hypothesis places the local map (the lines and trajectory
// the robot has seen so far, in its own start frame) on the saved map. Drawn:
// the saved lines, and per hypothesis (best first) the local lines and
// trajectory through its transform with its score, explained and conflicting
// evidence; the true trajectory through the map -> world fit (reloc_eval.h).
#ifndef IRSLAM_TESTS_TOOLS_RELOC_PICTURE_H_
#define IRSLAM_TESTS_TOOLS_RELOC_PICTURE_H_

#include <string>
#include <vector>

#include "robot/robot_core.h"
#include "sim/world.h"
#include "slam/relocalizer.h"

namespace irslam::metrics {

// What the search held at one moment.
struct HypothesisSnapshot {
  double t = -1;  // robot time (-1: never ambiguous)
  std::vector<slam::PoseHypothesis> hypotheses;  // best first
  std::vector<slam::LineFeature> local_lines;    // the local map's internal frame
  std::vector<TimedPose> local_trajectory;       // its internal frame
  std::vector<TimedPose> truth;                  // world frame, up to t
  double evidence_m = 0;
  double commit_t = -1;  // when the run committed (-1: it did not)
};

struct RelocPicture {
  std::string world;
  uint64_t seed = 0;
  Pose2 start;                          // world frame
  std::vector<slam::LineFeature> saved_lines;  // the saved map's frame
  Pose2 map_to_world;
  HypothesisSnapshot snapshot;
};

// Maps the world from its start (seed), then tries the first `tries` random
// free starts (reloc_eval's sampler, same seeds) until one goes through a
// moment with at least two hypotheses before it commits; returns that run's
// picture (snapshot.t < 0 when none did).
RelocPicture CaptureHypotheses(const sim::World& world, const robot::CoreOptions& options, uint64_t seed,
                               int tries = 10);

// The SVG: the saved map, the hypotheses (at most max_shown) and the truth.
std::string HypothesesSvg(const RelocPicture& p, int max_shown = 4);

}  // namespace irslam::metrics

#endif  // IRSLAM_TESTS_TOOLS_RELOC_PICTURE_H_
