// Reactive wall following with the right-hand rule (paper §5, exploration step 1):
// find a wall, turn so it is on the right, then keep it at follow_distance_m while
// driving at cruise speed; turn left in place at inner corners, arc right around
// outer corners. Works on the latest IR ranges only; pure (time is an argument).
#ifndef IRSLAM_CONTROL_WALL_FOLLOWER_H_
#define IRSLAM_CONTROL_WALL_FOLLOWER_H_

#include <array>
#include <optional>

#include "slam/slam.h"
#include "types/geometry.h"
#include "types/options.h"
#include "types/signals.h"

namespace irslam::control {

struct WallFollowerOptions {
  double follow_distance_m = 0.40;  // robot centre to the wall on the right
  double cruise_speed_mps = 0.20;
  double front_stop_m = 0.45;  // obstacle this close ahead (from the centre): inner corner
  double front_slow_m = 0.80;  // start slowing down below this
  double k_distance = 2.5;     // rad/s per metre of distance error
  double k_angle = 2.0;        // rad/s per radian of wall angle
  double max_turn_rate_rad_s = 1.2;
  double turn_rate_rad_s = 0.8;      // in-place turns at inner corners
  double lost_wall_margin_m = 0.30;  // wall farther than follow + this is "lost"
  double outer_arc_speed_mps = 0.12;
  double backoff_speed_mps = 0.08;
  double backoff_time_s = 0.6;
  double backoff_turn_rad = 0.5;
  // Boxed in: a whole inner-corner turn found nothing clear ahead (legs under a
  // table all round). Drive out the most open way seen in that turn, slowly, this
  // far at most, stopping this close to what is ahead (0: never; the robot turned
  // on the spot until the time limit).
  double squeeze_distance_m = 0.5;
  double squeeze_speed_mps = 0.08;
  double squeeze_stop_m = 0.25;
};
options::Table<WallFollowerOptions> WallFollowerKeys();  // [wall_follow]

// Which case of the follower is active (shown in status).
enum class FollowMode { kFind, kAlign, kFollow, kInnerCorner, kOuterCorner, kBackoff, kLeave, kSqueeze };
const char* ToString(FollowMode m);

struct Twist {
  double v = 0;      // m/s
  double omega = 0;  // rad/s, positive = left
};

// The right wall as seen from the robot centre.
struct WallEstimate {
  double distance_m = 0;
  double angle_rad = 0;  // wall direction relative to the heading (+: wall turns left/closer)
  // Only the side sensor sees it (the diagonal one sees nothing within range):
  // not a wall alongside but its end - the corner being passed.
  bool corner = false;
};

class WallFollower {
 public:
  WallFollower(WallFollowerOptions options, const std::array<SensorMount, kNumIrSensors>& mounts,
               double robot_radius_m);

  // One control step at robot time t with the latest scan; bumped: a bumper is pressed.
  // sensor_scan: the sensors' own readings when scan has remembered contacts
  // added (BumpMemory::Apply): driving out when boxed in goes by them alone.
  Twist Step(double t, const RangeScan& scan, bool bumped, const RangeScan* sensor_scan = nullptr);
  void Reset();
  // Turn away (left, a quarter turn) from what is being followed and look for
  // another wall: used when the contour followed was a free object, not the room.
  void Leave(double t);
  // Start following at once (the robot was placed beside a side, heading along it).
  void StartFollowing(double t);
  // Go round a corner seen by the side sensor alone at the follow distance
  // (contour following of free objects: small boxes, short sides) instead of
  // taking it as a wall alongside (following the room, tuned for its accuracy).
  void SetOrbitCorners(bool on) { orbit_corners_ = on; }
  FollowMode mode() const { return mode_; }
  // No wall being followed: finding one, turning to it, or leaving one.
  bool searching() const {
    return mode_ == FollowMode::kFind || mode_ == FollowMode::kAlign || mode_ == FollowMode::kLeave;
  }
  // True once a wall has been found and followed.
  bool following() const { return has_followed_; }
  // Following, parallel to the wall at the follow distance (within 5 cm, ~5 deg).
  bool steady() const { return mode_ == FollowMode::kFollow && steady_; }

  // Exposed for tests.
  std::optional<WallEstimate> RightWall(const RangeScan& scan) const;
  std::optional<double> FrontDistance(const RangeScan& scan) const;
  // The same in a corridor of this half width (what the body itself would hit:
  // the robot's radius).
  std::optional<double> FrontDistance(const RangeScan& scan, double half_width_m) const;

 private:
  void Enter(FollowMode m, double t);
  // The modes other than following: their twist (and mode changes).
  Twist StepMode(double t, std::optional<double> front, const std::optional<WallEstimate>& wall,
                 bool bumped);
  // At an inner corner: turning left until clear ahead (or boxed in: squeeze).
  Twist InnerCorner(double t, std::optional<double> front);
  // Boxed in: driving out the most open way of the last whole turn.
  Twist Squeeze(double t);
  // Following the wall on the right (or leaving following at a corner).
  Twist Follow(double t, std::optional<double> front, const std::optional<WallEstimate>& wall);

  WallFollowerOptions options_;
  std::array<SensorMount, kNumIrSensors> mounts_;
  double robot_radius_m_;
  FollowMode mode_ = FollowMode::kFind;
  double mode_since_ = 0;
  double last_t_ = 0;
  double turned_rad_ = 0;  // rotation accumulated in the current mode
  // kInnerCorner: the largest distance ahead in the turn's first revolution, and
  // the rotation it was seen at (where kSqueeze drives out).
  double corner_best_front_ = 0;
  double corner_best_turn_ = 0;
  std::optional<double> body_front_;  // FrontDistance in the body's own width, this step
  bool backoff_forward_ = false;  // this backoff cycle drives forward (still in contact after one)
  bool has_followed_ = false;
  bool steady_ = false;
  bool orbit_corners_ = false;
};

}  // namespace irslam::control

#endif  // IRSLAM_CONTROL_WALL_FOLLOWER_H_
