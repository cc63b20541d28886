// A mapped line from its end points, for tests that build line maps by hand:
// (rho, theta) in the SLAM's convention (rho >= 0, the normal pointing from
// the origin to the line).
#ifndef IRSLAM_TESTS_TESTING_LINES_H_
#define IRSLAM_TESTS_TESTING_LINES_H_

#include <cmath>

#include "slam/slam.h"
#include "types/geometry.h"

namespace irslam::testing {

inline slam::LineFeature Line(int id, double x0, double y0, double x1, double y1) {
  slam::LineFeature l;
  l.id = id;
  l.p0 = {x0, y0};
  l.p1 = {x1, y1};
  const Eigen::Vector2d d = (l.p1 - l.p0).normalized();
  l.theta = std::atan2(d.x(), -d.y());  // normal = d rotated by -90 deg
  l.rho = l.p0.dot(Eigen::Vector2d(std::cos(l.theta), std::sin(l.theta)));
  if (l.rho < 0) {
    l.rho = -l.rho;
    l.theta = NormalizeAngle(l.theta + M_PI);
  }
  return l;
}

inline slam::LineFeature Line(int id, const Eigen::Vector2d& p0, const Eigen::Vector2d& p1) {
  return Line(id, p0.x(), p0.y(), p1.x(), p1.y());
}

}  // namespace irslam::testing

#endif  // IRSLAM_TESTS_TESTING_LINES_H_
