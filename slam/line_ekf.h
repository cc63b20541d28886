// The geometrically constrained EKF (paper §4): state x = [rx, ry, rtheta,
// rho_1, theta_1, ..., rho_N, theta_N] with full covariance P, eq. (9).
// Models are free functions (tested against finite differences); LineEkf holds
// the state and applies prediction, measurement and pseudo-measurement updates
// (Joseph form), landmark insertion (inverse model) and deletion.
//
// Update cost: a measurement touches only the robot pose, the observed line and the
// lines of its pseudo-measurements (eqs. 11-12): H has at most ~9 non-zero columns.
// Update works from those columns and writes P in place (no n x n temporaries):
// O(n m) for P H', then one symmetric rank-2m update of P (the Joseph form
// regrouped; lower triangle computed, mirrored panel by panel).
#ifndef IRSLAM_SLAM_LINE_EKF_H_
#define IRSLAM_SLAM_LINE_EKF_H_

#include <Eigen/Core>
#include <vector>

#include "slam/odometry.h"
#include "types/geometry.h"
#include "types/signals.h"

namespace irslam::slam {

// A line seen from the robot: x cos(theta) + y sin(theta) = rho in the robot frame.
struct LineObservation {
  double rho = 0, theta = 0;
};

// Eq. (10): the observation of map line (rho, theta) from pose r, and its Jacobian
// with respect to [rx, ry, rtheta, rho, theta]. When d < 0 the robot is on the
// other side of the line: rho flips sign and theta turns by pi.
LineObservation PredictObservation(const Pose2& r, double rho, double theta,
                                   Eigen::Matrix<double, 2, 5>* jacobian);

// Inverse model (landmark initialisation): the map line for observation z from
// pose r, with Jacobians with respect to the pose (2x3) and to z (2x2).
void ObservationToMap(const Pose2& r, const LineObservation& z, double* rho, double* theta,
                      Eigen::Matrix<double, 2, 3>* g_pose, Eigen::Matrix2d* g_obs);

// Reduces an angle difference modulo pi/2 to (-pi/4, pi/4]: 0 for parallel and
// for orthogonal lines (eq. 11 for both cases at once).
double AngleModHalfPi(double a);

class LineEkf {
 public:
  LineEkf();

  int num_lines() const { return static_cast<int>((x_.size() - 3) / 2); }
  Pose2 pose() const { return {x_(0), x_(1), x_(2)}; }
  double rho(int i) const { return x_(3 + 2 * i); }
  double theta(int i) const { return x_(4 + 2 * i); }
  const Eigen::VectorXd& x() const { return x_; }
  const Eigen::MatrixXd& P() const { return P_; }
  Eigen::Matrix2d LineCov(int i) const { return P_.block<2, 2>(3 + 2 * i, 3 + 2 * i); }

  // Prediction with an odometry motion (robot block and its cross-covariances).
  void Predict(const Motion& m, const MotionNoise& noise);
  // Appends a line from an observation (inverse model); returns its index.
  int AddLine(const LineObservation& z, const Eigen::Matrix2d& r);
  // Removes line i's rows and columns.
  void RemoveLine(int i);

  // One stacked update: innovation y (already angle-wrapped), Jacobian H (m x n)
  // and noise R. Joseph form: P = (I-KH) P (I-KH)' + K R K', computed in place from
  // H's non-zero columns (found by a scan of H).
  void Update(const Eigen::VectorXd& y, const Eigen::MatrixXd& h, const Eigen::MatrixXd& r);
  // The same with H given by its non-zero columns: H(:, cols[j]) = hc.col(j), all
  // other columns zero (cols distinct, each in [0, n)).
  void UpdateColumns(const Eigen::VectorXd& y, const std::vector<int>& cols, const Eigen::MatrixXd& hc,
                     const Eigen::MatrixXd& r);
  // H P H' (m x m) from H's non-zero columns only, e.g. for an innovation gate.
  Eigen::MatrixXd ProjectedCov(const Eigen::MatrixXd& h) const;

  // The former dense update (same Joseph form, O(n^2 m) with several n x n
  // temporaries). Not used by Slam: kept to check Update against it (the test
  // InPlaceUpdateMatchesTheReference) and to benchmark both (tests/bench/ekf_bench.cc).
  void UpdateReference(const Eigen::VectorXd& y, const Eigen::MatrixXd& h, const Eigen::MatrixXd& r);

  // Puts line i back to rho >= 0, theta in (-pi, pi] (flipping its covariance rows).
  void NormalizeLineState(int i);
  // For tests: direct access.
  Eigen::VectorXd& mutable_x() { return x_; }
  Eigen::MatrixXd& mutable_P() { return P_; }

 private:
  // H's non-zero columns and their values, found by a scan of dense H.
  void FindColumns(const Eigen::MatrixXd& h);
  void NormalizeAllLines();

  Eigen::VectorXd x_;
  Eigen::MatrixXd P_;
  // Update's workspace (kept to avoid allocating while the state size is unchanged).
  std::vector<int> cols_;
  Eigen::MatrixXd hc_, pht_, ku_, uk_;
};

}  // namespace irslam::slam

#endif  // IRSLAM_SLAM_LINE_EKF_H_
