// The geometrically constrained EKF (paper §4): state x = [rx, ry, rtheta,
// kl, kr, kb, rho_1, theta_1, ..., rho_N, theta_N] with full covariance P: the
// paper's eq. (9) augmented with the odometry's systematic parameters (wheel
// radius and track width scale factors, slam/odometry.h OdometryCalibration),
// estimated from the line observations as the robot drives: simultaneous
// localisation and odometry self-calibration (Martinelli, Tomatis & Siegwart,
// IEEE T-RO 2007; Kuemmerle, Grisetti & Burgard, IROS 2011). They sit between the
// pose and the lines (indices 3..5); with zero covariance they stay fixed.
// Models are free functions (tested against finite differences); LineEkf holds
// the state and applies prediction, measurement and pseudo-measurement updates
// (Joseph form), landmark insertion (inverse model) and deletion.
//
// Update cost: a measurement touches only the robot pose, the observed line and the
// lines of its pseudo-measurements (eqs. 11-12): H has at most ~9 non-zero columns.
// Update works from those columns and writes P in place (no n x n temporaries):
// O(n m) for P H', then one symmetric rank-2m update of P's lower part (the
// Joseph form regrouped).
//
// Storage of P: only its block-lower part is kept. P is partitioned into the
// state's blocks (robot and calibration 6, then 2 per line); every block on or
// below the block diagonal is valid, the diagonal blocks whole (Predict and AddLine
// can leave them asymmetric in the last bit, as the full matrix was before); the
// blocks above the diagonal are not maintained. Readers take P(i, j) with i < j in
// different blocks from P(j, i) (Cov, PoseCov, LineCov; P() assembles the whole
// matrix). P lives in the top-left corner of a larger buffer, so that AddLine and
// RemoveLine work in place (no reallocation until the spare rows run out).
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

  // State layout: pose, calibration, lines.
  static constexpr int kCalib = 3;     // kl, kr, kb at 3, 4, 5
  static constexpr int kFirstLine = 6;
  static constexpr int RhoIndex(int i) { return kFirstLine + 2 * i; }
  static constexpr int ThetaIndex(int i) { return kFirstLine + 1 + 2 * i; }

  int num_lines() const { return static_cast<int>((x_.size() - kFirstLine) / 2); }
  Pose2 pose() const { return {x_(0), x_(1), x_(2)}; }
  OdometryCalibration calibration() const { return {x_(kCalib), x_(kCalib + 1), x_(kCalib + 2)}; }
  double rho(int i) const { return x_(RhoIndex(i)); }
  double theta(int i) const { return x_(ThetaIndex(i)); }
  const Eigen::VectorXd& x() const { return x_; }
  // Covariance blocks, O(1) (diagonal blocks: stored whole).
  Eigen::Matrix3d PoseCov() const { return P_.topLeftCorner<3, 3>(); }
  Eigen::Matrix3d CalibrationCov() const { return P_.block<3, 3>(kCalib, kCalib); }
  Eigen::Matrix2d LineCov(int i) const { return P_.block<2, 2>(RhoIndex(i), RhoIndex(i)); }
  // One entry of P, from the stored block-lower part.
  double Cov(long i, long j) const;
  // The whole covariance (n x n), assembled from the stored part: an O(n^2) copy,
  // for tests and diagnostics, not for the control loop.
  Eigen::MatrixXd P() const;

  // Sets the calibration parameters and their (diagonal) sigmas; only before the
  // first line (their cross-covariances are zeroed).
  void SetCalibration(const OdometryCalibration& c, const Eigen::Vector3d& sigma);
  // Prediction with an odometry motion (robot block and its cross-covariances);
  // the calibration is not used.
  void Predict(const Motion& m, const MotionNoise& noise);
  // Prediction with the wheels' nominal travel: the motion is calibrated with the
  // state's parameters (slam/odometry.h Calibrated) and the pose's Jacobian
  // includes them; the parameters get a random walk of calib_var_per_m per metre
  // travelled, and their sigma is kept at least min_sigma (only where they have
  // one: fixed parameters stay fixed).
  void Predict(const WheelMotion& w, double wheel_base_m, const MotionNoise& noise, double calib_var_per_m,
               double min_sigma);
  // Appends a line from an observation (inverse model); returns its index.
  int AddLine(const LineObservation& z, const Eigen::Matrix2d& r);
  // A saved map's line, for Restart.
  struct SavedLine {
    double rho = 0, theta = 0;
    Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  };
  // Starts over in a saved map (issue 14): pose and its covariance, the saved
  // lines with their own covariances and no cross-covariances (the saved file
  // keeps only the 2x2 blocks; the pose-line correlations are rebuilt by the
  // next updates); the calibration parameters and their covariance are kept.
  void Restart(const Pose2& pose, const Eigen::Matrix3d& pose_cov, const std::vector<SavedLine>& lines);
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
  // For tests: direct access to x; P set whole (x's size; only its block-lower
  // part is kept).
  Eigen::VectorXd& mutable_x() { return x_; }
  void SetCovariance(const Eigen::MatrixXd& p);

 private:
  // Spare rows and columns kept behind P when it grows (32 lines).
  static constexpr long kSpareRows = 64;
  // The first index of the block holding state index i (robot and calibration,
  // or a line).
  static constexpr long BlockStart(long i) { return i < kFirstLine ? 0 : i - ((i - kFirstLine) & 1); }
  // Makes room for an n x n P (keeps the current one).
  void Reserve(long n);
  // H's non-zero columns and their values, found by a scan of dense H.
  void FindColumns(const Eigen::MatrixXd& h);
  void NormalizeAllLines();

  Eigen::VectorXd x_;
  // P is P_'s top-left n x n corner (n = x_.size()), block-lower part only.
  Eigen::MatrixXd P_;
  // Workspace (kept to avoid allocating while the state size is unchanged).
  std::vector<int> cols_;
  Eigen::VectorXd column_;
  Eigen::MatrixXd hc_, pht_, ku_, uk_, rows_, line_cross_;
  Eigen::Matrix<double, 3, Eigen::Dynamic> pose_cross_;
};

}  // namespace irslam::slam

#endif  // IRSLAM_SLAM_LINE_EKF_H_
