// The SLAM front door: wheel ticks and range scans in (each with its own time),
// corrected pose, its covariance, the line map and the trajectory out.
// Pure: no clock, socket or file.
//
// Pipeline (paper §3-4): IR points are accumulated in the odometry frame into a
// pseudo dense scan (PDS) after each minimum pose change; when the window is
// complete (distance travelled or angle turned) its points are expressed in the
// robot frame, lines are extracted (line_extraction.h) and each line is
// associated (eqs. 13-16) with the map: matched lines update the geometrically
// constrained EKF (eq. 10 with the eq. 11/12 pseudo-measurements in the same
// update), collinear pieces are inserted with the collinear constraint, other
// lines parallel or orthogonal to the first wall are inserted, and the rest are
// not mapped. Collinear lines that come to overlap are merged (§4.5); a merge
// into the first line closes the loop.
//
// Frames: internally everything lives in the odometry frame of the start (so the
// pose stays continuous); the map frame of the outputs (map_*) is that frame
// rotated so the first wall lies along the x axis (theta_1 = pi/2).
#ifndef IRSLAM_SLAM_SLAM_H_
#define IRSLAM_SLAM_SLAM_H_

#include <Eigen/Core>
#include <array>
#include <deque>
#include <optional>
#include <vector>

#include "slam/line_ekf.h"
#include "slam/line_extraction.h"
#include "slam/odometry.h"
#include "types/geometry.h"
#include "types/options.h"
#include "types/signals.h"

namespace irslam::slam {

struct PdsOptions {
  double min_step_m = 0.01;     // a scan joins the PDS after this much motion ...
  double min_turn_rad = 0.03;   // ... or this much rotation
  double window_m = 0.6;        // the window closes after this distance ...
  double window_rad = 0.9;      // ... or this rotation
  double max_range_m = 0.8;     // readings beyond this are not used for mapping (noise grows ~d^2)
};

struct AssociationOptions {
  double weight_rho = 0.5;          // normalised weights of DH, eq. (13): sum to 1
  double weight_theta = 0.5;
  double max_dh = 0.006;            // epsilon_DH
  // True: eq. (13) taken between the observation and each mapped line as the
  // robot sees it from its estimated pose. False (default): in the map frame, as
  // the paper, where a heading error moves the rho of a line far from the origin
  // by distance x error, so the wall being followed stops matching after a bad
  // stretch (Slam::NearestLine). Measured in docs/error-budget.md: better on the
  // generated nominal rooms, worse on two paper worlds; off until that is solved.
  bool associate_in_robot_frame = false;
  double angle_tolerance_rad = 0.14;  // epsilon_theta: parallel/orthogonal to line 1
  // > 0: a line matched by eq. (13) that does not overlap the mapped line but
  // continues it across a gap of at most this is the same wall seen further on
  // (the next window of a wall being followed): it updates the line (eq. 10)
  // and extends it, instead of becoming a collinear piece (eqs. 14-15) that,
  // when declined (short partner), is a new line that never comes to overlap
  // and never corrects the pose. 0 (default): the paper's overlap test (eq. 16).
  double continuation_gap_m = 0;
  // > 0: when eq. (13) matches nothing, the mapped line the observation overlaps
  // with the smallest innovation Mahalanobis distance (with the prediction's
  // covariance; nearest neighbour within the gate, Bar-Shalom & Fortmann,
  // "Tracking and Data Association", 1988) is matched if its d^2 is within this
  // (chi^2, 2 dof; 5.99: 95 %), so what is matched widens with the pose's
  // uncertainty; and the first-wall angle test applies only to lines that match
  // nothing. 0 (default): eq. (13) alone, as the paper.
  double fallback_mahalanobis2 = 0;
  double fallback_max_gap_m = 0.3;  // ... to a line it overlaps or continues across at most this gap
  // ... and lies within this of as the robot sees it (its rho innovation): the
  // heading's uncertainty widens the angle that matches, not the offset, so a
  // face parallel to a wall a few cm in front of it is not taken for it.
  double fallback_max_offset_m = 0.06;
  double constraint_sigma_rad = 1e-3; // pseudo-measurement noise, eqs. (11)-(12)
  double collinear_sigma_m = 1e-3;
  double collinear_max_m = 0.04;        // a collinear piece is tied (eq. 12) only within this offset
  double collinear_min_length_m = 1.0;  // ... and only to a mapped line at least this long
  // Multiplies the eq. (7) covariance. 4 since 2026-12-07 (was 1): with the
  // motion noise a quarter of before (MotionNoise), the odometry's noise is a
  // sixteenth of the lines' relative to before (docs/error-budget.md, "Trusting
  // the odometry more"); the Hough scatter itself is, if anything, larger than
  // the lines' true error there.
  double measurement_cov_scale = 4.0;
  double max_mahalanobis2 = 13.8;     // innovation gate of a match (chi2, 2 dof, 99.9 %)
  // After this many gate rejections in a row (0: never), the next match the gate
  // rejects is used with its noise inflated to sit on the gate: the filter cannot
  // be locked out by its own overconfidence after a bad stretch (slip, a floor
  // change the calibration has not followed yet).
  int gate_recovery_after = 0;
  bool use_constraints = true;        // off: plain EKF (for comparison, Fig. 17)
  // The paper pins theta_1 at its first observation. Off (default): line 1 is
  // estimated like the others (the start pose is known, so the frame is fixed
  // anyway) and keeps improving; the map frame is still turned so that line 1
  // lies exactly along x.
  bool pin_first_line = false;
};

// The odometry calibration learnt (e.g. kept in a saved map): the scale factors
// and their standard deviations (kl, kr, kb).
struct CalibrationEstimate {
  OdometryCalibration value;
  Eigen::Vector3d sigma = Eigen::Vector3d::Zero();
  double ratio_sigma = 0;  // of value.ratio() (from the full covariance; 0 when not known)
};

// Continuing in a saved map (issue 14, Slam::AdoptMap): the uncertainty the
// relocalised pose starts with, and the least uncertainty a saved line keeps
// (a saved map's covariances are its own filter's, without the pose-line
// correlations that made them so small: a floor keeps the first updates from
// being overconfident).
struct ResumeOptions {
  double pose_sigma_m = 0.03;
  double pose_sigma_rad = 0.02;
  double line_sigma_rho_m = 0.005;
  double line_sigma_theta_rad = 0.005;
  // A local line (seen while relocalising) is one of the saved map's when a
  // saved line is within these of it and overlaps it; else it is kept as new.
  double known_offset_m = 0.1;
  double known_angle_rad = 0.1;
};
options::Table<ResumeOptions> ResumeKeys();  // [slam.resume]

struct SlamOptions {
  RobotGeometry geometry;
  MotionNoise motion_noise;
  CalibrationOptions calibration;  // [slam.calibration]
  // Not a config key: the calibration a mission starts from (the saved map's,
  // set by the daemon or the simulator); none: nominal with the prior sigmas.
  std::optional<CalibrationEstimate> initial_calibration;
  std::array<SensorMount, kNumIrSensors> mounts{};
  double trajectory_period_s = 0.25;  // trajectory sampling (>= 2 Hz, contracts §4)
  PdsOptions pds;
  ExtractionOptions extraction;
  AssociationOptions association;
  ResumeOptions resume;
};

struct LineFeature {
  int id = 0;
  double rho = 0;
  double theta = 0;
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  Eigen::Vector2d p0 = Eigen::Vector2d::Zero();
  Eigen::Vector2d p1 = Eigen::Vector2d::Zero();
  int observations = 0;
  int collinear_with = 0;  // id of the line this one is a collinear piece of (0: none)
  // Ids of lines of an adopted saved map merged into this one (§4.5: a wall
  // saved in pieces, seen whole again). The map's users may know a wall by any
  // of them; they stay its ids ("merged" in the map file).
  std::vector<int> merged;
  double length() const { return (p1 - p0).norm(); }
};

struct SlamStats {
  int windows = 0;
  int lines_extracted = 0;
  int updates = 0;
  int insertions = 0;
  int collinear_insertions = 0;
  int collinear_declined = 0;   // collinear by eq. (13) but not tied (offset, or short partner)
  int rejected_angle = 0;   // neither parallel nor orthogonal to line 1
  int rejected_gate = 0;    // matched by DH but inconsistent with the covariance
  int gate_recoveries = 0;  // rejected matches used anyway, noise inflated (gate_recovery_after)
  int fallback_matches = 0; // matched by the Mahalanobis fallback (fallback_mahalanobis2)
  int merges = 0;
  int loop_closures = 0;    // merges into the first line
  // Merges of a line mapped since AdoptMap into a line of the adopted saved
  // map: a wall of the saved map seen again whose piece the association missed
  // (a short piece a few degrees off, far from the origin, is beyond eq. (13)'s
  // Hough distance) but the merge recognised.
  int merges_into_saved = 0;
};

// Config section [slam]: SlamKeys() (with MotionNoiseKeys()), and its
// subsections [slam.pds], [slam.association], [slam.calibration] (CalibrationKeys()).
options::Table<SlamOptions> SlamKeys();
options::Table<PdsOptions> PdsKeys();
options::Table<AssociationOptions> AssociationKeys();

class Slam {
 public:
  explicit Slam(SlamOptions options);

  void AddWheelTicks(const WheelTicks& ticks);
  void AddRangeScan(const RangeScan& scan);

  // Internal (odometry-start) frame: continuous, for controllers.
  Pose2 pose() const { return ekf_.pose(); }
  // Map frame (first wall along x): for outputs.
  Pose2 map_pose() const { return ToMap(ekf_.pose()); }
  Eigen::Matrix3d map_pose_cov() const;
  std::vector<LineFeature> map_lines() const;
  std::vector<TimedPose> map_trajectory() const;
  Pose2 ToMap(const Pose2& p) const;
  // Internal -> map frame rotation (pi/2 - theta_1; 0 before the first line).
  double map_rotation() const;

  const std::vector<LineFeature>& lines() const { return lines_; }  // internal frame
  const std::vector<TimedPose>& trajectory() const { return trajectory_; }  // internal
  size_t num_lines() const { return lines_.size(); }
  const LineEkf& ekf() const { return ekf_; }
  const Pose2& odometry_pose() const { return odometry_.pose(); }
  double distance_m() const { return odometry_.distance_m(); }
  double time() const { return odometry_.last_t(); }
  const SlamStats& stats() const { return stats_; }
  // The factor the motion noise is multiplied by now (MotionNoise::adapt_window;
  // 1 when not adapted).
  double motion_noise_scale() const { return noise_scale_; }
  // The odometry's estimated systematic parameters and their sigmas.
  CalibrationEstimate calibration() const;
  // The lines extracted from the last closed PDS window (robot frame), e.g. for
  // recording observations for the Appendix 1 weights.
  const std::vector<ExtractedLine>& last_window_lines() const { return last_window_lines_; }
  const SlamOptions& options() const { return options_; }

  // Continues in a saved map (issue 14): the relocaliser found that this
  // SLAM's frame maps to the saved map's frame by local_to_map. From now on the
  // internal frame is the saved map's frame and stays it (map_rotation() 0):
  // the EKF's lines are replaced by the saved ones (map frame, ids kept, the
  // next new line numbered after them), the pose is carried over by the
  // transform with the [slam.resume] uncertainty, the trajectory so far is
  // transformed, and the calibration is kept. The local lines that are saved
  // lines seen again are dropped; the others (furniture moved or new) are
  // kept as new lines, numbered after the saved ones.
  void AdoptMap(const Pose2& local_to_map, const std::vector<LineFeature>& saved_lines);
  // Starts a new local map where the robot is (issue 14: the map disagreed and
  // the robot relocalises again): the lines and the trajectory are dropped, the
  // pose and the odometry (its distance too) go on, the frame is its own again.
  void ForgetMap();
  // Takes lines out of the map (issue 14: the sides of furniture that has moved
  // since the saved map), with their rows of the EKF state; ties to them are cut.
  void RemoveLines(const std::vector<int>& ids);
  bool in_saved_map() const { return saved_frame_; }

  // Feeds one window's extracted lines (robot frame) to the map; public so tests
  // can drive association and the EKF without the PDS.
  void ProcessLines(const std::vector<ExtractedLine>& lines);

 private:
  void AddScanAt(const RangeScan& scan, const Pose2& odom_pose);
  // Odometry pose at time t, interpolated in the recent history.
  Pose2 OdometryAt(double t) const;
  void CloseWindow();
  void Associate(const ExtractedLine& obs);
  // The pieces of Associate: the nearest mapped line by eq. (13) (-1: none
  // within epsilon_DH); a collinear piece, eqs. (14)-(15); a match, eq. (10),
  // its rows and innovation, its gate (false: not used; *r_scale > 1 for a gate
  // recovery).
  int NearestLine(const Pose2& pose, const ExtractedLine& obs, double rho_m, double theta_m,
                  double* best_dr) const;
  // fallback_mahalanobis2: of the lines the observation overlaps or continues
  // (fallback_max_gap_m) and lies within fallback_max_offset_m of, the one of the
  // smallest innovation d^2 within it (-1: none).
  int NearestByMahalanobis(const Pose2& pose, const ExtractedLine& obs, const Eigen::Vector2d& a,
                           const Eigen::Vector2d& b) const;
  // The normalised innovation squared (2 dof) of a match's rows and innovation
  // (MatchRows), with the prediction's covariance H P H' + R.
  double MatchNis(const std::vector<Eigen::RowVectorXd>& rows, const std::vector<double>& y,
                  const ExtractedLine& obs) const;
  // MotionNoise::adapt_window: one more match's NIS into the running mean.
  void AdaptMotionNoise(double nis);
  void InsertCollinearPiece(const ExtractedLine& obs, int best, double best_dr);
  void UpdateMatched(const ExtractedLine& obs, int best, const Pose2& pose);
  void MatchRows(const Pose2& pose, int best, const ExtractedLine& obs, std::vector<Eigen::RowVectorXd>* rows,
                 std::vector<double>* y) const;
  bool PassesGate(const std::vector<Eigen::RowVectorXd>& rows, const std::vector<double>& y,
                  const ExtractedLine& obs, double* r_scale);
  int InsertLine(const ExtractedLine& obs, int collinear_with_index);
  void ApplyConstraintsOnly(int index);
  void AppendConstraintRows(int index, std::vector<Eigen::RowVectorXd>* h,
                            std::vector<double>* y, std::vector<double>* r) const;
  void ExtendEndpoints(int index, const Eigen::Vector2d& a, const Eigen::Vector2d& b);
  void ReprojectEndpoints();
  void MergeOverlapping();
  double Overlap(int i, const Eigen::Vector2d& a, const Eigen::Vector2d& b) const;
  int IndexOf(int id) const;

  SlamOptions options_;
  Odometry odometry_;
  LineEkf ekf_;
  std::vector<LineFeature> lines_;  // lines_[i] is state line i
  std::vector<TimedPose> trajectory_;
  SlamStats stats_;
  std::vector<ExtractedLine> last_window_lines_;
  int next_id_ = 1;
  int gate_rejections_in_a_row_ = 0;
  std::deque<double> recent_nis_;  // MotionNoise::adapt_window
  double noise_scale_ = 1;
  bool saved_frame_ = false;  // AdoptMap: the internal frame is a saved map's
  int first_new_id_ = 0;      // AdoptMap: lines with a smaller id were adopted

  // Recent odometry poses (for scans stamped between encoder frames) and scans
  // waiting for the odometry to reach their time.
  std::deque<std::pair<double, Pose2>> odom_history_;
  std::deque<RangeScan> pending_scans_;

  // Pseudo dense scan window (odometry frame).
  Points pds_points_;
  std::vector<Eigen::Vector2d> pds_positions_;
  bool have_last_scan_pose_ = false;
  Pose2 last_scan_pose_;
  double window_distance_ = 0;
  double window_turn_ = 0;
};

}  // namespace irslam::slam

#endif  // IRSLAM_SLAM_SLAM_H_
