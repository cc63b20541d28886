// Planar geometry shared by every layer: poses, angle normalisation and the one
// pose composition (a point or pose in a frame given by a pose, to its parent).
#ifndef IRSLAM_TYPES_GEOMETRY_H_
#define IRSLAM_TYPES_GEOMETRY_H_

#include <array>
#include <cmath>

namespace irslam {

// Normalises an angle to (-pi, pi].
inline double NormalizeAngle(double a) {
  a = std::remainder(a, 2.0 * M_PI);
  if (a <= -M_PI) a += 2.0 * M_PI;
  return a;
}

struct Pose2 {
  double x = 0;
  double y = 0;
  double theta = 0;
};

// A pose at robot time t (trajectories: estimated, true, dead reckoning).
struct TimedPose {
  double t = 0;
  Pose2 pose;
};

// The point (x, y) given in frame p, in p's parent frame.
inline std::array<double, 2> ToParent(const Pose2& p, double x, double y) {
  const double c = std::cos(p.theta), s = std::sin(p.theta);
  return {p.x + c * x - s * y, p.y + s * x + c * y};
}

// The point (x, y) given in p's parent frame, in frame p.
inline std::array<double, 2> ToLocal(const Pose2& p, double x, double y) {
  const double c = std::cos(p.theta), s = std::sin(p.theta);
  const double dx = x - p.x, dy = y - p.y;
  return {c * dx + s * dy, -s * dx + c * dy};
}

// Composes a with b (b expressed in a's frame).
inline Pose2 Compose(const Pose2& a, const Pose2& b) {
  const auto [x, y] = ToParent(a, b.x, b.y);
  return {x, y, NormalizeAngle(a.theta + b.theta)};
}

}  // namespace irslam

#endif  // IRSLAM_TYPES_GEOMETRY_H_
