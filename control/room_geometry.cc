#include "control/room_geometry.h"

#include <algorithm>
#include <cmath>
#include <optional>

namespace irslam::control::room_geometry {

std::vector<Side> ToSides(const std::vector<slam::LineFeature>& lines,
                          const std::vector<TimedPose>& trajectory, double axis_tolerance_rad) {
  std::vector<Side> sides;
  for (const auto& l : lines) {
    const double t = l.theta;
    Side s;
    s.id = l.id;
    if (std::abs(std::remainder(t - M_PI / 2, M_PI)) < axis_tolerance_rad) {
      s.horizontal = true;
      s.c = 0.5 * (l.p0.y() + l.p1.y());
      s.a0 = std::min(l.p0.x(), l.p1.x());
      s.a1 = std::max(l.p0.x(), l.p1.x());
    } else if (std::abs(std::remainder(t, M_PI)) < axis_tolerance_rad) {
      s.c = 0.5 * (l.p0.x() + l.p1.x());
      s.a0 = std::min(l.p0.y(), l.p1.y());
      s.a1 = std::max(l.p0.y(), l.p1.y());
    } else {
      continue;
    }
    const Eigen::Vector2d mid = 0.5 * (l.p0 + l.p1);
    double best = 1e18;
    for (const auto& p : trajectory) {
      const double d = std::hypot(p.pose.x - mid.x(), p.pose.y - mid.y());
      if (d < best) {
        best = d;
        const double coord = s.horizontal ? p.pose.y : p.pose.x;
        s.seen_from = coord >= s.c ? +1 : -1;
      }
    }
    sides.push_back(s);
  }
  return sides;
}

double Overlap1d(double a0, double a1, double b0, double b1) {
  return std::min(a1, b1) - std::max(a0, b0);
}

// The object's box from its faces. A side's offset is its best-known coordinate
// (the EKF estimates it from every point along the side), while its end points
// are where the beams stopped hitting it (short of the corner, or past it by the
// noise): so each edge of the box is the outermost side facing that way - a
// vertical side seen from the left for xmin, and so on - and the extreme end
// point only where no side faces that way (an open, unseen face), or where the
// ends reach well beyond every face (compound furniture, seen in part).
Box FaceBox(const std::vector<Side>& sides, const std::vector<size_t>& group, const Box& ends) {
  constexpr double kBeyond = 0.10;  // ends this far past a face: that face is not the edge
  Box b = ends;
  std::optional<double> xmin, xmax, ymin, ymax;
  for (size_t i : group) {
    const Side& s = sides[i];
    auto& lo = s.horizontal ? ymin : xmin;
    auto& hi = s.horizontal ? ymax : xmax;
    if (s.seen_from < 0) lo = lo ? std::min(*lo, s.c) : s.c;
    if (s.seen_from > 0) hi = hi ? std::max(*hi, s.c) : s.c;
  }
  // Without a face that way: the mean of the ends that reach the extreme (one
  // end alone may be past the corner by the noise, another short of it).
  const auto mean_end = [&](bool horizontal_sides, bool high, double extreme) {
    double sum = 0;
    int n = 0;
    for (size_t i : group) {
      const Side& s = sides[i];
      // The extreme is a side's own offset (a face, seen from wherever): keep it.
      if (s.horizontal != horizontal_sides && std::abs(s.c - extreme) < 1e-9) return extreme;
    }
    for (size_t i : group) {
      const Side& s = sides[i];
      if (s.horizontal != horizontal_sides) continue;
      const double e = high ? s.a1 : s.a0;
      if (std::abs(e - extreme) < kBeyond) {
        sum += e;
        ++n;
      }
    }
    return n > 0 ? sum / n : extreme;
  };
  b.xmin = xmin && *xmin < ends.xmin + kBeyond ? *xmin : mean_end(true, false, ends.xmin);
  b.ymin = ymin && *ymin < ends.ymin + kBeyond ? *ymin : mean_end(false, false, ends.ymin);
  b.xmax = xmax && *xmax > ends.xmax - kBeyond ? *xmax : mean_end(true, true, ends.xmax);
  b.ymax = ymax && *ymax > ends.ymax - kBeyond ? *ymax : mean_end(false, true, ends.ymax);
  return b;
}

bool MakeCorner(const CornerEnd& a, const CornerEnd& b, double corner_m) {
  constexpr double kTight = 0.1;
  const double loose = 1.5 * corner_m;
  const bool near_a = a.end < corner_m || a.inside;
  const bool near_b = b.end < corner_m || b.inside;
  if (near_a && near_b && (a.end < corner_m || b.end < corner_m)) return true;
  return (a.end < kTight && (b.end < loose || b.inside)) ||
         (b.end < kTight && (a.end < loose || a.inside));
}

bool Meets(const Side& a, const Side& b, const ModelOptions& o) {
  if (a.horizontal == b.horizontal) {
    return std::abs(a.c - b.c) < o.collinear_m && Overlap1d(a.a0, a.a1, b.a0, b.a1) > -o.corner_m;
  }
  const Side& h = a.horizontal ? a : b;
  const Side& v = a.horizontal ? b : a;
  // The corner is (v.c, h.c).
  const CornerEnd along_h{std::min(std::abs(v.c - h.a0), std::abs(v.c - h.a1)),
                          v.c > h.a0 && v.c < h.a1};
  const CornerEnd along_v{std::min(std::abs(h.c - v.a0), std::abs(h.c - v.a1)),
                          h.c > v.a0 && h.c < v.a1};
  return MakeCorner(along_h, along_v, o.corner_m);
}

bool InsidePolygon(const std::vector<Eigen::Vector2d>& poly, const Eigen::Vector2d& p) {
  bool in = false;
  for (size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const Eigen::Vector2d& a = poly[i];
    const Eigen::Vector2d& b = poly[j];
    if ((a.y() > p.y()) != (b.y() > p.y()) &&
        p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x()) {
      in = !in;
    }
  }
  return in;
}

Box PolygonBounds(const std::vector<Eigen::Vector2d>& poly) {
  Box b{poly[0].x(), poly[0].y(), poly[0].x(), poly[0].y()};
  for (const auto& q : poly) {
    b.xmin = std::min(b.xmin, q.x());
    b.ymin = std::min(b.ymin, q.y());
    b.xmax = std::max(b.xmax, q.x());
    b.ymax = std::max(b.ymax, q.y());
  }
  return b;
}

}  // namespace irslam::control::room_geometry
