// The geometry the room modeller works on (internal to control/room_model.cc):
// the axis-aligned view of mapped lines (Side), the one corner rule, whether two
// sides belong to one object, an object's box from its faces, and the
// point-in-polygon test for followed contours. Pure.
#ifndef IRSLAM_CONTROL_ROOM_GEOMETRY_H_
#define IRSLAM_CONTROL_ROOM_GEOMETRY_H_

#include <Eigen/Core>
#include <vector>

#include "control/room_model.h"
#include "slam/slam.h"

namespace irslam::control::room_geometry {

// An axis-aligned view of a mapped line.
struct Side {
  int id = 0;
  bool horizontal = false;  // y = c, extent in x; else x = c, extent in y
  double c = 0, a0 = 0, a1 = 0;
  int seen_from = 0;  // +1: seen from the greater-coordinate side, -1: from the lesser
  Eigen::Vector2d End(int k) const {
    const double a = k == 0 ? a0 : a1;
    return horizontal ? Eigen::Vector2d(a, c) : Eigen::Vector2d(c, a);
  }
};

// The axis-aligned view of the mapped lines (others are skipped), each with the
// side it was seen from: the trajectory point nearest its middle.
std::vector<Side> ToSides(const std::vector<slam::LineFeature>& lines,
                          const std::vector<TimedPose>& trajectory, double axis_tolerance_rad);

// Overlap of two intervals (negative: the gap between them).
double Overlap1d(double a0, double a1, double b0, double b1);

// The corner rule. For each of two orthogonal sides: the distance from their
// corner (where their lines cross) to the side's nearest end, and whether the
// corner lies within the side's extent.
struct CornerEnd {
  double end = 0;
  bool inside = false;
};
// The two sides make a corner if it lies within corner_m of an end of one and
// near the other (within corner_m of its end, or inside it); or if one side
// ends right at it and the other was seen short of it (its end passed on a
// corner arc), by up to 1.5 corner_m, or runs past it.
bool MakeCorner(const CornerEnd& a, const CornerEnd& b, double corner_m);

// Whether two sides belong to one object: collinear pieces that overlap or
// nearly do, or orthogonal sides that make a corner (the corner rule).
bool Meets(const Side& a, const Side& b, const ModelOptions& o);

// The object's box from its faces (see the .cc); ends: the box of its end points.
Box FaceBox(const std::vector<Side>& sides, const std::vector<size_t>& group, const Box& ends);

// Even-odd rule.
bool InsidePolygon(const std::vector<Eigen::Vector2d>& poly, const Eigen::Vector2d& p);

// The axis-aligned bounds of a polygon (at least one point).
Box PolygonBounds(const std::vector<Eigen::Vector2d>& poly);

}  // namespace irslam::control::room_geometry

#endif  // IRSLAM_CONTROL_ROOM_GEOMETRY_H_
