// Bump memory: where the bumpers hit something the IR beams missed (a chair leg
// between the beams, a box corner), remembered in the internal frame, and shown
// to the followers as virtual beam readings and to the planner as obstacles.
// Pure.
#ifndef IRSLAM_CONTROL_BUMP_MEMORY_H_
#define IRSLAM_CONTROL_BUMP_MEMORY_H_

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <vector>

#include "types/geometry.h"
#include "types/options.h"
#include "types/robot.h"
#include "types/signals.h"

namespace irslam::control {

struct BumpMemoryOptions {
  double bump_contact_angle_rad = 0.6;  // bearing of a contact when only one bumper is pressed
  double bump_contact_offset_m = 0.02;  // the contact lies this far beyond the body's edge
  double bump_min_spacing_m = 0.03;     // a contact this close to the last one is not new
  double bump_reach_m = 1.0;            // contacts farther than this from the robot are ignored
  double bump_beam_half_width = 0.5;    // a beam sees a contact within this many robot radii
                                        // of its axis (the body would sweep into it)
  double bump_min_range_m = 0.05;       // shortest virtual reading
};
options::Table<BumpMemoryOptions> BumpMemoryKeys();

class BumpMemory {
 public:
  BumpMemory(BumpMemoryOptions options, const std::array<SensorMount, kNumIrSensors>& mounts,
             double robot_radius_m)
      : options_(options), mounts_(mounts), radius_m_(robot_radius_m) {}

  // Bearing of the contact relative to the heading from the bumper bits (bit0
  // left, bit1 right; both: straight ahead).
  double ContactBearing(uint8_t bumpers) const;
  // Remembers the contact of pressed bumpers at the robot's pose (no-op if none).
  void Record(const Pose2& me, uint8_t bumpers);
  // The scan with every remembered contact a beam would see added as a reading;
  // only those recorded from index `from` on (relocalising, the others are in
  // the map's frame, not the fresh local SLAM's `me` is in), and none closer
  // than skip_within_m to the robot's centre (under its body; 0: none left out).
  RangeScan Apply(const RangeScan& scan, const Pose2& me, size_t from = 0, double skip_within_m = 0) const;
  // An obstacle known otherwise than by a bumper, remembered as a contact (the
  // mouth of a pen left: mission.h).
  void Mark(const Eigen::Vector2d& p) { points_.push_back(p); }
  const std::vector<Eigen::Vector2d>& points() const { return points_; }
  // The contacts recorded from index `from` on were in another frame: moves
  // them by t (a point in that frame -> this one). Issue 14: the bumps of a
  // relocalisation, recorded in the local SLAM's frame, join the saved map's.
  void TransformSince(size_t from, const Pose2& t);

 private:
  BumpMemoryOptions options_;
  std::array<SensorMount, kNumIrSensors> mounts_;
  double radius_m_;
  std::vector<Eigen::Vector2d> points_;  // internal frame
};

}  // namespace irslam::control

#endif  // IRSLAM_CONTROL_BUMP_MEMORY_H_
