// Accuracy metrics of a simulated mission against the simulator's ground truth:
// pose errors of the SLAM estimate and of dead reckoning, mapped wall-line errors.
// The estimate lives in the SLAM's internal frame (the odometry frame of the
// start); it is put in the world frame through the true start pose, exactly like
// the truth file's odometry baseline (contracts §5), so both are judged alike.
#ifndef IRSLAM_TESTS_TOOLS_METRICS_H_
#define IRSLAM_TESTS_TOOLS_METRICS_H_

#include <cstdint>
#include <ctime>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "slam/slam.h"
#include "sim/coverage.h"
#include "sim/world.h"

namespace irslam::metrics {

// This thread's CPU time (ns): the work per control period measured without
// what the other processes of a loaded host took (sim::RunInProcess's clock).
inline int64_t ThreadCpuNs() {
  timespec ts{};
  ::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec;
}

struct PoseErrors {
  double final_position_m = 0;
  double final_heading_rad = 0;
  double rms_position_m = 0;
  double rms_heading_rad = 0;
  double max_position_m = 0;
};

// Errors of `est` against `truth` (both in the world frame), matched by time.
// Clutter: an object no side of which is longer than kClutterM (the
// generator's chair legs and posts, 2-6 cm: too thin for the beams, never
// mapped, not pieces the model must find).
constexpr double kClutterM = 0.06;
bool IsClutter(const sim::Box& b);
// Whether a contact with the robot's centre at (x, y) touched clutter: the
// nearest of the room's walls and the objects is clutter (else a wall or a
// piece of furniture).
bool ContactWithClutter(const sim::World& world, double x, double y);

// An ablation of the error envelope (irslam-report --noise-nominal): each key
// of `csv` (comma-separated sim::SimNoiseKeys names) set back to its nominal
// value (sim::SimNoise's default), so a campaign measures what one effect
// costs. False, and a one-line *error naming the key, for an unknown key.
bool SetNoiseNominal(const std::string& csv, sim::SimNoise* noise, std::string* error);

PoseErrors ComparePoses(const std::vector<TimedPose>& est, const std::vector<TimedPose>& truth);
// Position error at time t (nearest samples).
double PositionErrorAt(const std::vector<TimedPose>& est, const std::vector<TimedPose>& truth, double t);

std::vector<TimedPose> ToWorld(const std::vector<TimedPose>& internal, const Pose2& start);

struct LineError {
  int id = 0;
  double signed_angle_rad = 0;   // mapped - true
  double signed_offset_m = 0;    // mean signed offset along the true wall's normal (+x or +y)
  bool vertical = false;         // the true segment is parallel to y
  bool wall = false;         // matched a wall of the room (else a box side)
  double distance_m = 0;     // mean distance of the mapped end points from the true line
  double angle_rad = 0;
  double length_m = 0;
};

// Matches each mapped line (internal frame) with the true wall or box side it
// lies along (within 15 cm and 6 deg); unmatched lines are reported as not found.
std::vector<LineError> CompareLines(const std::vector<slam::LineFeature>& lines, const Pose2& start,
                                    const sim::World& world, int* unmatched);

// The rigid correction (about the start position) that best aligns the mapped
// lines with the true ones they were matched to: the map frame is arbitrary (it is
// defined by the first wall), so the map's own geometry is judged after it.
Pose2 BestAlignment(const std::vector<slam::LineFeature>& lines, const Pose2& start,
                    const sim::World& world);
// Applies a correction from BestAlignment to the start pose used for comparisons.
Pose2 CorrectStart(const Pose2& start, const Pose2& correction);
// The start pose in the room's frame: world.start corrected by the best
// alignment of `lines` (CorrectStart of BestAlignment), so a map turned or
// shifted as a whole is judged by its shape alone.
Pose2 RoomFrameStart(const std::vector<slam::LineFeature>& lines, const sim::World& world);

// Objects of a map (contracts §4) against the true furniture: touching boxes (and
// boxes under 10 cm apart) form one compound piece; a piece touching a wall is wall-contact. A piece nearer a
// wall than `impassable_gap_m` (e.g. the robot's diameter: the robot can neither
// pass through the gap nor see the side facing the wall) is wall-contact as far as
// the robot can tell, so both kinds count as right for it and its wall-facing
// side is left out of the edge error, as a touching piece's is. 0 judges the kind
// by touching alone.
struct ObjectScores {
  int pieces = 0, found = 0, kind_right = 0, complete = 0, extra = 0;
  int good = 0;           // found with IoU >= 0.5 and the kind right (the campaign's measure)
  int good_complete = 0;  // ... and marked complete
  double max_edge_m = 0;  // largest box-edge error over complete found pieces (wall sides excluded)
  double mean_iou = 0;
};
ObjectScores ScoreObjects(const nlohmann::json& map, const slam::Slam& slam, const sim::World& world,
                          double impassable_gap_m);

// Cleaning coverage against the truth (issue 13): sim/coverage.h, shared with
// irslam-sim run --baseline bounce.
using sim::CoverageScore;
using sim::ScoreCoverage;

}  // namespace irslam::metrics

#endif  // IRSLAM_TESTS_TOOLS_METRICS_H_
