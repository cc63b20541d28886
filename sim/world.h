// Simulated worlds (contracts.md §1): a rectangular or orthogonal-polygon room with
// axis-aligned boxes, a start pose, an optional seed and noise parameters.
#ifndef IRSLAM_SIM_WORLD_H_
#define IRSLAM_SIM_WORLD_H_

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "types/geometry.h"
#include "types/options.h"
#include "types/signals.h"

namespace irslam::sim {

struct Vec2 {
  double x = 0, y = 0;
};

struct Segment {
  Vec2 a, b;
};

struct Box {
  double xmin, ymin, xmax, ymax;
};

// Simulator noise parameters (the world file's optional "noise" object).
struct SimNoise {
  double wheel_radius_error_left = +0.0006;   // relative error of the true radius
  double wheel_radius_error_right = -0.0006;
  double slip_sigma = 0.01;                   // relative, per physics step, per wheel
  double ir_voltage_sigma_rel = 0.015;        // 1.5 % of the output voltage
  double ir_period_s = 0.038;
  double ir_period_jitter_s = 0.004;
  double ir_beam_deg = 5.0;
  // The realistic error envelope (issue 11; docs/robustness.md says where each
  // magnitude comes from). The defaults switch every effect off.
  double wheel_base_error = 0;       // relative error of the true track width
  double slip_correlation_s = 0;     // > 0: slip is correlated over this time (carpet), not
                                     // white per step, and grows with the turn rate
  double ir_surface_bias_m = 0;      // each wall and face: a fixed range bias in +- this
  double ir_max_incidence_deg = 90;  // returns beyond this incidence drop out; noise grows
                                     // as 1/cos(incidence) below it (90: off)
  double ir_outlier_rate = 0;        // this fraction of readings is a uniform random range
};

// The world file's "noise" keys (contracts.md §1 and §7), with bounds and docs.
options::Table<SimNoise> SimNoiseKeys();

struct World {
  std::string name;
  std::vector<Vec2> outline;  // closed orthogonal polygon (the room)
  std::vector<Box> objects;
  Pose2 start;
  std::optional<uint64_t> seed;
  SimNoise noise;

  std::vector<Segment> Segments() const;
  // Bounding box of the room outline.
  Box Bounds() const;
};

// Parses a world file's text; on error returns nullopt and a one-line *error
// naming the field. Unknown keys are rejected by name (a typo such as "objcts"
// must not give an empty room), and so are impossible worlds: a box outside the
// room, a start pose outside the room or inside a box.
std::optional<World> ParseWorld(std::string_view text, std::string* error);
std::optional<World> LoadWorldFile(const std::string& path, std::string* error);

// Ray cast: distance along the ray from p in direction angle to the nearest
// segment, or nullopt within max_range; *hit gets that segment's index.
std::optional<double> RayCast(const std::vector<Segment>& segs, Vec2 p, double angle,
                              double max_range, size_t* hit = nullptr);
// Distance from a point to a segment.
double PointSegmentDistance(Vec2 p, const Segment& s, Vec2* closest);
// The point of the segment nearest p (the one PointSegmentDistance measures to).
Vec2 ClosestOnSegment(Vec2 p, const Segment& s);

}  // namespace irslam::sim

#endif  // IRSLAM_SIM_WORLD_H_
