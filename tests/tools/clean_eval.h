// Cleaning scored against the simulator's truth (issue 13): a `clean` mission
// run in process, the true body disc's coverage of the reachable floor while
// cleaning, the path against the area over the cleaning width, contacts, pose
// error and the distance from the start at the end; and the random-bounce
// baseline (sim/bounce.h) for the same robot time.
#ifndef IRSLAM_TESTS_TOOLS_CLEAN_EVAL_H_
#define IRSLAM_TESTS_TOOLS_CLEAN_EVAL_H_

#include <string>
#include <utility>
#include <vector>

#include "robot/robot_core.h"
#include "sim/world.h"

namespace irslam::metrics {

struct CleanScore {
  std::string world;
  uint64_t seed = 0;
  std::string end_state;
  std::string reason;
  bool cleaned = false;        // cleaning ran and the mission ended done
  double explore_s = 0;        // robot time when cleaning began
  double clean_s = 0;          // cleaning (not going home)
  double reachable_m2 = 0;     // truth: floor the body can reach from the start
  double covered_m2 = 0;       // truth: swept by the body while cleaning
  double coverage = 0;         // covered / reachable
  double covered_total = 0;    // ... counting the exploration before it too
  double estimated_fraction = 0;  // the robot's own estimate (status.cleaning.fraction)
  double path_m = 0;           // estimated cleaning path (status.cleaning.path_m)
  double path_ratio = 0;       // path_m / (reachable_m2 / cleaning width)
  double unreachable_m2 = 0;
  int cells = 0, cells_done = 0;
  int contacts_cleaning = 0;   // contacts with anything while cleaning or going home
  // ... of them with clutter (metrics::ContactWithClutter: chair legs, posts);
  // the rest touched walls or furniture (the issue's "no contact with mapped
  // furniture", clutter counted apart).
  int contacts_clutter = 0;
  double rms_position_m = 0;   // pose error while cleaning
  double home_error_m = 0;     // true end position to the true start
  double cross_track_rms_m = 0;
  double bounce_coverage = 0;  // the random-bounce baseline, same robot time as cleaning
  std::vector<std::pair<double, double>> curve, bounce_curve;  // (s since cleaning began, fraction)
};

CleanScore RunAndScoreClean(const sim::World& world, const robot::CoreOptions& options, uint64_t seed,
                            double max_time_s, bool with_bounce);

}  // namespace irslam::metrics

#endif  // IRSLAM_TESTS_TOOLS_CLEAN_EVAL_H_
