// Slam's methods (the class and its algorithm: slam/slam.h) and its option tables.
// Longer than the ~400-line bar (issue 10) on purpose: after the short map-frame
// views at the top (map_lines, map_trajectory, ToMap: ~50 lines) and the key tables
// at the bottom (~45 lines), the rest is one algorithm over one private state —
// the window of scans, the EKF's pose and line rows, the end points — as
// Associate (paper section 4: NearestLine, eq. (13); InsertCollinearPiece,
// eqs. (14)-(15); UpdateMatched with MatchRows and PassesGate, eq. (10) and the
// innovation gate) calling InsertLine, ExtendEndpoints, ReprojectEndpoints and
// MergeOverlapping (section 4.5). Those are private members that read and
// rewrite the same rows and index map; split across files they would be one
// class's internals in two places with no interface between them, which reads
// worse than one file in the paper's order.
#include "slam/slam.h"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>

namespace irslam::slam {
namespace {

Eigen::Vector2d Transform(const Pose2& p, const Eigen::Vector2d& v) {
  const auto [x, y] = ToParent(p, v.x(), v.y());
  return {x, y};
}

Eigen::Vector2d InverseTransform(const Pose2& p, const Eigen::Vector2d& v) {
  const auto [x, y] = ToLocal(p, v.x(), v.y());
  return {x, y};
}

Eigen::Vector2d Direction(double theta) { return {-std::sin(theta), std::cos(theta)}; }
Eigen::Vector2d Normal(double theta) { return {std::cos(theta), std::sin(theta)}; }

// The pose uncertainty of a mission continuing in a saved map ([slam.resume]).
Eigen::Matrix3d ResumedPoseCov(const ResumeOptions& ro) {
  return Eigen::Vector3d(ro.pose_sigma_m * ro.pose_sigma_m, ro.pose_sigma_m * ro.pose_sigma_m,
                         ro.pose_sigma_rad * ro.pose_sigma_rad)
      .asDiagonal();
}

}  // namespace

Slam::Slam(SlamOptions options) : options_(options), odometry_(options.geometry) {
  // The odometry's parameters start from a saved calibration if there is one
  // (its sigma widened by resume_sigma), else nominal with the prior sigmas;
  // disabled: the saved values (or nominal) with zero variance, i.e. fixed.
  const CalibrationOptions& co = options_.calibration;
  OdometryCalibration start;
  Eigen::Vector3d sigma(co.prior_sigma_wheel, co.prior_sigma_wheel, co.prior_sigma_base);
  if (options_.initial_calibration) {
    start = options_.initial_calibration->value;
    const Eigen::Vector3d& s = options_.initial_calibration->sigma;
    sigma = (s.cwiseAbs2().array() + co.resume_sigma * co.resume_sigma).sqrt();
  }
  if (!co.enabled) sigma.setZero();
  ekf_.SetCalibration(start, sigma);
}

CalibrationEstimate Slam::calibration() const {
  const Eigen::Matrix3d c = ekf_.CalibrationCov();
  const OdometryCalibration v = ekf_.calibration();
  // ratio = right / left: d ratio = (-right / left^2, 1 / left, 0) d(kl, kr, kb).
  const Eigen::Vector3d j(-v.right / (v.left * v.left), 1 / v.left, 0);
  return {v, c.diagonal().cwiseMax(0).cwiseSqrt(), std::sqrt(std::max(0.0, j.dot(c * j)))};
}

double Slam::map_rotation() const {
  if (saved_frame_) return 0;
  return ekf_.num_lines() > 0 ? NormalizeAngle(M_PI / 2 - ekf_.theta(0)) : 0.0;
}

Pose2 Slam::ToMap(const Pose2& p) const {
  const double rot = map_rotation();
  const double c = std::cos(rot), s = std::sin(rot);
  return {c * p.x - s * p.y, s * p.x + c * p.y, NormalizeAngle(p.theta + rot)};
}

Eigen::Matrix3d Slam::map_pose_cov() const {
  const double rot = map_rotation();
  Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
  r.topLeftCorner<2, 2>() << std::cos(rot), -std::sin(rot), std::sin(rot), std::cos(rot);
  return r * ekf_.PoseCov() * r.transpose();
}

std::vector<LineFeature> Slam::map_lines() const {
  std::vector<LineFeature> out = lines_;
  const Pose2 rot{0, 0, map_rotation()};
  for (auto& l : out) {
    l.theta = NormalizeAngle(l.theta + rot.theta);  // rho is invariant under rotation
    l.p0 = Transform(rot, l.p0);
    l.p1 = Transform(rot, l.p1);
  }
  return out;
}

std::vector<TimedPose> Slam::map_trajectory() const {
  std::vector<TimedPose> out = trajectory_;
  for (auto& p : out) p.pose = ToMap(p.pose);
  return out;
}

void Slam::AdoptMap(const Pose2& local_to_map, const std::vector<LineFeature>& saved_lines) {
  const ResumeOptions& ro = options_.resume;
  const Eigen::Matrix2d floor =
      Eigen::Vector2d(ro.line_sigma_rho_m * ro.line_sigma_rho_m,
                      ro.line_sigma_theta_rad * ro.line_sigma_theta_rad)
          .asDiagonal();
  std::vector<LineEkf::SavedLine> state;
  state.reserve(saved_lines.size());
  for (const auto& l : saved_lines) {
    Eigen::Matrix2d c = l.cov;
    c(0, 0) = std::max(c(0, 0), floor(0, 0));
    c(1, 1) = std::max(c(1, 1), floor(1, 1));
    state.push_back({l.rho, l.theta, c});
  }
  const Eigen::Matrix3d pose_cov = ResumedPoseCov(ro);
  // Local lines the saved map does not have (a piece of furniture moved or
  // new, seen while relocalising) are kept, as new lines after the saved ones:
  // the model then knows them before any work is planned.
  std::vector<LineFeature> kept = saved_lines;
  for (LineFeature l : lines_) {
    l.p0 = Transform(local_to_map, l.p0);
    l.p1 = Transform(local_to_map, l.p1);
    l.theta = NormalizeAngle(l.theta + local_to_map.theta);
    l.rho += Normal(l.theta).dot(Eigen::Vector2d(local_to_map.x, local_to_map.y));
    if (l.rho < 0) {
      l.rho = -l.rho;
      l.theta = NormalizeAngle(l.theta + M_PI);
    }
    const bool known = std::any_of(saved_lines.begin(), saved_lines.end(), [&](const LineFeature& m) {
      const double dt = std::abs(NormalizeAngle(l.theta - m.theta));
      const Eigen::Vector2d d = Direction(m.theta);
      const double lo = std::min(d.dot(m.p0), d.dot(m.p1)), hi = std::max(d.dot(m.p0), d.dot(m.p1));
      const double a = std::min(d.dot(l.p0), d.dot(l.p1)), b = std::max(d.dot(l.p0), d.dot(l.p1));
      return dt < ro.known_angle_rad && std::abs(l.rho - m.rho) < ro.known_offset_m &&
             std::min(hi, b) - std::max(lo, a) > -ro.known_offset_m;
    });
    if (known) continue;
    l.collinear_with = 0;
    l.id = 0;  // numbered below, after the saved ones
    kept.push_back(l);
    Eigen::Matrix2d c = l.cov;
    c(0, 0) = std::max(c(0, 0), floor(0, 0));
    c(1, 1) = std::max(c(1, 1), floor(1, 1));
    state.push_back({l.rho, l.theta, c});
  }
  ekf_.Restart(Compose(local_to_map, ekf_.pose()), pose_cov, state);
  lines_ = std::move(kept);
  next_id_ = 1;
  for (const auto& l : lines_) next_id_ = std::max(next_id_, l.id + 1);
  for (auto& l : lines_) {
    if (l.id == 0) l.id = next_id_++;
  }
  for (size_t i = 0; i < lines_.size(); ++i) {
    // The state's normalised (rho >= 0) form; the endpoints are the saved ones.
    lines_[i].rho = ekf_.rho(static_cast<int>(i));
    lines_[i].theta = ekf_.theta(static_cast<int>(i));
    lines_[i].cov = ekf_.LineCov(static_cast<int>(i));
    next_id_ = std::max(next_id_, lines_[i].id + 1);
  }
  for (auto& p : trajectory_) p.pose = Compose(local_to_map, p.pose);
  gate_rejections_in_a_row_ = 0;
  saved_frame_ = true;
  first_new_id_ = next_id_;
}

void Slam::ForgetMap() {
  const ResumeOptions& ro = options_.resume;
  const Eigen::Matrix3d pose_cov = ResumedPoseCov(ro);
  ekf_.Restart(ekf_.pose(), pose_cov, {});
  lines_.clear();
  trajectory_.clear();
  gate_rejections_in_a_row_ = 0;
  saved_frame_ = false;
  first_new_id_ = 0;
}

void Slam::RemoveLines(const std::vector<int>& ids) {
  for (int id : ids) {
    const int i = IndexOf(id);
    // Line 0 fixes the map frame's rotation when it is not a saved one: kept.
    if (i < 0 || (i == 0 && !saved_frame_)) continue;
    ekf_.RemoveLine(i);
    lines_.erase(lines_.begin() + i);
  }
  for (auto& l : lines_) {
    if (std::find(ids.begin(), ids.end(), l.collinear_with) != ids.end()) l.collinear_with = 0;
  }
}

int Slam::IndexOf(int id) const {
  for (size_t i = 0; i < lines_.size(); ++i) {
    if (lines_[i].id == id) return static_cast<int>(i);
  }
  return -1;
}

void Slam::AddWheelTicks(const WheelTicks& ticks) {
  const std::optional<WheelMotion> m = odometry_.Add(ticks, ekf_.calibration());
  odom_history_.emplace_back(ticks.t, odometry_.pose());
  while (odom_history_.size() > 2 && odom_history_.front().first < ticks.t - 0.5) {
    odom_history_.pop_front();
  }
  if (!m) {
    trajectory_.push_back({ticks.t, ekf_.pose()});
    return;
  }
  MotionNoise noise = options_.motion_noise;
  noise.var_per_m *= noise_scale_;
  noise.var_theta_per_rad *= noise_scale_;
  noise.var_theta_per_m *= noise_scale_;
  ekf_.Predict(*m, options_.geometry.wheel_base_m, noise,
               options_.calibration.random_walk_per_m, options_.calibration.min_sigma);
  if (trajectory_.empty() || ticks.t - trajectory_.back().t >= options_.trajectory_period_s) {
    trajectory_.push_back({ticks.t, ekf_.pose()});
  }
  // Scans stamped up to now can be placed on the odometry path.
  while (!pending_scans_.empty() && pending_scans_.front().t <= ticks.t) {
    const RangeScan scan = pending_scans_.front();
    pending_scans_.pop_front();
    AddScanAt(scan, OdometryAt(scan.t));
  }
}

Pose2 Slam::OdometryAt(double t) const {
  if (odom_history_.empty()) return odometry_.pose();
  if (t <= odom_history_.front().first) return odom_history_.front().second;
  for (size_t i = 1; i < odom_history_.size(); ++i) {
    const auto& [t1, p1] = odom_history_[i];
    if (t <= t1) {
      const auto& [t0, p0] = odom_history_[i - 1];
      const double f = t1 > t0 ? (t - t0) / (t1 - t0) : 1.0;
      return {p0.x + f * (p1.x - p0.x), p0.y + f * (p1.y - p0.y),
              NormalizeAngle(p0.theta + f * NormalizeAngle(p1.theta - p0.theta))};
    }
  }
  return odom_history_.back().second;
}

void Slam::AddRangeScan(const RangeScan& scan) {
  // The IR sample is usually stamped a few ms after the last encoder frame: wait
  // for the odometry to get there, so each point is placed from the pose it was
  // measured at (at 0.8 rad/s, 10 ms of lag would bend a PDS line by ~0.5 deg).
  if (scan.t <= odometry_.last_t() && !odom_history_.empty()) {
    AddScanAt(scan, OdometryAt(scan.t));
  } else {
    pending_scans_.push_back(scan);
    while (pending_scans_.size() > 16) pending_scans_.pop_front();
  }
}

void Slam::AddScanAt(const RangeScan& scan, const Pose2& o) {
  if (have_last_scan_pose_) {
    const double moved = std::hypot(o.x - last_scan_pose_.x, o.y - last_scan_pose_.y);
    const double turned = std::abs(NormalizeAngle(o.theta - last_scan_pose_.theta));
    // The PDS takes a scan only after a minimum pose change (§3.1).
    if (moved < options_.pds.min_step_m && turned < options_.pds.min_turn_rad) return;
    window_distance_ += moved;
    window_turn_ += turned;
  }
  have_last_scan_pose_ = true;
  last_scan_pose_ = o;
  for (int i = 0; i < kNumIrSensors; ++i) {
    if (!scan.range_m[i] || *scan.range_m[i] > options_.pds.max_range_m) continue;
    const SensorMount& m = options_.mounts[i];
    const Eigen::Vector2d in_robot(m.x + *scan.range_m[i] * std::cos(m.theta),
                                   m.y + *scan.range_m[i] * std::sin(m.theta));
    pds_points_.push_back(Transform(o, in_robot));
  }
  pds_positions_.emplace_back(o.x, o.y);
  if (window_distance_ >= options_.pds.window_m || window_turn_ >= options_.pds.window_rad) {
    CloseWindow();
  }
}

void Slam::CloseWindow() {
  ++stats_.windows;

  // Express the window in the robot frame now, so lines come out as observations.
  const Pose2& o = odometry_.pose();
  Points pts;
  pts.reserve(pds_points_.size());
  for (const auto& p : pds_points_) pts.push_back(InverseTransform(o, p));
  Eigen::Vector2d centre = Eigen::Vector2d::Zero();
  for (const auto& p : pds_positions_) centre += InverseTransform(o, p);
  if (!pds_positions_.empty()) centre /= static_cast<double>(pds_positions_.size());
  const std::vector<ExtractedLine> lines = ExtractLines(pts, centre, options_.extraction);
  stats_.lines_extracted += static_cast<int>(lines.size());
  last_window_lines_ = lines;
  pds_points_.clear();
  pds_positions_.clear();
  window_distance_ = 0;
  window_turn_ = 0;
  ProcessLines(lines);
}

void Slam::ProcessLines(const std::vector<ExtractedLine>& lines) {
  for (const auto& l : lines) Associate(l);
  MergeOverlapping();
}

double Slam::Overlap(int i, const Eigen::Vector2d& a, const Eigen::Vector2d& b) const {
  // Lov (eq. 16): l_i + l_j - span of both, along line i; > 0 when they overlap.
  const Eigen::Vector2d dir = Direction(ekf_.theta(i));
  const double a0 = dir.dot(lines_[i].p0), a1 = dir.dot(lines_[i].p1);
  const double b0 = dir.dot(a), b1 = dir.dot(b);
  return std::min(std::max(a0, a1), std::max(b0, b1)) - std::max(std::min(a0, a1), std::min(b0, b1));
}

void Slam::AppendConstraintRows(int index, std::vector<Eigen::RowVectorXd>* h,
                                std::vector<double>* y, std::vector<double>* r) const {
  if (!options_.association.use_constraints || index == 0) return;
  const long n = ekf_.x().size();
  const double sc = options_.association.constraint_sigma_rad;
  // Eq. (11): theta_1 - theta_k (- pi/2) = 0, for parallel and orthogonal lines alike.
  Eigen::RowVectorXd row = Eigen::RowVectorXd::Zero(n);
  row(LineEkf::ThetaIndex(index)) = 1;
  row(LineEkf::ThetaIndex(0)) = -1;
  h->push_back(row);
  y->push_back(-AngleModHalfPi(ekf_.theta(index) - ekf_.theta(0)));
  r->push_back(sc * sc);
  // Eq. (12): a collinear piece of another wall: [rho_w - rho_w', theta_w - theta_w'] = 0.
  const int partner = lines_[index].collinear_with ? IndexOf(lines_[index].collinear_with) : -1;
  if (partner >= 0) {
    const double sr = options_.association.collinear_sigma_m;
    Eigen::RowVectorXd rr = Eigen::RowVectorXd::Zero(n), rt = Eigen::RowVectorXd::Zero(n);
    rr(LineEkf::RhoIndex(index)) = 1;
    rr(LineEkf::RhoIndex(partner)) = -1;
    rt(LineEkf::ThetaIndex(index)) = 1;
    rt(LineEkf::ThetaIndex(partner)) = -1;
    h->push_back(rr);
    y->push_back(-(ekf_.rho(index) - ekf_.rho(partner)));
    r->push_back(sr * sr);
    h->push_back(rt);
    y->push_back(-NormalizeAngle(ekf_.theta(index) - ekf_.theta(partner)));
    r->push_back(sc * sc);
  }
}

void Slam::ApplyConstraintsOnly(int index) {
  std::vector<Eigen::RowVectorXd> rows;
  std::vector<double> y, r;
  AppendConstraintRows(index, &rows, &y, &r);
  if (rows.empty()) return;
  const long m = static_cast<long>(rows.size());
  Eigen::MatrixXd h(m, ekf_.x().size());
  Eigen::VectorXd yy(m);
  Eigen::MatrixXd rr = Eigen::MatrixXd::Zero(m, m);
  for (long k = 0; k < m; ++k) {
    h.row(k) = rows[static_cast<size_t>(k)];
    yy(k) = y[static_cast<size_t>(k)];
    rr(k, k) = r[static_cast<size_t>(k)];
  }
  ekf_.Update(yy, h, rr);
}

int Slam::InsertLine(const ExtractedLine& obs, int collinear_with_index) {
  const Eigen::Matrix2d r = obs.cov * options_.association.measurement_cov_scale;
  const Pose2 pose = ekf_.pose();
  const int index = ekf_.AddLine({obs.rho, obs.theta}, r);
  LineFeature f;
  f.id = next_id_++;
  f.observations = 1;
  f.collinear_with = collinear_with_index >= 0 ? lines_[static_cast<size_t>(collinear_with_index)].id : 0;
  f.p0 = Transform(pose, obs.p0);
  f.p1 = Transform(pose, obs.p1);
  lines_.push_back(f);
  ++stats_.insertions;
  if (index == 0) {
    // The first line is a wall and defines the map's orientation: the map frame
    // is the internal frame turned so that it lies along x (theta_1 = pi/2). The
    // paper pins its angle (a near-zero-noise pseudo-measurement); optional here.
    if (options_.association.pin_first_line) {
      Eigen::MatrixXd h = Eigen::MatrixXd::Zero(1, ekf_.x().size());
      h(0, LineEkf::ThetaIndex(0)) = 1;
      Eigen::MatrixXd rr(1, 1);
      rr(0, 0) = 1e-12;
      ekf_.Update(Eigen::VectorXd::Zero(1), h, rr);
    }
  } else {
    ApplyConstraintsOnly(index);
  }
  ReprojectEndpoints();
  return index;
}

void Slam::ExtendEndpoints(int index, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  // Project the outermost points onto the (updated) line: the segment only grows.
  LineFeature& l = lines_[static_cast<size_t>(index)];
  const double th = ekf_.theta(index), rho = ekf_.rho(index);
  const Eigen::Vector2d dir = Direction(th), nrm = Normal(th);
  const double s[4] = {dir.dot(l.p0), dir.dot(l.p1), dir.dot(a), dir.dot(b)};
  const double lo = *std::min_element(s, s + 4), hi = *std::max_element(s, s + 4);
  l.p0 = rho * nrm + lo * dir;
  l.p1 = rho * nrm + hi * dir;
}

void Slam::ReprojectEndpoints() {
  for (size_t i = 0; i < lines_.size(); ++i) {
    LineFeature& l = lines_[i];
    const int k = static_cast<int>(i);
    const Eigen::Vector2d dir = Direction(ekf_.theta(k)), nrm = Normal(ekf_.theta(k));
    l.p0 = ekf_.rho(k) * nrm + dir.dot(l.p0) * dir;
    l.p1 = ekf_.rho(k) * nrm + dir.dot(l.p1) * dir;
    l.rho = ekf_.rho(k);
    l.theta = ekf_.theta(k);
    l.cov = ekf_.LineCov(k);
  }
}

void Slam::Associate(const ExtractedLine& obs) {
  const Pose2 pose = ekf_.pose();
  double rho_m, theta_m;
  ObservationToMap(pose, {obs.rho, obs.theta}, &rho_m, &theta_m, nullptr, nullptr);
  const Eigen::Vector2d a = Transform(pose, obs.p0), b = Transform(pose, obs.p1);
  if (lines_.empty()) {
    InsertLine(obs, -1);
    return;
  }
  // Only lines parallel or orthogonal to the first wall are mapped; with the
  // Mahalanobis fallback the test is for lines that match nothing.
  const auto& ao = options_.association;
  const bool square = std::abs(AngleModHalfPi(theta_m - ekf_.theta(0))) <= ao.angle_tolerance_rad;
  if (!square && ao.fallback_mahalanobis2 <= 0) {
    ++stats_.rejected_angle;
    return;
  }
  double best_dr = 0;
  int best = NearestLine(pose, obs, rho_m, theta_m, &best_dr);
  bool fallback = false;
  if (best < 0 && ao.fallback_mahalanobis2 > 0) {
    best = NearestByMahalanobis(pose, obs, a, b);
    fallback = best >= 0;
    if (fallback) ++stats_.fallback_matches;
  }
  if (best >= 0 && (fallback || Overlap(best, a, b) > -ao.continuation_gap_m)) {
    UpdateMatched(obs, best, pose);
    return;
  }
  if (!square) {
    ++stats_.rejected_angle;
    return;
  }
  if (best < 0) {
    InsertLine(obs, -1);
    return;
  }
  InsertCollinearPiece(obs, best, best_dr);
}

int Slam::NearestLine(const Pose2& pose, const ExtractedLine& obs, double rho_m, double theta_m,
                      double* best_dr) const {
  // Eq. (13): the weighted Hough distance to every mapped line; keep the nearest.
  // As the paper, in the map frame (default); there a heading error e moves the
  // rho of a line seen at distance D from the map's origin by about D e (4
  // degrees at 5 m: 0.35 m, far beyond epsilon_DH), so after a stretch of slip
  // the wall being followed becomes a new line instead of correcting the
  // heading. associate_in_robot_frame takes it where the observation was made:
  // between the line extracted in the robot frame and each mapped line as the
  // robot would see it from its estimated pose (eq. (10)'s prediction), where the
  // same error moves rho only by the lever from the robot to the line; parallel
  // lines keep their separation in both (docs/error-budget.md).
  const auto& ao = options_.association;
  int best = -1;
  double best_dh = ao.max_dh;
  for (int i = 0; i < ekf_.num_lines(); ++i) {
    double dr, dt;
    if (ao.associate_in_robot_frame) {
      const LineObservation z = PredictObservation(pose, ekf_.rho(i), ekf_.theta(i), nullptr);
      dr = obs.rho - z.rho;
      dt = NormalizeAngle(obs.theta - z.theta);
    } else {
      dr = rho_m - ekf_.rho(i);
      dt = NormalizeAngle(theta_m - ekf_.theta(i));
      if (std::abs(dt) > M_PI / 2) {  // the same line seen with the opposite normal (rho ~ 0)
        dr = -rho_m - ekf_.rho(i);
        dt = NormalizeAngle(dt + M_PI);
      }
    }
    const double dh = ao.weight_rho * dr * dr + ao.weight_theta * dt * dt;
    if (dh < best_dh) {
      best_dh = dh;
      *best_dr = dr;
      best = i;
    }
  }
  return best;
}

int Slam::NearestByMahalanobis(const Pose2& pose, const ExtractedLine& obs, const Eigen::Vector2d& a,
                               const Eigen::Vector2d& b) const {
  int best = -1;
  double best_d2 = options_.association.fallback_mahalanobis2;
  for (int i = 0; i < ekf_.num_lines(); ++i) {
    if (Overlap(i, a, b) < -options_.association.fallback_max_gap_m) continue;
    std::vector<Eigen::RowVectorXd> rows;
    std::vector<double> y;
    MatchRows(pose, i, obs, &rows, &y);
    // y[0]: the offset as the robot sees it; the heading's error does not move it.
    if (std::abs(y[0]) > options_.association.fallback_max_offset_m) continue;
    const double d2 = MatchNis(rows, y, obs);
    if (d2 <= best_d2) {
      best_d2 = d2;
      best = i;
    }
  }
  return best;
}

void Slam::InsertCollinearPiece(const ExtractedLine& obs, int best, double best_dr) {
  // Eqs. (14)-(15): collinear with a mapped line but not overlapping it: another
  // piece of the same wall (furniture in between), tied to it by eq. (12). The
  // tie is exact, and within epsilon_DH lie also the faces of two pieces of
  // furniture a few cm out of line: tying those would pull both (and the
  // robot) onto one line. So the tie is made only to a long line (a wall, not
  // a face of furniture) and when the offsets agree closely.
  const auto& ao = options_.association;
  const LineFeature& partner = lines_[static_cast<size_t>(best)];
  if (std::abs(best_dr) > ao.collinear_max_m || (partner.p1 - partner.p0).norm() < ao.collinear_min_length_m) {
    ++stats_.collinear_declined;
    InsertLine(obs, -1);
    return;
  }
  ++stats_.collinear_insertions;
  InsertLine(obs, best);
}

void Slam::MatchRows(const Pose2& pose, int best, const ExtractedLine& obs, std::vector<Eigen::RowVectorXd>* rows,
                     std::vector<double>* y) const {
  // Eq. (10): the measurement model of the matched line and its Jacobian in the
  // robot's and the line's columns; the innovation with the angle wrapped.
  Eigen::Matrix<double, 2, 5> j;
  const LineObservation zhat = PredictObservation(pose, ekf_.rho(best), ekf_.theta(best), &j);
  const long n = ekf_.x().size();
  for (int k = 0; k < 2; ++k) {
    Eigen::RowVectorXd row = Eigen::RowVectorXd::Zero(n);
    row.head<3>() = j.row(k).head<3>();
    row(LineEkf::RhoIndex(best)) = j(k, 3);
    row(LineEkf::ThetaIndex(best)) = j(k, 4);
    rows->push_back(row);
  }
  y->push_back(obs.rho - zhat.rho);
  y->push_back(NormalizeAngle(obs.theta - zhat.theta));
}

double Slam::MatchNis(const std::vector<Eigen::RowVectorXd>& rows, const std::vector<double>& y,
                      const ExtractedLine& obs) const {
  Eigen::MatrixXd hm(2, ekf_.x().size());
  hm.row(0) = rows[0];
  hm.row(1) = rows[1];
  // H P H' from H's non-zero columns (not a pass over the whole of P).
  const Eigen::Matrix2d s = ekf_.ProjectedCov(hm) + obs.cov * options_.association.measurement_cov_scale;
  const Eigen::Vector2d yy(y[0], y[1]);
  return yy.dot(s.inverse() * yy);
}

void Slam::AdaptMotionNoise(double nis) {
  // Covariance matching (odometry.h, MotionNoise::adapt_window): E[NIS] = 2 when
  // the filter's noise is right. One wild match moves the mean by a bounded step.
  const MotionNoise& n = options_.motion_noise;
  if (n.adapt_window <= 0) return;
  recent_nis_.push_back(std::min(nis, 2 * n.adapt_max_scale));
  while (recent_nis_.size() > static_cast<size_t>(n.adapt_window)) recent_nis_.pop_front();
  double sum = 0;
  for (double v : recent_nis_) sum += v;
  const double mean = sum / static_cast<double>(recent_nis_.size());
  noise_scale_ = std::clamp(mean / 2, 1.0, n.adapt_max_scale);
}

bool Slam::PassesGate(const std::vector<Eigen::RowVectorXd>& rows, const std::vector<double>& y,
                      const ExtractedLine& obs, double* r_scale) {
  // Innovation gate: a DH match that the covariance cannot explain is not used
  // (a wrong association would pull the whole map).
  const auto& ao = options_.association;
  const double d2 = MatchNis(rows, y, obs);
  AdaptMotionNoise(d2);
  if (d2 <= ao.max_mahalanobis2) {
    gate_rejections_in_a_row_ = 0;
    return true;
  }
  ++stats_.rejected_gate;
  if (ao.gate_recovery_after <= 0 || ++gate_rejections_in_a_row_ < ao.gate_recovery_after) return false;
  // Locked out: use it with R scaled so that it sits on the gate.
  gate_rejections_in_a_row_ = 0;
  ++stats_.gate_recoveries;
  *r_scale = d2 / ao.max_mahalanobis2;
  return true;
}

void Slam::UpdateMatched(const ExtractedLine& obs, int best, const Pose2& pose) {
  // Matched: eq. (10) with the constraints of this line, in one update.
  std::vector<Eigen::RowVectorXd> rows;
  std::vector<double> y, r;
  MatchRows(pose, best, obs, &rows, &y);
  double r_scale = 1;  // > 1 only for a gate recovery
  if (!PassesGate(rows, y, obs, &r_scale)) return;
  AppendConstraintRows(best, &rows, &y, &r);
  const long n = ekf_.x().size();
  const long m = static_cast<long>(rows.size());
  Eigen::MatrixXd h(m, n);
  Eigen::VectorXd yy(m);
  Eigen::MatrixXd rr = Eigen::MatrixXd::Zero(m, m);
  rr.topLeftCorner<2, 2>() = obs.cov * (options_.association.measurement_cov_scale * r_scale);
  for (long k = 0; k < m; ++k) {
    h.row(k) = rows[static_cast<size_t>(k)];
    yy(k) = y[static_cast<size_t>(k)];
    if (k >= 2) rr(k, k) = r[static_cast<size_t>(k - 2)];
  }
  ekf_.Update(yy, h, rr);
  ++stats_.updates;
  ++lines_[static_cast<size_t>(best)].observations;
  ReprojectEndpoints();
  // End points extended with the observation, seen from the corrected pose.
  const Pose2 corrected = ekf_.pose();
  ExtendEndpoints(best, Transform(corrected, obs.p0), Transform(corrected, obs.p1));
  ReprojectEndpoints();
}

void Slam::MergeOverlapping() {
  // §4.5: collinear lines that now overlap are one wall: update the older with
  // the newer (a zero-noise eq. (12) pseudo-measurement), take the outer end
  // points, delete the newer's rows and columns.
  bool merged = true;
  while (merged) {
    merged = false;
    for (int i = 0; i < ekf_.num_lines() && !merged; ++i) {
      for (int k = i + 1; k < ekf_.num_lines() && !merged; ++k) {
        const auto& ao = options_.association;
        const double dr = ekf_.rho(i) - ekf_.rho(k);
        const double dt = NormalizeAngle(ekf_.theta(i) - ekf_.theta(k));
        const double dh = ao.weight_rho * dr * dr + ao.weight_theta * dt * dt;
        const bool linked = lines_[static_cast<size_t>(k)].collinear_with == lines_[static_cast<size_t>(i)].id;
        if (!(linked || dh < ao.max_dh)) continue;
        if (Overlap(i, lines_[static_cast<size_t>(k)].p0, lines_[static_cast<size_t>(k)].p1) <= 0) continue;
        const long n = ekf_.x().size();
        Eigen::MatrixXd h = Eigen::MatrixXd::Zero(2, n);
        h(0, LineEkf::RhoIndex(i)) = 1;
        h(0, LineEkf::RhoIndex(k)) = -1;
        h(1, LineEkf::ThetaIndex(i)) = 1;
        h(1, LineEkf::ThetaIndex(k)) = -1;
        Eigen::VectorXd y(2);
        y << -dr, -dt;
        Eigen::MatrixXd r = Eigen::MatrixXd::Zero(2, 2);
        r(0, 0) = 1e-8;
        r(1, 1) = 1e-8;
        ekf_.Update(y, h, r);
        const LineFeature gone = lines_[static_cast<size_t>(k)];
        if (saved_frame_ && lines_[static_cast<size_t>(i)].id < first_new_id_ && gone.id >= first_new_id_)
          ++stats_.merges_into_saved;
        std::vector<int>& aliases = lines_[static_cast<size_t>(i)].merged;
        if (saved_frame_ && gone.id < first_new_id_) aliases.push_back(gone.id);
        aliases.insert(aliases.end(), gone.merged.begin(), gone.merged.end());
        ReprojectEndpoints();
        ExtendEndpoints(i, gone.p0, gone.p1);
        lines_[static_cast<size_t>(i)].observations += gone.observations;
        ekf_.RemoveLine(k);
        lines_.erase(lines_.begin() + k);
        for (auto& l : lines_) {
          if (l.collinear_with == gone.id) l.collinear_with = lines_[static_cast<size_t>(i)].id;
          if (l.collinear_with == l.id) l.collinear_with = 0;
        }
        ++stats_.merges;
        if (i == 0) ++stats_.loop_closures;
        ReprojectEndpoints();
        merged = true;
      }
    }
  }
}

options::Table<SlamOptions> SlamKeys() {
  static constexpr options::Key<SlamOptions> kKeys[] = {
      {"trajectory_period_s", &SlamOptions::trajectory_period_s, 0.01, 0.5, "s", "map trajectory sampling"},
  };
  return kKeys;
}

options::Table<PdsOptions> PdsKeys() {
  using P = PdsOptions;
  static constexpr options::Key<P> kKeys[] = {
      {"min_step_m", &P::min_step_m, 0, 1, "m", "a scan joins the pseudo dense scan after this much motion ..."},
      {"min_turn_rad", &P::min_turn_rad, 0, 1, "rad", "... or this much rotation"},
      {"window_m", &P::window_m, 0.05, 10, "m", "the window closes after this distance ..."},
      {"window_rad", &P::window_rad, 0.05, 10, "rad", "... or this rotation"},
      {"max_range_m", &P::max_range_m, 0.1, 10, "m", "readings beyond this are not used for mapping"},
  };
  return kKeys;
}

options::Table<ResumeOptions> ResumeKeys() {
  using R = ResumeOptions;
  static constexpr options::Key<R> kKeys[] = {
      {"pose_sigma_m", &R::pose_sigma_m, 0.001, 1, "m",
       "position uncertainty of the pose relocalised in a saved map"},
      {"pose_sigma_rad", &R::pose_sigma_rad, 0.001, 1, "rad", "... and of its heading"},
      {"line_sigma_rho_m", &R::line_sigma_rho_m, 0, 1, "m",
       "a saved line's rho keeps at least this uncertainty when a mission continues in its map"},
      {"line_sigma_theta_rad", &R::line_sigma_theta_rad, 0, 1, "rad", "... and its theta this"},
      {"known_offset_m", &R::known_offset_m, 0, 2, "m",
       "a line seen while relocalising is a saved one if within this offset (and angle) and overlapping ..."},
      {"known_angle_rad", &R::known_angle_rad, 0, 1, "rad", "... else it is kept as a new line"},
  };
  return kKeys;
}

options::Table<AssociationOptions> AssociationKeys() {
  using A = AssociationOptions;
  static constexpr options::Key<A> kKeys[] = {
      {"weight_rho", &A::weight_rho, 0, 1, "", "DH weight of rho, eq. (13); weight_rho + weight_theta = 1"},
      {"weight_theta", &A::weight_theta, 0, 1, "", "DH weight of theta, eq. (13)"},
      {"max_dh", &A::max_dh, 0, 10, "", "epsilon_DH: the largest weighted Hough distance of a match"},
      {"associate_in_robot_frame", &A::associate_in_robot_frame, 0, 0, "",
       "true: eq. (13) between the observation and each line as seen from the robot (false: in the map frame, as "
       "the paper; docs/error-budget.md)"},
      {"angle_tolerance_rad", &A::angle_tolerance_rad, 0, 0.78, "rad",
       "parallel/orthogonal to line 1 within this, else not mapped"},
      {"continuation_gap_m", &A::continuation_gap_m, 0, 1, "m",
       "a line matched by eq. (13) that continues the mapped one across at most this gap (no overlap) updates and "
       "extends it (0: a collinear piece, eqs. (14)-(15), as the paper)"},
      {"fallback_mahalanobis2", &A::fallback_mahalanobis2, 0, 1e3, "",
       "> 0: a line eq. (13) matches to nothing is matched to the overlapped line of the smallest innovation d^2 "
       "within this; the angle test then only for lines matching nothing (0: eq. (13) alone)"},
      {"fallback_max_gap_m", &A::fallback_max_gap_m, 0, 5, "m",
       "... a line the observation overlaps or continues across a gap of at most this"},
      {"fallback_max_offset_m", &A::fallback_max_offset_m, 0, 1, "m",
       "... and lies within this of, as the robot sees it (a parallel face farther away is another line)"},
      {"constraint_sigma_rad", &A::constraint_sigma_rad, 1e-9, 1, "rad", "pseudo-measurement noise, eqs. (11)-(12)"},
      {"collinear_sigma_m", &A::collinear_sigma_m, 1e-9, 1, "m", "collinear pseudo-measurement noise, eq. (12)"},
      {"collinear_max_m", &A::collinear_max_m, 0, 1, "m",
       "a collinear piece is tied to a mapped line only within this offset"},
      {"collinear_min_length_m", &A::collinear_min_length_m, 0, 100, "m",
       "... and only to one at least this long (a wall, not a face)"},
      {"measurement_cov_scale", &A::measurement_cov_scale, 1e-6, 1e6, "", "multiplies the eq. (7) covariance"},
      {"max_mahalanobis2", &A::max_mahalanobis2, 0.1, 1e9, "", "innovation gate of a match (chi^2, 2 dof)"},
      {"gate_recovery_after", &A::gate_recovery_after, 0, 1000, "",
       "after this many gate rejections in a row, the next is used with its noise inflated onto the gate (0: never)"},
      {"use_constraints", &A::use_constraints, 0, 0, "", "false: plain EKF (comparison, Fig. 17)"},
      {"pin_first_line", &A::pin_first_line, 0, 0, "",
       "true: the paper's pinned theta_1 (less accurate, docs/accuracy.md)"},
  };
  return kKeys;
}

}  // namespace irslam::slam
