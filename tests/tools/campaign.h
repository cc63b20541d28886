// The random-world campaign (issue 11): generated worlds (sim/generator.h) run
// through the whole mission in process, every run scored against the simulator's
// truth and every failure classified, so robustness is a measured property of the
// distribution of rooms and robots, not of eight hand-made worlds.
#ifndef IRSLAM_TESTS_TOOLS_CAMPAIGN_H_
#define IRSLAM_TESTS_TOOLS_CAMPAIGN_H_

#include <cstdint>
#include <string>
#include <vector>

#include "robot/robot_core.h"
#include "sim/generator.h"

namespace irslam::campaign {

struct RunScore {
  uint64_t seed = 0;
  sim::NoiseProfile profile = sim::NoiseProfile::kNominal;
  std::string world;             // its name
  bool done = false;             // the mission ended `done` within the time limit
  std::string end_state;         // the state at the end
  double robot_time_s = 0;
  int pieces = 0;                // true furniture pieces (touching boxes are one; clutter not counted)
  int good = 0;                  // ... found with IoU >= 0.5 and the kind right
  int complete = 0;              // ... of those, marked complete
  int extra = 0;                 // mapped objects matching no true piece
  double max_edge_m = 0;         // largest box-edge error over complete pieces
  double final_position_m = 0, final_heading_rad = 0, rms_position_m = 0, max_position_m = 0;
  double odom_final_position_m = 0;
  // The largest position error in the room's frame: the start pose corrected by
  // the map's best alignment to the true walls (metrics::BestAlignment), so a
  // map turned or shifted as a whole (heading drift before the first wall is
  // seen, which no observation can undo) does not count, its distortion does.
  double room_max_position_m = 0;
  int contacts_furniture = 0;    // contacts with walls or furniture
  int contacts_clutter = 0;      // contacts with legs and posts (<= 6 cm)
  // Odometry self-calibration: the estimated wheel radius ratio (right/left)
  // against the world's true one, relative, at the end of the first
  // wall-following loop (the mission leaves wall_follow), or at the end of the
  // run when that never happened (ratio_at_loop false).
  double ratio_error = 0;
  bool ratio_at_loop = false;
  // The control loop's work per period (issue 15), this host's clock (ms).
  double tick_p99_ms = 0, tick_max_ms = 0;
  std::string tick_phase;        // what took the largest period
  // The same run re-measured (RemeasureWorstPeriods; < 0: not re-run).
  double tick_max_alone_ms = -1;
  std::string tick_phase_alone;
  double x_realtime = 0;         // robot time / wall time of the run
  std::vector<std::string> failures;  // the failure classes of this run (empty: a good run)
};

// One generated world, run and scored. max_time_s: the mission's time limit.
// noise_nominal: noise keys set back to nominal (metrics::SetNoiseNominal; an
// ablation), already checked.
RunScore RunAndScore(uint64_t seed, sim::NoiseProfile profile, const robot::CoreOptions& options,
                     double max_time_s, const std::string& noise_nominal = "");

// Seeds first_seed .. first_seed + count - 1 of one profile on `jobs` threads
// (the core has no global state); results in seed order.
std::vector<RunScore> RunCampaign(sim::NoiseProfile profile, uint64_t first_seed, int count,
                                  const robot::CoreOptions& options, int jobs,
                                  const std::string& noise_nominal = "");

// The rates the targets are stated in (fractions; contacts per run).
struct Rates {
  int runs = 0;
  double done = 0, pieces_good = 0, pieces_complete = 0, pose_ok = 0, lost = 0;
  double lost_in_room = 0;  // runs whose room_max_position_m exceeds 20 cm (no target: a diagnosis)
  double furniture_contacts_per_run = 0;
  double ratio_within = 0;  // runs whose ratio_error is within 0.1 %
};
Rates Summarise(const std::vector<RunScore>& runs);

// The `count` runs with the largest period, and every run with a period over
// `above_ms`, run again one at a time after the campaign: the least of up to
// three (stopping at one under 10 ms) is tick_max_alone_ms. This VM charges a
// thread's CPU clock with time it did not run while the host is busy (single
// periods of 100-101 ms in any phase, in campaigns and in a run alone on a
// loaded machine); the run is deterministic, so only the host differs.
void RemeasureWorstPeriods(std::vector<RunScore>* runs, const robot::CoreOptions& options, int count,
                           double above_ms, const std::string& noise_nominal = "");

// docs/robustness.md (and its SVG histograms, written beside it).
std::string RobustnessReport(const std::vector<std::vector<RunScore>>& by_profile, const std::string& out_dir,
                             const std::string& command);

}  // namespace irslam::campaign

#endif  // IRSLAM_TESTS_TOOLS_CAMPAIGN_H_
