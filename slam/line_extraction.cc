#include "slam/line_extraction.h"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <numeric>

#include "types/geometry.h"
#include "types/signals.h"

namespace irslam::slam {
namespace {

double PointLineDistance(const Eigen::Vector2d& p, const Eigen::Vector2d& a,
                         const Eigen::Vector2d& b) {
  const Eigen::Vector2d d = b - a;
  const double len = d.norm();
  if (len < 1e-12) return (p - a).norm();
  return std::abs(d.x() * (p.y() - a.y()) - d.y() * (p.x() - a.x())) / len;
}

double Extent(const Points& pts) { return pts.size() < 2 ? 0.0 : (pts.back() - pts.front()).norm(); }

void SplitRecursive(const Points& pts, size_t lo, size_t hi, double t, std::vector<Points>* out) {
  double best = -1;
  size_t at = lo;
  for (size_t i = lo + 1; i < hi; ++i) {
    const double d = PointLineDistance(pts[i], pts[lo], pts[hi]);
    if (d > best) {
      best = d;
      at = i;
    }
  }
  if (best > t && at > lo && at < hi) {
    // C1 = {lo..a}, C2 = {a..hi}: the split point belongs to both (§3.2).
    SplitRecursive(pts, lo, at, t, out);
    SplitRecursive(pts, at, hi, t, out);
    return;
  }
  out->emplace_back(pts.begin() + static_cast<long>(lo), pts.begin() + static_cast<long>(hi) + 1);
}

}  // namespace

void NormalizeLine(double* rho, double* theta) {
  if (*rho < 0) {
    *rho = -*rho;
    *theta += M_PI;
  }
  *theta = NormalizeAngle(*theta);
}

Points GravityResample(const Points& pts, const Eigen::Vector2d& centre, double radius,
                       int max_points) {
  if (pts.empty()) return {};
  std::vector<std::pair<double, Eigen::Vector2d>> polar;
  polar.reserve(pts.size());
  for (const auto& p : pts) polar.emplace_back(std::atan2(p.y() - centre.y(), p.x() - centre.x()), p);
  std::sort(polar.begin(), polar.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  // Start the sequence after the widest angular gap, so that a surface seen across
  // the -pi/pi cut of the polar angle stays in one piece.
  size_t start = 0;
  double widest = polar.front().first + 2 * M_PI - polar.back().first;
  for (size_t i = 1; i < polar.size(); ++i) {
    const double gap = polar[i].first - polar[i - 1].first;
    if (gap > widest) {
      widest = gap;
      start = i;
    }
  }
  std::rotate(polar.begin(), polar.begin() + static_cast<long>(start), polar.end());
  Points out;
  size_t i = 0;
  while (i < polar.size()) {
    Eigen::Vector2d sum = polar[i].second;
    int n = 1;
    size_t j = i + 1;
    while (j < polar.size() && n < max_points && (polar[j].second - polar[i].second).norm() < radius) {
      sum += polar[j].second;
      ++n;
      ++j;
    }
    out.push_back(sum / n);  // "gravity": the cluster's mean
    i = j;
  }
  return out;
}

std::vector<Points> GapCluster(const Points& pts, double gap) {
  std::vector<Points> out;
  for (size_t i = 0; i < pts.size(); ++i) {
    if (i == 0 || (pts[i] - pts[i - 1]).norm() > gap) out.emplace_back();
    out.back().push_back(pts[i]);
  }
  return out;
}

std::vector<Points> SplitAndMerge(const Points& cluster, double threshold) {
  if (cluster.size() < 3) return {cluster};
  std::vector<Points> pieces;
  SplitRecursive(cluster, 0, cluster.size() - 1, threshold, &pieces);
  // Merge consecutive pieces whose points all lie within T of the joint chord.
  bool merged = true;
  while (merged && pieces.size() > 1) {
    merged = false;
    for (size_t i = 0; i + 1 < pieces.size(); ++i) {
      Points joint = pieces[i];
      joint.insert(joint.end(), pieces[i + 1].begin() + 1, pieces[i + 1].end());
      bool fits = true;
      for (const auto& p : joint) {
        if (PointLineDistance(p, joint.front(), joint.back()) > threshold) {
          fits = false;
          break;
        }
      }
      if (fits) {
        pieces[i] = std::move(joint);
        pieces.erase(pieces.begin() + static_cast<long>(i) + 1);
        merged = true;
        break;
      }
    }
  }
  return pieces;
}

std::vector<Points> Prune(std::vector<Points> clusters, int min_points, double min_length) {
  clusters.erase(std::remove_if(clusters.begin(), clusters.end(),
                                [&](const Points& c) {
                                  return static_cast<int>(c.size()) < min_points ||
                                         Extent(c) < min_length;
                                }),
                 clusters.end());
  return clusters;
}

LineFit FitLine(const Points& pts) {
  LineFit f;
  if (pts.size() < 2) return f;
  Eigen::Vector2d c = Eigen::Vector2d::Zero();
  for (const auto& p : pts) c += p;
  c /= static_cast<double>(pts.size());
  Eigen::Matrix2d s = Eigen::Matrix2d::Zero();
  for (const auto& p : pts) s += (p - c) * (p - c).transpose();
  // The normal is the eigenvector of the smallest eigenvalue of the scatter matrix:
  // the orthogonal (total) least-squares version of the paper's eqs. (1)-(4).
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> es(s);
  const Eigen::Vector2d n = es.eigenvectors().col(0);
  f.theta = std::atan2(n.y(), n.x());
  f.rho = n.dot(c);
  NormalizeLine(&f.rho, &f.theta);
  f.rms = std::sqrt(std::max(0.0, es.eigenvalues()(0)) / static_cast<double>(pts.size()));
  return f;
}

HoughResult ConstrainedHough(const Points& pts, double rho0, double theta0,
                             const ExtractionOptions& o) {
  const int kr = static_cast<int>(std::lround(o.hough_rho_window_m / o.hough_rho_res_m));
  const int kt = static_cast<int>(std::lround(o.hough_theta_window_rad / o.hough_theta_res_rad));
  const int nr = 2 * kr + 1, nt = 2 * kt + 1;
  std::vector<int> votes(static_cast<size_t>(nr * nt), 0);
  HoughResult h;
  h.cells = nr * nt;
  std::vector<double> ct(static_cast<size_t>(nt)), st(static_cast<size_t>(nt));
  for (int l = 0; l < nt; ++l) {
    const double th = theta0 + (l - kt) * o.hough_theta_res_rad;
    ct[static_cast<size_t>(l)] = std::cos(th);
    st[static_cast<size_t>(l)] = std::sin(th);
  }
  for (const auto& p : pts) {
    for (int l = 0; l < nt; ++l) {
      const double r = p.x() * ct[static_cast<size_t>(l)] + p.y() * st[static_cast<size_t>(l)];
      const int k = static_cast<int>(std::lround((r - rho0) / o.hough_rho_res_m));
      if (k < -kr || k > kr) continue;
      ++votes[static_cast<size_t>((k + kr) * nt + l)];
      ++h.votes_cast;
    }
  }
  int best = 0, bk = 0, bl = 0;
  for (int k = 0; k < nr; ++k) {
    for (int l = 0; l < nt; ++l) {
      const int v = votes[static_cast<size_t>(k * nt + l)];
      // Ties: prefer the cell nearest the fit (the window's centre).
      if (v > best || (v == best && v > 0 && std::abs(k - kr) + std::abs(l - kt) <
                                              std::abs(bk - kr) + std::abs(bl - kt))) {
        best = v;
        bk = k;
        bl = l;
      }
    }
  }
  h.peak_votes = best;
  const auto rho_of = [&](int k) { return rho0 + (k - kr) * o.hough_rho_res_m; };
  const auto theta_of = [&](int l) { return theta0 + (l - kt) * o.hough_theta_res_rad; };
  // (rhoMax, thetaMax): the peak cell, refined to sub-cell by the vote-weighted mean
  // of its 3x3 neighbourhood (the cells are 1 cm x 1 deg; the mean is not quantised).
  double sw = 0, sr = 0, stt = 0;
  for (int k = std::max(0, bk - 1); k <= std::min(nr - 1, bk + 1); ++k) {
    for (int l = std::max(0, bl - 1); l <= std::min(nt - 1, bl + 1); ++l) {
      const double w = votes[static_cast<size_t>(k * nt + l)];
      sw += w;
      sr += w * rho_of(k);
      stt += w * theta_of(l);
    }
  }
  h.rho = sw > 0 ? sr / sw : rho0;
  h.theta = sw > 0 ? stt / sw : theta0;
  // Eq. (7): the vote-weighted scatter of the cells about (rhoMax, thetaMax).
  Eigen::Matrix2d c = Eigen::Matrix2d::Zero();
  double total = 0;
  for (int k = 0; k < nr; ++k) {
    for (int l = 0; l < nt; ++l) {
      const double v = votes[static_cast<size_t>(k * nt + l)];
      if (v == 0) continue;
      const Eigen::Vector2d d(rho_of(k) - h.rho, theta_of(l) - h.theta);
      c += v * d * d.transpose();
      total += v;
    }
  }
  if (total > 0) c /= total;
  // Guard against a degenerate (zero) matrix: the cells' quantisation variance.
  c(0, 0) += o.hough_rho_res_m * o.hough_rho_res_m / 12.0;
  c(1, 1) += o.hough_theta_res_rad * o.hough_theta_res_rad / 12.0;
  h.cov = c;
  NormalizeLine(&h.rho, &h.theta);
  return h;
}

HoughResult FullHough(const Points& pts, double max_rho, const ExtractionOptions& o) {
  const int nr = static_cast<int>(std::ceil(max_rho / o.hough_rho_res_m)) + 1;
  const int nt = static_cast<int>(std::lround(2 * M_PI / o.hough_theta_res_rad));
  std::vector<int> votes(static_cast<size_t>(nr * nt), 0);
  HoughResult h;
  h.cells = nr * nt;
  for (const auto& p : pts) {
    for (int l = 0; l < nt; ++l) {
      const double th = -M_PI + l * o.hough_theta_res_rad;
      const double r = p.x() * std::cos(th) + p.y() * std::sin(th);
      if (r < 0) continue;
      const int k = static_cast<int>(std::lround(r / o.hough_rho_res_m));
      if (k >= nr) continue;
      ++votes[static_cast<size_t>(k * nt + l)];
      ++h.votes_cast;
    }
  }
  int best = -1;
  for (int k = 0; k < nr; ++k) {
    for (int l = 0; l < nt; ++l) {
      if (votes[static_cast<size_t>(k * nt + l)] > best) {
        best = votes[static_cast<size_t>(k * nt + l)];
        h.rho = k * o.hough_rho_res_m;
        h.theta = -M_PI + l * o.hough_theta_res_rad;
      }
    }
  }
  h.peak_votes = best;
  return h;
}

double CombinedUncertainty(double length, const Eigen::Matrix2d& cov, const ExtractionOptions& o) {
  // Eq. (8): U = wl / l + wrho * c_rho_rho + wtheta * c_theta_theta.
  return o.weight_length / std::max(length, 1e-6) + o.weight_rho * cov(0, 0) +
         o.weight_theta * cov(1, 1);
}

std::vector<ExtractedLine> ExtractLines(const Points& pds, const Eigen::Vector2d& centre,
                                        const ExtractionOptions& o, ExtractionStats* stats) {
  ExtractionStats st;
  st.input_points = static_cast<int>(pds.size());
  const Points resampled = GravityResample(pds, centre, o.gravity_radius_m, o.gravity_max_points);
  st.resampled_points = static_cast<int>(resampled.size());
  const std::vector<Points> clusters =
      Prune(GapCluster(resampled, o.cluster_gap_m), o.min_points, o.min_length_m);
  st.clusters = static_cast<int>(clusters.size());
  std::vector<Points> segments;
  for (const auto& c : clusters) {
    for (auto& s : SplitAndMerge(c, o.split_threshold_m)) segments.push_back(std::move(s));
  }
  segments = Prune(std::move(segments), o.min_points, o.min_length_m);
  st.segments = static_cast<int>(segments.size());
  std::vector<ExtractedLine> out;
  for (const auto& seg : segments) {
    const LineFit fit = FitLine(seg);
    if (fit.rms > o.max_fit_rms_m) continue;  // 2nd filter (delta)
    ++st.fitted;
    const HoughResult h = ConstrainedHough(seg, fit.rho, fit.theta, o);
    ExtractedLine line;
    line.rho = h.rho;
    line.theta = h.theta;
    line.cov = h.cov;
    line.points = static_cast<int>(seg.size());
    // End points: the extreme points projected onto the refined line.
    const Eigen::Vector2d n(std::cos(h.theta), std::sin(h.theta));
    const Eigen::Vector2d dir(-n.y(), n.x());
    double smin = 1e18, smax = -1e18;
    for (const auto& p : seg) {
      const double s = dir.dot(p);
      smin = std::min(smin, s);
      smax = std::max(smax, s);
    }
    line.p0 = h.rho * n + smin * dir;
    line.p1 = h.rho * n + smax * dir;
    line.length = smax - smin;
    line.uncertainty = CombinedUncertainty(line.length, line.cov, o);
    if (line.length < o.min_length_m || line.uncertainty > o.max_uncertainty) continue;
    ++st.kept;
    out.push_back(line);
  }
  if (stats) *stats = st;
  return out;
}

options::Table<ExtractionOptions> ExtractionKeys() {
  using X = ExtractionOptions;
  static constexpr options::Key<X> kKeys[] = {
      {"gravity_radius_m", &X::gravity_radius_m, 0, 1, "m", "resampling: neighbours closer than this ..."},
      {"gravity_max_points", &X::gravity_max_points, 1, 100, "", "... and at most this many are averaged"},
      {"cluster_gap_m", &X::cluster_gap_m, 0.005, 2, "m", "D: split where consecutive points are farther apart"},
      {"min_points", &X::min_points, 2, 10000, "", "N: fewest points of a line"},
      {"min_length_m", &X::min_length_m, 0.01, 10, "m", "L: shortest line"},
      {"split_threshold_m", &X::split_threshold_m, 0.001, 1, "m", "T (IEPF split and merge)"},
      {"max_fit_rms_m", &X::max_fit_rms_m, 0.0001, 1, "m", "delta: orthogonal fit residual (RMS)"},
      {"hough_rho_window_m", &X::hough_rho_window_m, 0.001, 1, "m", "constrained Hough: +- this in rho ..."},
      {"hough_rho_res_m", &X::hough_rho_res_m, 0.0001, 0.5, "m", "... at this resolution"},
      {"hough_theta_window_rad", &X::hough_theta_window_rad, 0.001, 1, "rad", "+- this in theta ..."},
      {"hough_theta_res_rad", &X::hough_theta_res_rad, 0.0001, 0.5, "rad", "... at this resolution"},
      {"weight_length", &X::weight_length, 0, 1e6, "m", "eq. (8) weight wl (irslam-weights computes them)"},
      {"weight_rho", &X::weight_rho, 0, 1e9, "1/m^2", "eq. (8) weight wrho"},
      {"weight_theta", &X::weight_theta, 0, 1e9, "1/rad^2", "eq. (8) weight wtheta"},
      {"max_uncertainty", &X::max_uncertainty, 0, 1e9, "", "lines with U (eq. 8) above this are dropped"},
  };
  return kKeys;
}

}  // namespace irslam::slam
