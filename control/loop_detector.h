// Loop detection while following the room's walls: an anchor pose is taken once
// the follower has been steady for a while (so it lies on the path the robot will
// come back along); the loop closes when the robot is back near the anchor, at
// about its heading, after covering a minimum distance. The net turn since the
// anchor tells the room (walked counter-clockwise with the wall on the right,
// +2 pi) from the outside of a free object (clockwise, -2 pi). Pure.
#ifndef IRSLAM_CONTROL_LOOP_DETECTOR_H_
#define IRSLAM_CONTROL_LOOP_DETECTOR_H_

#include "types/geometry.h"
#include "types/options.h"

namespace irslam::control {

struct LoopOptions {
  double loop_min_distance_m = 3.0;   // wall following must cover this before a loop can close
  double loop_close_radius_m = 0.25;  // back within this of where wall following started
  double loop_close_angle_rad = 0.7;  // ... and within this of its heading
  double loop_anchor_steady_s = 1.5;  // the anchor is taken after this long of steady following
  double loop_free_object_turn_rad = M_PI;  // a loop that turned more than this clockwise went
                                            // round a free object, not the room
};
options::Table<LoopOptions> LoopKeys();

enum class LoopEvent {
  kNone,
  kRoom,        // a loop of the room closed (the anchor stays until Rearm)
  kFreeObject,  // a loop round a free object closed; the anchor is dropped
};

class LoopDetector {
 public:
  explicit LoopDetector(LoopOptions options) : options_(options) {}

  // Starts over (no anchor).
  void Reset() { have_anchor_ = false; }
  // One step of wall following: steady is WallFollower::steady(), distance_m the
  // odometric distance covered so far.
  LoopEvent Update(double t, bool steady, const Pose2& pose, double distance_m);
  // After a room loop: the next loop starts here.
  void Rearm(const Pose2& pose, double distance_m);
  bool has_anchor() const { return have_anchor_; }
  const Pose2& anchor() const { return anchor_; }
  // Net heading change since the anchor (+: counter-clockwise).
  double turned() const { return turned_since_anchor_; }

 private:
  LoopOptions options_;
  double follow_since_ = -1;  // steady following since then (-1: not steady)
  bool have_anchor_ = false;
  Pose2 anchor_;
  Pose2 last_pose_;
  double turned_since_anchor_ = 0;
  double anchor_distance_ = 0;
};

}  // namespace irslam::control

#endif  // IRSLAM_CONTROL_LOOP_DETECTOR_H_
