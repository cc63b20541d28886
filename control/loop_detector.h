// Loop detection while following the room's walls: an anchor pose is taken once
// the follower has been steady for a while (so it lies on the path the robot will
// come back along), and another every loop_anchor_spacing_m of steady following
// after it; the loop closes when the robot is back near any anchor, at about its
// heading, after covering a minimum distance since it. The net turn since that
// anchor tells the room (walked counter-clockwise with the wall on the right,
// +2 pi) from the outside of a free object (clockwise, -2 pi).
// More than one anchor: the first steady following is not always on the loop
// the robot then walks for ever - it can follow a piece of furniture for a
// while, leave it for the room's wall at a corner, and go round the room
// without passing that first anchor again (the generated rooms: 14 of 200
// nominal missions circled the room until the mission's time limit).
// A free object can also be circled without ever following it steadily (a
// small box whose sides are shorter than the follower needs to settle: the
// robot orbits it at the lost-wall distance, and no anchor is ever taken): so
// the heading is also followed all the time, and a net clockwise turn of
// loop_orbit_turn_rad from its most counter-clockwise value is a free object
// as well. Following the room (wall on the right) turns +2 pi per loop; going
// round furniture standing at a wall turns at most about -pi on the way, so a
// full clockwise turn and then some is only seen round a free object. Pure.
#ifndef IRSLAM_CONTROL_LOOP_DETECTOR_H_
#define IRSLAM_CONTROL_LOOP_DETECTOR_H_

#include <cstddef>
#include <vector>

#include "types/geometry.h"
#include "types/options.h"

namespace irslam::control {

struct LoopOptions {
  double loop_min_distance_m = 3.0;   // wall following must cover this before a loop can close
  double loop_close_radius_m = 0.25;  // back within this of where wall following started
  double loop_close_angle_rad = 0.7;  // ... and within this of its heading
  double loop_anchor_steady_s = 1.5;  // the anchor is taken after this long of steady following
  double loop_anchor_spacing_m = 1.0;  // ... and another every this much of steady following
                                       // (the last kMaxAnchors are kept; more than the
                                       // distance walked: the first anchor only, as before)
  double loop_free_object_turn_rad = M_PI;  // a loop that turned more than this clockwise went
                                            // round a free object, not the room
  double loop_orbit_turn_rad = 2 * M_PI + 1.0;  // net clockwise turn (steady or not) that is a
                                                // free object circled
};
options::Table<LoopOptions> LoopKeys();

enum class LoopEvent {
  kNone,
  kRoom,        // a loop of the room closed (the anchor stays until Rearm)
  kFreeObject,  // a loop round a free object closed; the anchor is dropped
};

class LoopDetector {
 public:
  static constexpr size_t kMaxAnchors = 256;

  explicit LoopDetector(LoopOptions options) : options_(options) { anchors_.reserve(kMaxAnchors); }

  // Starts over (no anchor).
  void Reset() {
    anchors_.clear();
    have_heading_ = false;
  }
  // One step of wall following: steady is WallFollower::steady(), distance_m the
  // odometric distance covered so far; searching: the follower has no wall
  // (finding one, aligning to it, or leaving one): the orbit check starts over
  // (its in-place turns are not a way round anything).
  LoopEvent Update(double t, bool steady, const Pose2& pose, double distance_m,
                   bool searching = false);
  // After a room loop: the next loop starts here (the only anchor).
  void Rearm(const Pose2& pose, double distance_m);
  bool has_anchor() const { return !anchors_.empty(); }
  size_t anchors() const { return anchors_.size(); }
  // The anchor of the loop that closed last (before any: the first anchor).
  const Pose2& anchor() const { return anchor_.pose; }
  // Net heading change since that anchor (+: counter-clockwise).
  double turned() const { return heading_ - anchor_.heading; }
  // Net clockwise turn since the most counter-clockwise heading (the orbit check).
  double orbit_turned() const { return heading_peak_ - heading_; }

 private:
  LoopOptions options_;
  struct Anchor {
    Pose2 pose;
    double heading = 0;   // heading_ there
    double distance = 0;  // the distance covered there
  };
  void AddAnchor(const Pose2& pose, double distance_m);

  double follow_since_ = -1;  // steady following since then (-1: not steady)
  std::vector<Anchor> anchors_;  // oldest first; at most kMaxAnchors (reserved)
  Anchor anchor_;                // see anchor()
  // The heading unwrapped since Reset (the sum of the turns between updates),
  // and the orbit check's most counter-clockwise value of it since the follower
  // last searched.
  bool have_heading_ = false;
  double last_theta_ = 0;
  double heading_ = 0;
  double heading_peak_ = 0;
};

}  // namespace irslam::control

#endif  // IRSLAM_CONTROL_LOOP_DETECTOR_H_
