// Furniture that moved since the saved map was made (issue 14). After a
// relocalisation (or a start in the live map), each side of a saved object is
// watched: where the robot passes it in view (on the side it was seen from,
// within the IR mapping range, the side ahead or beside the robot) its length
// is marked, and a side passed in view along most of its length but never
// matched again by the SLAM is missing; so is a side the SLAM has stretched
// between its saved corners (the piece moved along it). An object with enough
// missing sides has moved (or gone); so has a complete one whose side the SLAM
// has stretched past the object's box (a side of a closed box cannot reach
// beyond its corners: moved along that side, whose saved part may have been
// short of them). Its lines leave the map, and the modeller is told, so that
// the piece found elsewhere with the same size keeps its id with a note
// (room_model.h Modeler::NoteMoved), rather than the map silently holding both.
// Bounded work: O(watched sides x map lines) per period (each undecided side's
// line is looked up once). Pure.
#ifndef IRSLAM_CONTROL_MAP_CHANGES_H_
#define IRSLAM_CONTROL_MAP_CHANGES_H_

#include <algorithm>
#include <vector>

#include "control/room_geometry.h"
#include "control/room_model.h"
#include "slam/slam.h"
#include "types/geometry.h"
#include "types/options.h"

namespace irslam::control {

struct MapChangeOptions {
  // A side is in view from this perpendicular distance (of the robot's
  // centre) ...: the sensors sit 5 cm from the centre and read nothing under
  // 0.2 m, so a side nearer than 0.25 m is not seen; counted as passed in view
  // (0.12 until 2026-12-05), passes that near made a side that had not moved
  // "missing" (a kidnap test run lost a saved piece's ids so).
  double view_min_m = 0.27;
  double view_max_m = 0.55;       // ... up to this (well inside the mapping range)
  double view_bearing_rad = 1.75; // ... and within this of the heading (the sensors look ahead and sideways)
  double bin_m = 0.05;            // a side's length is marked in bins of this
  double seen_fraction = 0.7;     // passed in view along this share: it should have been seen again
  double min_side_m = 0.2;        // shorter sides are not watched
  // The part of a side within this of a wall is not asked for: the robot's
  // centre stays a body radius and more from the wall, so the end side of a
  // piece against it (0.5 m deep) could never be passed along seen_fraction
  // of its length (a piece moved along its wall went unnoticed).
  double wall_margin_m = 0.25;
  int min_missing_sides = 2;      // an object with this many sides missing has moved or gone
  // A side the SLAM has stretched by more than this (the piece moved along
  // it: its new place is collinear with the old, and the line grows over
  // both) is missing too, wherever the robot is; only a side both of whose
  // ends met a line across it (within corner_m) when watching began: a side
  // seen in part before (its end in the open, or at a collinear piece of
  // itself) grows when seen whole.
  double stretched_m = 0.3;
  double corner_m = 0.1;
  // A side of a complete object reaching more than stretched_m past the
  // object's box (its saved model) shows the move alone, without a second
  // missing side: fig20's box moved along its wall was saved with its long
  // side short of the far corner (not bounded) and its end sides at the wall
  // or hidden by the piece's new place, so no second side could go missing.
  bool past_box_moves = true;
};
options::Table<MapChangeOptions> MapChangeKeys();  // [relocalize] too

class MapChanges {
 public:
  explicit MapChanges(MapChangeOptions options) : options_(options) {}

  // Watches the objects' sides of `model` (map frame lines and the trajectory
  // they were seen from) from now on; nothing is watched after Clear.
  // axis_tolerance_rad: the modeller's ([model]), so the sides are the model's.
  void Reset(const std::vector<slam::LineFeature>& lines, const std::vector<TimedPose>& trajectory,
             const EnvironmentModel& model, double axis_tolerance_rad);
  void Clear() { sides_.clear(); }
  // One period at map pose `me`; `lines` is the SLAM's map (map frame, ids).
  // Returns the ids of objects found moved in this period (each object once).
  std::vector<int> Step(const Pose2& me, const std::vector<slam::LineFeature>& lines);
  // Object `id` was found moved elsewhere (the IR check): not reported again.
  void Reported(int object_id) {
    if (std::find(reported_.begin(), reported_.end(), object_id) == reported_.end()) reported_.push_back(object_id);
  }

 private:
  struct Watched {
    room_geometry::Side side;
    int object = 0;
    int observations = 0;  // the line's count when watching began
    std::vector<bool> passed;
    size_t first = 0, last = 0;  // the bins [first, last) asked for (wall_margin_m)
    bool bounded = false;        // both ends met another line (corner_m)
    bool boxed = false;          // a side of a complete object: it lies within ...
    double box_lo = 0, box_hi = 0;  // ... this extent of the object's box along it
    bool missing = false;
    bool decided = false;  // seen again, or judged missing
  };
  // l: w's line in the map now, nullptr if it was merged into another.
  bool SeenAgain(const Watched& w, const slam::LineFeature* l) const;
  bool Stretched(const Watched& w, const slam::LineFeature* l) const;
  bool PastItsBox(const Watched& w, const slam::LineFeature* l) const;
  // w is missing: the object's id if it has now moved (once), else 0.
  // conclusive: w alone shows the move (PastItsBox).
  int Missing(Watched* w, bool conclusive = false);

  MapChangeOptions options_;
  std::vector<Watched> sides_;
  std::vector<int> reported_;
};

}  // namespace irslam::control

#endif  // IRSLAM_CONTROL_MAP_CHANGES_H_
