#include "slam/line_ekf.h"

#include <Eigen/LU>
#include <algorithm>
#include <cassert>
#include <cmath>

#include "slam/line_extraction.h"

namespace irslam::slam {

LineObservation PredictObservation(const Pose2& r, double rho, double theta,
                                   Eigen::Matrix<double, 2, 5>* jacobian) {
  const double c = std::cos(theta), s = std::sin(theta);
  // Eq. (10): d = rho - rx cos(theta) - ry sin(theta); z_rho = |d|;
  // z_theta = atan2(dy, dx) - rtheta with (dx, dy) = d (cos theta, sin theta).
  const double d = rho - r.x * c - r.y * s;
  LineObservation z;
  double sign = 1;
  if (d >= 0) {
    z.rho = d;
    z.theta = NormalizeAngle(theta - r.theta);
  } else {
    sign = -1;  // the robot is on the other side of the line
    z.rho = -d;
    z.theta = NormalizeAngle(theta + M_PI - r.theta);
  }
  if (jacobian) {
    auto& j = *jacobian;
    j << sign * -c, sign * -s, 0, sign * 1, sign * (r.x * s - r.y * c),
         0, 0, -1, 0, 1;
  }
  return z;
}

void ObservationToMap(const Pose2& r, const LineObservation& z, double* rho, double* theta,
                      Eigen::Matrix<double, 2, 3>* g_pose, Eigen::Matrix2d* g_obs) {
  double th = z.theta + r.theta;
  double c = std::cos(th), s = std::sin(th);
  double rh = z.rho + r.x * c + r.y * s;
  const double lever = -r.x * s + r.y * c;  // d rho / d theta
  Eigen::Matrix<double, 2, 3> gp;
  gp << c, s, lever,
        0, 0, 1;
  Eigen::Matrix2d gz;
  gz << 1, lever,
        0, 1;
  if (rh < 0) {
    rh = -rh;
    th += M_PI;
    gp.row(0) *= -1;
    gz.row(0) *= -1;
  }
  *rho = rh;
  *theta = NormalizeAngle(th);
  if (g_pose) *g_pose = gp;
  if (g_obs) *g_obs = gz;
}

double AngleModHalfPi(double a) {
  a = std::remainder(a, M_PI / 2);  // in [-pi/4, pi/4]
  if (a <= -M_PI / 4) a += M_PI / 2;
  return a;
}

LineEkf::LineEkf() : x_(Eigen::VectorXd::Zero(kFirstLine)), P_(Eigen::MatrixXd::Zero(kFirstLine, kFirstLine)) {
  x_.segment<3>(kCalib).setOnes();
}

double LineEkf::Cov(long i, long j) const {
  if (i < j && BlockStart(i) != BlockStart(j)) std::swap(i, j);
  return P_(i, j);
}

Eigen::MatrixXd LineEkf::P() const {
  const long n = x_.size();
  Eigen::MatrixXd p = P_.topLeftCorner(n, n).selfadjointView<Eigen::Lower>();
  // The diagonal blocks as stored (their upper entries are kept, not mirrored).
  p.topLeftCorner<kFirstLine, kFirstLine>() = P_.topLeftCorner<kFirstLine, kFirstLine>();
  for (int i = 0; i < num_lines(); ++i) p(RhoIndex(i), ThetaIndex(i)) = P_(RhoIndex(i), ThetaIndex(i));
  return p;
}

void LineEkf::SetCovariance(const Eigen::MatrixXd& p) {
  const long n = x_.size();
  assert(p.rows() == n && p.cols() == n);
  Reserve(n);
  P_.topLeftCorner(n, n) = p;
}

void LineEkf::Reserve(long n) {
  if (P_.rows() >= n) return;
  const long old = std::min<long>(x_.size(), P_.rows());
  Eigen::MatrixXd grown = Eigen::MatrixXd::Zero(n + kSpareRows, n + kSpareRows);
  grown.topLeftCorner(old, old) = P_.topLeftCorner(old, old);
  P_.swap(grown);
}

void LineEkf::SetCalibration(const OdometryCalibration& c, const Eigen::Vector3d& sigma) {
  x_.segment<3>(kCalib) << c.left, c.right, c.base;
  const long n = x_.size();
  // Rows and columns 3..5 of the stored part: within the robot block, and below it.
  P_.block<3, kFirstLine>(kCalib, 0).setZero();
  P_.block<kFirstLine, 3>(0, kCalib).setZero();
  P_.block(kFirstLine, kCalib, n - kFirstLine, 3).setZero();
  P_.block<3, 3>(kCalib, kCalib) = sigma.cwiseAbs2().asDiagonal();
}

void LineEkf::Predict(const WheelMotion& w, double wheel_base_m, const MotionNoise& noise,
                      double calib_var_per_m, double min_sigma) {
  const Pose2 p = pose();
  const OdometryCalibration c = calibration();
  const Motion m = Odometry::Calibrated(w, wheel_base_m, c);
  // F = d(pose', calib') / d(pose, calib) = [F_pose, G_motion J_calib; 0, I].
  Eigen::Matrix<double, 6, 6> f = Eigen::Matrix<double, 6, 6>::Identity();
  f.topLeftCorner<3, 3>() = Odometry::JacobianPose(p, m);
  f.topRightCorner<3, 3>() =
      Odometry::JacobianMotion(p, m) * Odometry::JacobianCalibration(w, wheel_base_m, c);
  const Pose2 n = Odometry::Apply(p, m);
  x_(0) = n.x;
  x_(1) = n.y;
  x_(2) = n.theta;
  const long rest = x_.size() - kFirstLine;
  Eigen::Matrix<double, 6, 6> top = f * P_.topLeftCorner<6, 6>() * f.transpose();
  top.topLeftCorner<3, 3>() += Odometry::ProcessNoise(p, m, noise);
  // The parameters' random walk (only those being estimated: a zero variance
  // means fixed), with their sigma kept at least min_sigma.
  const double walk = calib_var_per_m * std::abs(m.ds);
  for (int k = kCalib; k < kCalib + 3; ++k) {
    if (top(k, k) <= 0) continue;
    top(k, k) = std::max(top(k, k) + walk, min_sigma * min_sigma);
  }
  P_.topLeftCorner<6, 6>() = top;
  if (rest > 0) {
    // The pose's cross-covariances with the lines, F P(0:6, lines), from the
    // stored columns 0..5 below the robot block (contiguous).
    rows_ = P_.block(kFirstLine, 0, rest, 6).transpose();
    // (Operand and result types as in the former f * P.topRightCorner(6, rest):
    // the same Eigen kernel, the same rounding.)
    pose_cross_.noalias() = f.topRows<3>() * rows_.topLeftCorner(6, rest);
    P_.block(kFirstLine, 0, rest, 3) = pose_cross_.transpose();
  }
}

void LineEkf::Predict(const Motion& m, const MotionNoise& noise) {
  const Pose2 p = pose();
  const Eigen::Matrix3d f = Odometry::JacobianPose(p, m);
  const Eigen::Matrix3d q = Odometry::ProcessNoise(p, m, noise);
  const Pose2 n = Odometry::Apply(p, m);
  x_(0) = n.x;
  x_(1) = n.y;
  x_(2) = n.theta;
  const long dim = x_.size(), rest = dim - 3;
  P_.topLeftCorner<3, 3>() = f * P_.topLeftCorner<3, 3>() * f.transpose() + q;
  // P(0:3, 3:dim): the calibration's columns within the robot block, the lines'
  // from the stored columns 0..2 below it.
  rows_.resize(3, rest);
  rows_.leftCols<3>() = P_.block<3, 3>(0, kCalib);
  rows_.rightCols(dim - kFirstLine) = P_.block(kFirstLine, 0, dim - kFirstLine, 3).transpose();
  pose_cross_.noalias() = f * rows_.topLeftCorner(3, rest);
  P_.block<3, 3>(0, kCalib) = pose_cross_.leftCols<3>();
  P_.block(3, 0, rest, 3) = pose_cross_.transpose();
}

int LineEkf::AddLine(const LineObservation& z, const Eigen::Matrix2d& r) {
  double rho, theta;
  Eigen::Matrix<double, 2, 3> gp;
  Eigen::Matrix2d gz;
  ObservationToMap(pose(), z, &rho, &theta, &gp, &gz);
  const long n = x_.size();
  Reserve(n + 2);
  x_.conservativeResize(n + 2);
  x_(n) = rho;
  x_(n + 1) = theta;
  // Cross-covariance with everything: G_pose * P(pose, :), P(pose, :) from the
  // robot block and the stored columns 0..2 below it.
  rows_.resize(3, n);
  rows_.leftCols<kFirstLine>() = P_.topLeftCorner<3, kFirstLine>();
  rows_.rightCols(n - kFirstLine) = P_.block(kFirstLine, 0, n - kFirstLine, 3).transpose();
  line_cross_.noalias() = gp * rows_.topLeftCorner(3, n);
  P_.block(n, 0, 2, n) = line_cross_;
  P_.block<2, 2>(n, n) = gp * P_.topLeftCorner<3, 3>() * gp.transpose() + gz * r * gz.transpose();
  return static_cast<int>((n - kFirstLine) / 2);
}

void LineEkf::Restart(const Pose2& pose, const Eigen::Matrix3d& pose_cov,
                      const std::vector<SavedLine>& lines) {
  const Eigen::Vector3d calib = x_.segment<3>(kCalib);
  const Eigen::Matrix3d calib_cov = P_.block<3, 3>(kCalib, kCalib);
  const long n = kFirstLine + 2 * static_cast<long>(lines.size());
  x_ = Eigen::VectorXd::Zero(n);
  P_ = Eigen::MatrixXd::Zero(n + kSpareRows, n + kSpareRows);
  x_.head<3>() << pose.x, pose.y, NormalizeAngle(pose.theta);
  P_.topLeftCorner<3, 3>() = 0.5 * (pose_cov + pose_cov.transpose());
  x_.segment<3>(kCalib) = calib;
  P_.block<3, 3>(kCalib, kCalib) = calib_cov;
  for (size_t i = 0; i < lines.size(); ++i) {
    const int k = RhoIndex(static_cast<int>(i));
    x_(k) = lines[i].rho;
    x_(k + 1) = lines[i].theta;
    P_.block<2, 2>(k, k) = 0.5 * (lines[i].cov + lines[i].cov.transpose());
    NormalizeLineState(static_cast<int>(i));
  }
}

void LineEkf::RemoveLine(int i) {
  const long at = RhoIndex(i), n = x_.size(), tail = n - at - 2;
  x_.segment(at, tail) = x_.tail(tail).eval();
  x_.conservativeResize(n - 2);
  // In place, the stored part only: the columns before line i lose rows at and
  // at+1; each column after it moves two columns left and two rows up (column j
  // holds rows BlockStart(j)..n-1). Destinations precede their sources.
  double* const d = P_.data();
  const long ld = P_.outerStride();
  for (long j = 0; j < at; ++j) std::copy(d + j * ld + at + 2, d + j * ld + n, d + j * ld + at);
  for (long j = at + 2; j < n; ++j) {
    const long top = BlockStart(j);
    std::copy(d + j * ld + top, d + j * ld + n, d + (j - 2) * ld + top - 2);
  }
}

void LineEkf::FindColumns(const Eigen::MatrixXd& h) {
  cols_.clear();
  for (long j = 0; j < h.cols(); ++j) {
    if ((h.col(j).array() != 0).any()) cols_.push_back(static_cast<int>(j));
  }
  hc_.resize(h.rows(), static_cast<long>(cols_.size()));
  for (size_t j = 0; j < cols_.size(); ++j) hc_.col(static_cast<long>(j)) = h.col(cols_[j]);
}

void LineEkf::Update(const Eigen::VectorXd& y, const Eigen::MatrixXd& h, const Eigen::MatrixXd& r) {
  FindColumns(h);
  UpdateColumns(y, cols_, hc_, r);
}

Eigen::MatrixXd LineEkf::ProjectedCov(const Eigen::MatrixXd& h) const {
  std::vector<long> cols;
  for (long j = 0; j < h.cols(); ++j) {
    if ((h.col(j).array() != 0).any()) cols.push_back(j);
  }
  const long c = static_cast<long>(cols.size());
  Eigen::MatrixXd hc(h.rows(), c), pc(c, c);
  for (long a = 0; a < c; ++a) {
    hc.col(a) = h.col(cols[static_cast<size_t>(a)]);
    for (long b = 0; b < c; ++b) pc(a, b) = Cov(cols[static_cast<size_t>(a)], cols[static_cast<size_t>(b)]);
  }
  return hc * pc * hc.transpose();
}

void LineEkf::UpdateColumns(const Eigen::VectorXd& y, const std::vector<int>& cols, const Eigen::MatrixXd& hc,
                            const Eigen::MatrixXd& r) {
  const long n = x_.size(), m = y.size();
  // P H' (n x m) from H's non-zero columns only: sum over them of P(:, c) H(:, c)'.
  // P(:, c) is gathered from the stored part: the rows above c's block from row c,
  // the rest from column c.
  pht_.setZero(n, m);
  column_.resize(n);
  for (size_t j = 0; j < cols.size(); ++j) {
    const long c = cols[j], top = BlockStart(c);
    column_.head(top) = P_.row(c).head(top).transpose();
    column_.tail(n - top) = P_.col(c).segment(top, n - top);
    pht_.noalias() += column_ * hc.col(static_cast<long>(j)).transpose();
  }
  // S = H P H' + R (m x m): H times the rows of P H' at H's columns.
  Eigen::MatrixXd s = r;
  for (size_t j = 0; j < cols.size(); ++j) s.noalias() += hc.col(static_cast<long>(j)) * pht_.row(cols[j]);
  // ku_ = [K U], uk_ = [U K] with the gain K = P H' S^-1 and U = P H' - K S / 2.
  ku_.resize(n, 2 * m);
  uk_.resize(n, 2 * m);
  auto k = ku_.leftCols(m);
  auto u = ku_.rightCols(m);
  k.noalias() = pht_ * s.inverse();
  x_.noalias() += k * y;
  x_(2) = NormalizeAngle(x_(2));
  u = pht_;
  u.noalias() -= 0.5 * k * s;
  uk_.leftCols(m) = u;
  uk_.rightCols(m) = k;
  // Joseph form, exactly: (I-KH) P (I-KH)' + K R K' = P - K H P - P H' K' + K S K'
  //                                                 = P - (K U' + U K').
  // A symmetric rank-2m update of P's lower triangle in place, one panel of kPanel
  // columns at a time (a GEMM of depth 2m each); each panel's diagonal square is
  // made exactly symmetric (the diagonal blocks are stored whole). Nothing above
  // the panels' diagonal squares is written: half the memory traffic of a full
  // update. No n x n temporary.
  constexpr long kPanel = 64;  // even: a line's block never straddles two panels
  for (long jb = 0; jb < n; jb += kPanel) {
    const long b = std::min(kPanel, n - jb);
    P_.block(jb, jb, n - jb, b).noalias() -= ku_.bottomRows(n - jb) * uk_.middleRows(jb, b).transpose();
    auto diagonal = P_.block(jb, jb, b, b);
    diagonal.triangularView<Eigen::StrictlyUpper>() = diagonal.transpose();
  }
  NormalizeAllLines();
}

void LineEkf::UpdateReference(const Eigen::VectorXd& y, const Eigen::MatrixXd& h, const Eigen::MatrixXd& r) {
  const long n = x_.size();
  Eigen::MatrixXd p = P();
  const Eigen::MatrixXd pht = p * h.transpose();             // n x m
  const Eigen::MatrixXd s = h * pht + r;                     // m x m
  const Eigen::MatrixXd k = pht * s.inverse();               // n x m
  x_ += k * y;
  x_(2) = NormalizeAngle(x_(2));
  // Joseph form, in O(n^2 m): A = (I - K H) P; P = A (I - K H)' + K R K'.
  const Eigen::MatrixXd a = p - k * pht.transpose();
  p = a - (a * h.transpose()) * k.transpose() + k * r * k.transpose();
  P_.topLeftCorner(n, n) = 0.5 * (p + p.transpose());
  NormalizeAllLines();
}

void LineEkf::NormalizeAllLines() {
  for (int i = 0; i < num_lines(); ++i) NormalizeLineState(i);
}

void LineEkf::NormalizeLineState(int i) {
  const long at = RhoIndex(i);
  if (x_(at) < 0) {
    x_(at) = -x_(at);
    x_(at + 1) += M_PI;
    // Row and column at of P, in the stored part: left of the line's block, within
    // it (the diagonal entry flips twice), below it.
    const long n = x_.size();
    P_.row(at).head(at) *= -1;
    P_(at + 1, at) *= -1;
    P_(at, at + 1) *= -1;
    P_.col(at).segment(at + 2, n - at - 2) *= -1;
  }
  x_(at + 1) = NormalizeAngle(x_(at + 1));
}

}  // namespace irslam::slam
