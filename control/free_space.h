// Floor seen free by the IR beams, to tell the room from a pen.
//
// The paper (section 5) takes the loop of wall following for the room's
// boundary. A loop can also close round a pen: floor enclosed by furniture and
// a wall whose gaps the robot could pass but the follower, keeping its wall
// distance, turned at (a corner taken as the room's). The beams then see floor
// beyond the pen's "walls", which no loop round the room can: outside a room's
// walls there is nothing to see. This grid counts the beams that crossed each
// cell (up to free_range_m, short of the hit) and the hits in it; after the
// loop, seen-free cells outside the modelled room box are the evidence.
// (The idea is the free-space side of an occupancy grid: Elfes, "Using
// occupancy grids for mobile robot perception and navigation", IEEE Computer
// 22(6), 1989; here only the free counts and the hits are kept, no log-odds.)
// The cells are in the SLAM frame at the poses the beams were taken from: the
// evidence is as good as the pose was then (see PenOptions). Pure; bounded
// (at most kMaxCells cells; beyond them nothing new is recorded).
#ifndef IRSLAM_CONTROL_FREE_SPACE_H_
#define IRSLAM_CONTROL_FREE_SPACE_H_

#include <Eigen/Core>
#include <array>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "control/room_model.h"
#include "types/geometry.h"
#include "types/options.h"
#include "types/robot.h"
#include "types/signals.h"

namespace irslam::control {

struct PenOptions {
  // [mission] keys.
  bool pen_check = true;             // leave a loop that went round a pen (floor seen outside it)
  double pen_open_area_m2 = 0.15;    // ... this much seen-free floor outside the room's box
  double pen_margin_m = 0.2;         // ... counted this far beyond the box
  double pen_goal_margin_m = 0.3;    // the way out: a seen-free point this far beyond the box,
  double pen_goal_clear_m = 0.08;    // ... with no hit this far beyond the robot's radius,
  double pen_goal_away_m = 0.5;      // ... and this far from where the robot went
  int pen_max_escapes = 2;           // pens left per mission; then the loop is taken as it is
  double pen_free_range_m = 1.2;     // a beam marks the floor free up to this (short of its hit)
  double pen_cell_m = 0.1;           // the grid's cells
  double pen_cover_margin_m = 0.1;   // a wall's mapped line covers this beyond its ends
};
options::Table<PenOptions> PenKeys();

// The room a loop modelled, for FreeSpace: its box (map frame) and, for each
// wall (bottom, right, top, left, as RoomModel::walls), the stretches along it
// its mapped lines cover (x for bottom and top, y for right and left). Floor
// seen beyond a covered stretch was seen through a wall: the pose was off
// when the beam was taken (drift), not a gap; only floor beyond the walls'
// uncovered stretches is a pen's evidence.
struct RoomOutline {
  Box box;
  std::array<std::vector<std::pair<double, double>>, 4> covered;
};

class FreeSpace {
 public:
  static constexpr size_t kMaxCells = 100000;  // 1000 m2 at 0.1 m cells

  FreeSpace(PenOptions options, const std::array<SensorMount, kNumIrSensors>& mounts)
      : options_(options), mounts_(mounts) {
    cells_.reserve(4096);
  }

  void Reset() {
    cells_.clear();
    last_scan_t_ = -1;
  }
  // One scan, taken at pose (SLAM frame); a scan already recorded (same time) is skipped.
  void Record(const Pose2& pose, const RangeScan& scan);
  // Seen-free floor (m2) outside the room's box (map frame: the SLAM frame
  // turned by rotation) by more than margin_m, beyond no covered stretch of a
  // wall (RoomOutline).
  double OutsideArea(const RoomOutline& room, double rotation, double margin_m) const;
  // Up to n seen-free cell centres (SLAM frame) outside box by more than
  // margin_m with no hit within clear_m (room for the robot) and away_m from
  // where the robot went, the farthest from the box first. Bounded: of the
  // kMaxChecked farthest outside cells.
  std::vector<Eigen::Vector2d> OutsidePoints(const RoomOutline& room, double rotation, double margin_m,
                                             double clear_m, double away_m, size_t n) const;
  static constexpr size_t kMaxChecked = 400;
  // Whether a beam hit something within r_m of p (SLAM frame).
  bool HitNear(const Eigen::Vector2d& p, double r_m) const;
  // Whether the robot's centre was within r_m of p.
  bool VisitedNear(const Eigen::Vector2d& p, double r_m) const;
  size_t cells() const { return cells_.size(); }

 private:
  struct Cell {
    uint16_t free = 0;
    uint16_t hit = 0;
    bool visited = false;  // the robot's centre was in it
  };
  int64_t Key(double x, double y) const;
  Eigen::Vector2d Centre(int64_t key) const;
  template <typename Pred>
  bool AnyNear(const Eigen::Vector2d& p, double r_m, Pred&& pred) const;
  template <typename F>
  void ForOutside(const RoomOutline& room, double rotation, double margin_m, F&& f) const;

  PenOptions options_;
  std::array<SensorMount, kNumIrSensors> mounts_;
  std::unordered_map<int64_t, Cell> cells_;
  double last_scan_t_ = -1;
};

}  // namespace irslam::control

#endif  // IRSLAM_CONTROL_FREE_SPACE_H_
