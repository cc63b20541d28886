// Contour following of one object (paper §5, exploration step 2): from P1 beside
// one of its sides, follow it with the object on the right until the model says
// it is complete, until the robot has been all round it (the model then closes
// the last side from the contour, or it is tried once more), until a wall-contact
// object's free sides have been followed, or until a timeout. Also: which object
// to complete next, and where to start following it. Pure.
#ifndef IRSLAM_CONTROL_CONTOUR_FOLLOW_H_
#define IRSLAM_CONTROL_CONTOUR_FOLLOW_H_

#include <Eigen/Core>
#include <vector>

#include "control/room_model.h"
#include "control/wall_follower.h"
#include "slam/slam.h"
#include "types/options.h"

namespace irslam::control {

struct ContourOptions {
  double contour_timeout_s = 150;        // give up completing an object after this
  int contour_loops = 2;                 // times round an object before giving it up
  double contour_leave_m = 0.6;          // a wall-contact object's free sides have been followed
                                         // once the robot is this much farther than the follow
                                         // distance from it (it follows the wall away); a free
                                         // object is then asked to be closed near the wall, or
                                         // where its contour went past its missing side
  double contour_leave_after_s = 5.0;    // ... checked only after following it this long
  double contour_turn_margin_rad = 0.3;  // all round: turned 2 pi plus this (clockwise)
  double contour_trace_step_m = 0.05;    // the followed contour is recorded at this spacing
};
options::Table<ContourOptions> ContourKeys();

// The incomplete object (not given up) whose box centre is nearest the robot
// (map frame); nullptr if none.
const ObjectModel* NearestPending(const EnvironmentModel& m, const Pose2& map_pose);

// Where contour following of an object can start (map frame): at the follow
// distance from a side's centre, on the side it was seen from, heading along it
// with the object on the right.
struct ContourStart {
  Eigen::Vector2d p;
  double heading = 0;
};
// The object's sides' centres, nearest the robot first; for a wall-contact
// object, then the same beside each side's end the heading leads to, then
// beside its other end: a short side that meets a wall (the end of a piece of
// furniture against it, 0.5 m deep) has its centre too near the wall for the
// robot, and beside its free end it can start (a piece moved along its wall
// was left "P1 unreachable"; docs/relocalization.md).
std::vector<ContourStart> ContourStarts(const ObjectModel& target,
                                        const std::vector<slam::LineFeature>& lines,
                                        const std::vector<TimedPose>& trajectory,
                                        const Pose2& map_pose, double follow_distance_m);

class ContourFollow {
 public:
  enum class Status {
    kFollowing,
    kComplete,       // the model completed it from new lines
    kClosed,         // all round it, or along a wall-contact object's free sides, or a free
                     // object left along a wall too near it or after going past its missing
                     // side: the model inferred the last side
    kIncomplete,     // all round it contour_loops times, still incomplete
    kFreeSidesDone,  // a wall-contact object's free sides followed, still incomplete
    kTimedOut,
  };
  struct Result {
    Status status = Status::kFollowing;
    Twist twist;  // kFollowing
  };

  ContourFollow(ContourOptions options, double follow_distance_m)
      : options_(options), follow_distance_m_(follow_distance_m) {}

  // The object to complete next (before going to it).
  void SetTarget(int id, bool at_wall) {
    target_ = id;
    at_wall_ = at_wall;
  }
  // Following begins (the follower has been started beside the target).
  void Start(double t, double theta, int slam_windows);
  // One step; scan with bump memory applied. Updates the model through modeler.
  Result Step(double t, const slam::Slam& slam, const RangeScan& scan, bool bumped,
              WallFollower* follower, Modeler* modeler);

 private:
  // The robot is far enough from the target: a wall-contact one's free sides were followed,
  // a free one was left along a wall.
  bool LeftTarget(const EnvironmentModel& m, const Pose2& here) const;

  ContourOptions options_;
  double follow_distance_m_;
  int target_ = 0;
  bool at_wall_ = false;
  double since_ = 0;
  double turned_ = 0;  // net heading change (+: ccw)
  double last_theta_ = 0;
  int loops_done_ = 0;
  int windows_seen_ = 0;
  bool away_ = false;  // a free target: left (CloseNearWall and CloseAlongWall asked)
  std::vector<Eigen::Vector2d> trace_;  // map frame: where contour following went
};

}  // namespace irslam::control

#endif  // IRSLAM_CONTROL_CONTOUR_FOLLOW_H_
