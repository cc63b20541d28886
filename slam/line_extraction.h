// Line feature extraction from a pseudo dense scan: the paper's multi-level
// filter (§3). Every step is a separate pure function so it can be tested alone.
//   1. gravity resampling of the PDS (§3.1)
//   2. gap clustering + IEPF split-and-merge, N/L pruning (1st filter, §3.2)
//   3. orthogonal least-squares fit, delta residual filter (2nd filter, §3.3)
//   4. constrained Hough transform around (rho0, theta0) (§3.4)
//   5. measurement covariance from the votes, eq. (7); combined uncertainty U,
//      eq. (8), as the last filter (§3.5)
// Line convention: x cos(theta) + y sin(theta) = rho, rho >= 0, theta in (-pi, pi].
#ifndef IRSLAM_SLAM_LINE_EXTRACTION_H_
#define IRSLAM_SLAM_LINE_EXTRACTION_H_

#include <Eigen/Core>
#include <vector>

#include "types/options.h"

namespace irslam::slam {

using Points = std::vector<Eigen::Vector2d>;

struct ExtractionOptions {
  double gravity_radius_m = 0.02;   // resampling: neighbours closer than this ...
  int gravity_max_points = 4;       // ... and at most this many form one cluster
  double cluster_gap_m = 0.10;      // D: split where consecutive points are farther apart
  int min_points = 6;               // N
  double min_length_m = 0.30;       // L
  double split_threshold_m = 0.03;  // T (IEPF)
  double max_fit_rms_m = 0.02;      // delta: orthogonal fit residual (RMS)
  double hough_rho_window_m = 0.05; // constrained Hough: +-5 cm ...
  double hough_rho_res_m = 0.01;    // ... at 1 cm
  double hough_theta_window_rad = 5 * M_PI / 180;  // +-5 deg ...
  double hough_theta_res_rad = 1 * M_PI / 180;     // ... at 1 deg
  // Eq. (8) weights (Appendix 1; `irslam-weights` computes them from recorded lines)
  // (defaults: irslam-weights over the Fig. 14 room, seeds 1-3, docs/accuracy.md)
  double weight_length = 0.487;     // wl  [m]
  double weight_rho = 1459;         // wrho [1/m^2]
  double weight_theta = 791;        // wtheta [1/rad^2]
  // Lines with U above this are dropped. 12, not the 4.5 first set on the Fig. 14
  // room alone: over 200 generated rooms it finds furniture in 80.4 % of them
  // (4.5: 70.8 %) and every paper world's objects as well or better
  // (docs/error-budget.md, "the eq. (8) threshold").
  double max_uncertainty = 12;
};

// Config section [slam.extraction].
options::Table<ExtractionOptions> ExtractionKeys();

struct LineFit {
  double rho = 0, theta = 0;
  double rms = 0;  // orthogonal residual RMS
};

struct HoughResult {
  double rho = 0, theta = 0;       // (rhoMax, thetaMax), refined to sub-cell
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();  // eq. (7)
  int votes_cast = 0;
  int cells = 0;
  int peak_votes = 0;
};

struct ExtractedLine {
  double rho = 0, theta = 0;
  Eigen::Matrix2d cov = Eigen::Matrix2d::Zero();
  Eigen::Vector2d p0 = Eigen::Vector2d::Zero(), p1 = Eigen::Vector2d::Zero();
  double length = 0;
  int points = 0;
  double uncertainty = 0;  // U, eq. (8)
};

struct ExtractionStats {
  int input_points = 0;
  int resampled_points = 0;
  int clusters = 0;     // after gap clustering and pruning
  int segments = 0;     // after IEPF and pruning (1st filter)
  int fitted = 0;       // after the delta filter (2nd filter)
  int kept = 0;         // after the U filter
};

// Normalises (rho, theta) so that rho >= 0 and theta is in (-pi, pi].
void NormalizeLine(double* rho, double* theta);

// Step 1: sort by polar angle about `centre`, merge neighbours into their mean.
Points GravityResample(const Points& pts, const Eigen::Vector2d& centre, double radius,
                       int max_points);
// Step 2: split consecutive points where the gap exceeds D.
std::vector<Points> GapCluster(const Points& pts, double gap);
// IEPF: recursive split at the farthest point from the end-point chord while it is
// farther than T, then merge neighbours whose joint chord fits within T.
std::vector<Points> SplitAndMerge(const Points& cluster, double threshold);
// Drops clusters with fewer than N points or shorter than L.
std::vector<Points> Prune(std::vector<Points> clusters, int min_points, double min_length);
// Step 3: orthogonal (total) least squares.
LineFit FitLine(const Points& pts);
// Step 4+5: votes in a (2w/res+1)^2 window around (rho0, theta0); covariance eq. (7).
HoughResult ConstrainedHough(const Points& pts, double rho0, double theta0,
                             const ExtractionOptions& o);
// The unconstrained transform over all (rho, theta) for comparison (Table 1).
HoughResult FullHough(const Points& pts, double max_rho, const ExtractionOptions& o);
// Eq. (8).
double CombinedUncertainty(double length, const Eigen::Matrix2d& cov, const ExtractionOptions& o);

// The whole chain; `centre` is the PDS window centre (for the polar sort).
std::vector<ExtractedLine> ExtractLines(const Points& pds, const Eigen::Vector2d& centre,
                                        const ExtractionOptions& o,
                                        ExtractionStats* stats = nullptr);

}  // namespace irslam::slam

#endif  // IRSLAM_SLAM_LINE_EXTRACTION_H_

