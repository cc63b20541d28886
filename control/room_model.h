// Environment modelling from the line map (paper §5): the Room (bottom, right,
// top, left walls, each one or more collinear lines), wall-contact objects (the
// side against the wall is never seen: 3 lines), free objects (4 lines),
// compound furniture (touching boxes: one object with more lines), incomplete
// objects (open ends). Pure: lines and trajectory in (map frame: the first wall
// along x, so lines are axis-aligned), model out. Object ids are kept stable
// between calls by matching boxes.
#ifndef IRSLAM_CONTROL_ROOM_MODEL_H_
#define IRSLAM_CONTROL_ROOM_MODEL_H_

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "slam/slam.h"
#include "types/options.h"

namespace irslam::control {

struct ModelOptions {
  double axis_tolerance_rad = 0.12;  // lines this close to an axis count as axis-aligned
  double collinear_m = 0.08;         // pieces of one wall/side: offsets within this
  double corner_m = 0.35;            // two sides meet: their corner within this of an end
                                     // (gaps narrower than the robot are not passable anyway)
  double wall_contact_m = 0.30;      // an object this close to a wall touches it: the robot
                                     // (0.34 m across) can neither pass the gap nor see the side
                                     // facing the wall (0.15 until 2026-12-06: pieces 0.15-0.3 m
                                     // off a wall waited for a side no pass could map)
  double wall_reach_m = 0.35;        // a side ending this close to a wall (along it) runs into it
  double same_size_m = 0.15;         // a moved piece is recognised by its size within this
  double merge_touching_m = 0.20;    // incomplete objects whose boxes are this close are pieces
                                     // of one (compound furniture whose step was not mapped, a
                                     // piece's sides that no corner joined; 0: off)
  double trace_band_m = 0.6;         // a contour along the wall (a free object's own, beside
                                     // the edge) this close to the middle of a box edge,
                                     // outside it, went past that side
  double narrow_gap_m = 0.9;         // a free object's one unmapped side facing a wall closer
                                     // than this is inferred once its contour has left it along
                                     // that wall: the robot, keeping the follow distance (0.40 m)
                                     // from both and stopping 0.45 m before the wall, cannot go
                                     // between (0: off)
};
options::Table<ModelOptions> ModelKeys();  // [model]

struct Box {
  double xmin = 0, ymin = 0, xmax = 0, ymax = 0;
  double width() const { return xmax - xmin; }
  double height() const { return ymax - ymin; }
};

struct RoomModel {
  // bottom, right, top, left: the ids of the collinear lines of each wall.
  std::array<std::vector<int>, 4> walls;
  std::optional<Box> box;
};

enum class ObjectKind { kWallContact, kFree };
const char* ToString(ObjectKind k);

struct ObjectModel {
  int id = 0;
  ObjectKind kind = ObjectKind::kFree;
  std::vector<int> lines;
  bool complete = false;
  Box box;
  int open_ends = 0;      // line ends that meet no other side (nor a wall)
  bool given_up = false;  // exploration could not complete it (kept: complete = false)
  std::string note;
};

struct EnvironmentModel {
  RoomModel room;
  std::vector<ObjectModel> objects;
  // Incomplete objects not given up: what exploration still has to visit.
  int pending() const;
};

class Modeler {
 public:
  explicit Modeler(ModelOptions options) : options_(options) {}

  // Builds the model from map-frame lines; `trajectory` (map frame) tells from
  // which side each line was seen. Object ids persist across calls.
  const EnvironmentModel& Update(const std::vector<slam::LineFeature>& lines,
                                 const std::vector<TimedPose>& trajectory);
  // The robot has followed the object's contour all round, along `loop` (map
  // frame): every mapped side inside the loop belongs to this one object (the
  // pieces of compound furniture, and sides whose ends were seen short of their
  // corners, are joined). If at least three of its sides are mapped, a missing
  // one is inferred from their extents and the object counts as complete
  // (noted). False if fewer sides are known.
  bool CloseByContour(int object_id, const std::vector<Eigen::Vector2d>& loop,
                      const std::vector<slam::LineFeature>& lines,
                      const std::vector<TimedPose>& trajectory);
  // A wall-contact object's free sides have been followed, along `trace` (map
  // frame: from the wall, round the object, back to the wall): if one edge of
  // its box is neither a mapped face nor against a wall, and the trace went
  // past it outside (within trace_band_m of its middle), that side is
  // inferred and the object counts as complete (noted) - the wall-contact
  // counterpart of CloseByContour. The same for a free object with three
  // sides mapped whose contour following went past its fourth and then left
  // it (along a wall, or drawn off round the room: noted "... that went past
  // it"). Any later Update applies it too. False if still incomplete.
  bool CloseAlongWall(int object_id, const std::vector<Eigen::Vector2d>& trace,
                      const std::vector<slam::LineFeature>& lines,
                      const std::vector<TimedPose>& trajectory);
  // The robot could not go round free object `object_id`: contour following
  // left it along a wall (it met the wall in the gap beside the object and
  // followed it away), or no way to its sides was found. If exactly
  // one side of its box is not a mapped face and that side faces a wall
  // within narrow_gap_m, where the robot cannot go between, the side is
  // inferred and the object counts as complete (noted). Any later Update
  // applies it too. False if still incomplete.
  bool CloseNearWall(int object_id, const std::vector<slam::LineFeature>& lines,
                     const std::vector<TimedPose>& trajectory);
  // Starts from a saved model (issue 14: a mission continuing in a saved map):
  // its objects' ids are kept by the next Update (by their boxes, as ever),
  // complete objects stay complete (a side inferred from a contour is not
  // re-inferred without the contour), given-up ones stay given up. The saved
  // trajectory tells from which side the saved lines were seen: every Update
  // puts it before the trajectory it is given.
  void Seed(const EnvironmentModel& saved, std::vector<TimedPose> saved_trajectory);
  // Object `id` of the saved map is not where it was (map_changes.h): the next
  // object found that is not in the saved map and has about its size (within
  // same_size_m) is taken to be it: it keeps its id, with a note saying where
  // it was; one modelled as new before this call is renamed so once it is
  // complete. Other objects not in the saved map are noted as new.
  void NoteMoved(int id, const Box& was);
  // Marks an object as not completable (e.g. unreachable); it stays incomplete.
  void GiveUp(int object_id, const std::string& why);
  const EnvironmentModel& model() const { return model_; }
  // A piece NoteMoved was told of has not been found again yet.
  bool moved_unplaced() const { return !moved_.empty(); }

 private:
  // Gives the new model's objects the ids of the old ones they overlap most (new
  // ids otherwise), and applies closed contours and given-up notes.
  // `passed_by`: per group, the ids of the targets whose CloseAlongWall trace
  // went past its one missing edge.
  void AssignIds(EnvironmentModel* m, const std::vector<bool>& group_in_loop,
                 const std::vector<std::vector<int>>& passed_by,
                 const std::vector<bool>& group_narrow);
  // Updates the model; whether object `object_id` is in it complete.
  bool CompleteAfterUpdate(int object_id, const std::vector<slam::LineFeature>& lines,
                           const std::vector<TimedPose>& trajectory);
  void NameNewObject(ObjectModel* obj);
  // The piece NoteMoved was told of that has obj's size: obj takes its id
  // and a "moved" note (false: none).
  bool TakeMoved(ObjectModel* obj);
  // A complete object named new earlier that is a moved piece: renamed.
  void RenameNewAsMoved(ObjectModel* obj);

  ModelOptions options_;
  EnvironmentModel model_;
  int next_id_ = 1;
  std::vector<std::pair<int, std::string>> given_up_;
  std::vector<int> closed_by_contour_;
  // Objects whose side was inferred along or near a wall or where their contour
  // went past it, or complete in a saved map: each id once, with the note's
  // inference (nullptr: none).
  std::vector<std::pair<int, const char*>> inferred_;
  std::vector<int> left_near_wall_;  // ids CloseNearWall was told of
  std::vector<std::vector<Eigen::Vector2d>> contour_loops_;  // map frame
  // CloseAlongWall's: the target's id and its trace (map frame).
  std::vector<std::pair<int, std::vector<Eigen::Vector2d>>> wall_traces_;
  std::vector<TimedPose> prior_trajectory_;  // Seed's (map frame)
  bool seeded_ = false;
  std::vector<int> saved_ids_;                     // Seed's objects
  std::vector<std::pair<int, Box>> moved_;         // NoteMoved, not found again yet
  std::vector<int> new_ids_;                       // objects named new since the saved map
  std::vector<std::pair<int, std::string>> notes_; // kept on the object while it is complete
};

}  // namespace irslam::control

#endif  // IRSLAM_CONTROL_ROOM_MODEL_H_
