// The relocaliser (the method: slam/relocalizer.h) and its option table.
// Longer than the ~400-line bar (issue 10) on purpose: apart from the key
// table (~40 lines) it is one algorithm over two private value types, the
// saved map in its axis frame (SavedMap, AxisSegment) and the local evidence
// (LocalEvidence, LocalLine): preparing both, placing, voting (BestOffsets),
// scoring (Explained, Score), refining (Refine) and keeping distinct
// hypotheses, in the order of the header's method description. Every step
// reads those same types, which are private to this file; split across files
// they would need a private header shared by parts with no interface of their
// own between them.
#include "slam/relocalizer.h"

#include <Eigen/Cholesky>
#include <algorithm>
#include <cmath>
#include <utility>

namespace irslam::slam {

namespace {

constexpr double kSampleStepM = 0.1;  // local lines are checked against free space at this step
constexpr double kEndSlackM = 0.1;    // saved end points are this uncertain (overlap, crossing)
constexpr double kPathStepM = 0.1;    // local trajectory decimation ...
constexpr size_t kMaxPathPoints = 200;  // ... and its bound

using Vec2 = Eigen::Vector2d;

int Sign(double v) { return v > 0 ? 1 : (v < 0 ? -1 : 0); }
bool SidesAgree(int a, int b) { return a == 0 || b == 0 || a == b; }

Vec2 Transform(const Pose2& t, const Vec2& p) {
  const auto [x, y] = ToParent(t, p.x(), p.y());
  return {x, y};
}

// A pose as a rotation and a translation, for transforming many points (ToParent's arithmetic).
struct Rigid {
  explicit Rigid(const Pose2& t) : c(std::cos(t.theta)), s(std::sin(t.theta)), x(t.x), y(t.y) {}
  Vec2 Rotate(const Vec2& p) const { return {c * p.x() - s * p.y(), s * p.x() + c * p.y()}; }
  Vec2 operator()(const Vec2& p) const { return Rotate(p) + Vec2(x, y); }
  double c, s, x, y;
};

// Length-weighted direction of a Manhattan line set, modulo pi/2, in
// (-pi/4, pi/4]: the circular mean of 4 * theta.
double AxisAngle(const std::vector<std::pair<double, double>>& theta_length) {
  double s = 0, c = 0;
  for (const auto& [theta, length] : theta_length) {
    s += length * std::sin(4 * theta);
    c += length * std::cos(4 * theta);
  }
  return (s == 0 && c == 0) ? 0.0 : std::atan2(s, c) / 4;
}

// A segment's direction class in a frame whose axes are the map's: 0 along x
// (its offset is y), 1 along y (its offset is x), -1 neither within tolerance.
int Direction(const Vec2& a, const Vec2& b, double tolerance_rad) {
  const Vec2 d = b - a;
  const double n = d.norm();
  if (n <= 0) return -1;
  const double sin_tol = std::sin(tolerance_rad);
  if (std::abs(d.y()) <= sin_tol * n) return 0;
  if (std::abs(d.x()) <= sin_tol * n) return 1;
  return -1;
}

}  // namespace

namespace internal {

// A line along a map axis: dir 0 along x (offset is its y), 1 along y;
// [lo, hi] along the line; side: sign of (robot - offset) along the offset
// axis, 0 when not known.
struct AxisSegment {
  int dir = -1;
  double offset = 0;
  double lo = 0;
  double hi = 0;
  int side = 0;
  double length() const { return hi - lo; }
};

// The saved map in its axis frame (the map frame turned by -axis_rad so its
// lines lie along x and y).
struct SavedMap {
  double axis_rad = 0;
  std::vector<AxisSegment> segments;
  double min[2] = {0, 0};
  double max[2] = {0, 0};
};

}  // namespace internal

namespace {

using internal::AxisSegment;
using internal::SavedMap;

// The side of segment a-b (towards its unit normal n: +1) the trajectory
// points near it passed on (nearer points weigh more); 0 when none passed it.
int TrajectorySide(const Vec2& a, const Vec2& b, const Vec2& n, const std::vector<Vec2>& path, double range_m) {
  const double length = (b - a).norm();
  if (length <= 0) return 0;
  const Vec2 d = (b - a) / length;
  double vote = 0;
  for (const Vec2& p : path) {
    const double along = d.dot(p - a);
    if (along < -0.2 || along > length + 0.2) continue;
    const double off = n.dot(p - a);
    if (std::abs(off) > range_m) continue;
    vote += Sign(off) / (0.05 + std::abs(off));
  }
  return Sign(vote);
}

SavedMap PrepareSaved(const RelocalizeOptions& options, const std::vector<LineFeature>& lines,
                      const std::vector<TimedPose>& trajectory) {
  SavedMap saved;
  std::vector<std::pair<double, double>> theta_length;
  for (const LineFeature& l : lines) theta_length.emplace_back(l.theta, l.length());
  saved.axis_rad = AxisAngle(theta_length);
  const Pose2 to_axis{0, 0, -saved.axis_rad};
  std::vector<Vec2> path;
  path.reserve(trajectory.size());
  for (const TimedPose& p : trajectory) path.push_back(Transform(to_axis, {p.pose.x, p.pose.y}));
  bool first = true;
  for (const LineFeature& l : lines) {
    const Vec2 a = Transform(to_axis, l.p0), b = Transform(to_axis, l.p1);
    for (const Vec2& p : {a, b}) {
      for (int k = 0; k < 2; ++k) {
        saved.min[k] = first ? p[k] : std::min(saved.min[k], p[k]);
        saved.max[k] = first ? p[k] : std::max(saved.max[k], p[k]);
      }
      first = false;
    }
    AxisSegment s;
    s.dir = Direction(a, b, options.angle_tolerance_rad);
    if (s.dir < 0) continue;  // not a Manhattan line: the EKF does not map those
    const int k = 1 - s.dir;
    s.offset = (a[k] + b[k]) / 2;
    s.lo = std::min(a[s.dir], b[s.dir]);
    s.hi = std::max(a[s.dir], b[s.dir]);
    s.side = TrajectorySide(a, b, s.dir == 0 ? Vec2(0, 1) : Vec2(1, 0), path, options.side_range_m);
    saved.segments.push_back(s);
  }
  return saved;
}

// A local line between its end points projected onto its (rho, theta) line,
// and the side of it the local trajectory passed on, relative to its normal.
struct LocalLine {
  Vec2 a, b;
  Vec2 normal;
  int side = 0;
  double length = 0;
};

struct LocalEvidence {
  std::vector<LocalLine> lines;
  std::vector<Vec2> path;  // decimated, at most kMaxPathPoints
  double axis_rad = 0;     // local axis direction modulo pi/2
  double evidence_m = 0;
  std::array<double, 2> by_direction_m{};
};

std::vector<Vec2> DecimatePath(const std::vector<TimedPose>& trajectory) {
  std::vector<Vec2> path;
  for (const TimedPose& p : trajectory) {
    const Vec2 q(p.pose.x, p.pose.y);
    if (path.empty() || (q - path.back()).norm() >= kPathStepM) path.push_back(q);
  }
  if (!trajectory.empty()) {
    const Vec2 last(trajectory.back().pose.x, trajectory.back().pose.y);
    if (path.back() != last) path.push_back(last);
  }
  if (path.size() > kMaxPathPoints) {
    std::vector<Vec2> kept;
    kept.reserve(kMaxPathPoints);
    for (size_t i = 0; i < kMaxPathPoints; ++i) {
      kept.push_back(path[i * (path.size() - 1) / (kMaxPathPoints - 1)]);
    }
    path = std::move(kept);
  }
  return path;
}

LocalEvidence PrepareLocal(const RelocalizeOptions& options, const std::vector<LineFeature>& lines,
                           const std::vector<TimedPose>& trajectory) {
  LocalEvidence local;
  local.path = DecimatePath(trajectory);
  std::vector<std::pair<double, double>> theta_length;
  for (const LineFeature& l : lines) {
    if (l.length() >= options.min_line_m) theta_length.emplace_back(l.theta, l.length());
  }
  local.axis_rad = AxisAngle(theta_length);
  const Pose2 to_axis{0, 0, -local.axis_rad};
  for (const LineFeature& l : lines) {
    if (l.length() < options.min_line_m) continue;
    const Vec2 n(std::cos(l.theta), std::sin(l.theta));
    LocalLine line;
    line.normal = n;
    line.a = l.p0 - (n.dot(l.p0) - l.rho) * n;
    line.b = l.p1 - (n.dot(l.p1) - l.rho) * n;
    line.length = (line.b - line.a).norm();
    const int dir = Direction(Transform(to_axis, line.a), Transform(to_axis, line.b),
                              options.angle_tolerance_rad);
    if (dir < 0 || line.length < options.min_line_m) continue;  // not Manhattan in its own frame
    line.side = TrajectorySide(line.a, line.b, n, local.path, options.side_range_m);
    local.evidence_m += line.length;
    local.by_direction_m[dir] += line.length;
    local.lines.push_back(line);
  }
  return local;
}

// A local line in the saved map's axis frame under a hypothesis.
struct PlacedLine {
  Vec2 a, b;
  AxisSegment seg;  // dir -1: not along an axis under this hypothesis
};

PlacedLine Place(const RelocalizeOptions& options, const Rigid& t, const LocalLine& l) {
  PlacedLine p;
  p.a = t(l.a);
  p.b = t(l.b);
  AxisSegment& s = p.seg;
  s.dir = Direction(p.a, p.b, options.angle_tolerance_rad);
  if (s.dir < 0) return p;
  const int k = 1 - s.dir;
  s.offset = (p.a[k] + p.b[k]) / 2;
  s.lo = std::min(p.a[s.dir], p.b[s.dir]);
  s.hi = std::max(p.a[s.dir], p.b[s.dir]);
  s.side = l.side * Sign(t.Rotate(l.normal)[k]);
  return p;
}

// The intervals (along the line) of a placed local line lying on saved lines,
// merged; returns their total length.
double Explained(const RelocalizeOptions& options, const SavedMap& saved, const AxisSegment& s,
                 std::vector<std::pair<double, double>>* intervals, double min_saved_m = 0) {
  intervals->clear();
  if (s.dir < 0) return 0;
  for (const AxisSegment& m : saved.segments) {
    if (m.dir != s.dir || std::abs(m.offset - s.offset) > options.line_tolerance_m) continue;
    if (m.hi - m.lo < min_saved_m) continue;
    if (!SidesAgree(m.side, s.side)) continue;
    const double lo = std::max(s.lo, m.lo - kEndSlackM), hi = std::min(s.hi, m.hi + kEndSlackM);
    if (hi > lo) intervals->emplace_back(lo, hi);
  }
  std::sort(intervals->begin(), intervals->end());
  double total = 0;
  size_t out = 0;
  for (const auto& iv : *intervals) {
    if (out > 0 && iv.first <= (*intervals)[out - 1].second) {
      (*intervals)[out - 1].second = std::max((*intervals)[out - 1].second, iv.second);
    } else {
      (*intervals)[out++] = iv;
    }
  }
  intervals->resize(out);
  for (const auto& iv : *intervals) total += iv.second - iv.first;
  return total;
}

double DistanceSquared(const AxisSegment& m, const Vec2& p) {
  const double along = p[m.dir];
  const double da = std::max({m.lo - along, 0.0, along - m.hi});
  const double dp = p[1 - m.dir] - m.offset;
  return da * da + dp * dp;
}

bool Inside(const SavedMap& saved, const Vec2& p, double margin) {
  return p.x() >= saved.min[0] - margin && p.x() <= saved.max[0] + margin &&
         p.y() >= saved.min[1] - margin && p.y() <= saved.max[1] + margin;
}

double ExplainedOnly(const RelocalizeOptions& options, const SavedMap& saved,
                     const LocalEvidence& local, const Pose2& t,
                     std::vector<std::pair<double, double>>* scratch) {
  double explained = 0;
  const Rigid rigid(t);
  for (const LocalLine& l : local.lines)
    explained += Explained(options, saved, Place(options, rigid, l).seg, scratch);
  return explained;
}

// t: local frame -> saved axis frame.
PoseHypothesis Score(const RelocalizeOptions& options, const SavedMap& saved,
                     const LocalEvidence& local, const Pose2& t) {
  PoseHypothesis h;
  h.local_to_map = Compose(Pose2{0, 0, saved.axis_rad}, t);
  if (local.evidence_m <= 0) return h;
  std::vector<std::pair<double, double>> intervals;
  const Rigid rigid(t);
  const double margin2 = options.free_margin_m * options.free_margin_m;
  for (const LocalLine& l : local.lines) {
    const PlacedLine p = Place(options, rigid, l);
    if (p.seg.dir >= 0) {
      // On saved lines long enough to be walls (furniture moves, walls do not).
      h.anchored_m[static_cast<size_t>(p.seg.dir)] +=
          Explained(options, saved, p.seg, &intervals, options.anchor_line_m);
    }
    h.explained_m += Explained(options, saved, p.seg, &intervals);
    // The unexplained rest: a conflict where it lies in the saved free space.
    const int n = std::max(1, static_cast<int>(std::ceil(l.length / kSampleStepM)));
    const double w = l.length / n;
    for (int i = 0; i < n; ++i) {
      const Vec2 q = p.a + (p.b - p.a) * ((i + 0.5) / n);
      if (p.seg.dir >= 0) {
        const double along = q[p.seg.dir];
        const bool on = std::any_of(intervals.begin(), intervals.end(), [&](const auto& iv) {
          return along >= iv.first && along <= iv.second;
        });
        if (on) continue;
      }
      if (!Inside(saved, q, 0)) continue;
      const bool near =
          std::any_of(saved.segments.begin(), saved.segments.end(),
                      [&](const AxisSegment& m) { return DistanceSquared(m, q) <= margin2; });
      if (!near) h.conflict_m += w;
    }
  }
  // The local trajectory through a saved line, or out of the saved room.
  Vec2 prev = Vec2::Zero();
  for (size_t i = 0; i < local.path.size(); ++i) {
    const Vec2 q = rigid(local.path[i]);
    if (i > 0) {
      if (!Inside(saved, q, options.free_margin_m)) h.conflict_m += (q - prev).norm();
      for (const AxisSegment& m : saved.segments) {
        const int k = 1 - m.dir;
        const double u = prev[k] - m.offset, v = q[k] - m.offset;
        if (!(u * v < 0)) continue;
        const double along = prev[m.dir] + (q[m.dir] - prev[m.dir]) * (u / (u - v));
        if (along > m.lo + kEndSlackM && along < m.hi - kEndSlackM)
          h.conflict_m += m.length() >= options.anchor_line_m ? options.crossing_conflict_m
                                                               : options.short_crossing_conflict_m;
      }
    }
    prev = q;
  }
  h.score = (h.explained_m - h.conflict_m) / local.evidence_m;
  return h;
}

struct Vote {
  double offset;
  double weight;
};

// The best `count` offsets of a 1-D vote: the heaviest window of width
// 2 * tolerance, its weighted mean, votes within 2 * tolerance removed, again.
std::vector<double> BestOffsets(std::vector<Vote> votes, double tolerance, int count) {
  std::sort(votes.begin(), votes.end(),
            [](const Vote& a, const Vote& b) { return a.offset < b.offset; });
  std::vector<double> out;
  const size_t n = votes.size();
  while (static_cast<int>(out.size()) < count) {
    double best = 0;
    size_t best_i = n;
    double window = 0;
    size_t lo = 0, hi = 0;
    for (size_t i = 0; i < n; ++i) {
      while (hi < n && votes[hi].offset <= votes[i].offset + tolerance)
        window += votes[hi++].weight;
      while (votes[lo].offset < votes[i].offset - tolerance) window -= votes[lo++].weight;
      if (votes[i].weight > 0 && window > best) {
        best = window;
        best_i = i;
      }
    }
    if (best_i == n) break;
    double sum = 0, sum_w = 0;
    for (size_t j = 0; j < n; ++j) {
      if (std::abs(votes[j].offset - votes[best_i].offset) <= tolerance) {
        sum += votes[j].weight * votes[j].offset;
        sum_w += votes[j].weight;
      }
    }
    const double center = sum / sum_w;
    out.push_back(center);
    for (Vote& v : votes) {
      if (std::abs(v.offset - center) <= 2 * tolerance) v.weight = 0;
    }
  }
  return out;
}

// Least-squares refinement of t (Gauss-Newton, a few steps): the end points
// of each placed local line onto the saved line it overlaps most (same
// direction and side, within line_tolerance_m), weighted by length. The vote
// gives the offsets only to the cluster's width and the rotation comes from
// the axis estimates alone; this uses all matched lines at once.
Pose2 Refine(const RelocalizeOptions& options, const SavedMap& saved, const LocalEvidence& local,
             Pose2 t) {
  for (int iteration = 0; iteration < 3; ++iteration) {
    Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    int matched_dirs[2] = {0, 0};
    const Rigid rigid(t);
    for (const LocalLine& l : local.lines) {
      const AxisSegment s = Place(options, rigid, l).seg;
      if (s.dir < 0) continue;
      const AxisSegment* best = nullptr;
      double best_overlap = 0;
      for (const AxisSegment& m : saved.segments) {
        if (m.dir != s.dir || std::abs(m.offset - s.offset) > options.line_tolerance_m) continue;
        if (!SidesAgree(m.side, s.side)) continue;
        const double overlap =
            std::min(s.hi, m.hi + kEndSlackM) - std::max(s.lo, m.lo - kEndSlackM);
        if (overlap > best_overlap) {
          best_overlap = overlap;
          best = &m;
        }
      }
      if (best == nullptr) continue;
      ++matched_dirs[s.dir];
      const int k = 1 - s.dir;
      for (const Vec2& p : {l.a, l.b}) {
        const Vec2 rotated = rigid.Rotate(p);
        const Vec2 q = rotated + Vec2(t.x, t.y);
        const Eigen::Vector3d j(k == 0 ? 1.0 : 0.0, k == 1 ? 1.0 : 0.0,
                                k == 0 ? -rotated.y() : rotated.x());
        const double w = best_overlap / 2;
        a += w * j * j.transpose();
        b += w * j * (q[k] - best->offset);
      }
    }
    // Both offsets and the rotation need lines of both directions.
    if (matched_dirs[0] == 0 || matched_dirs[1] == 0 || matched_dirs[0] + matched_dirs[1] < 3)
      return t;
    const Eigen::Vector3d delta = -a.ldlt().solve(b);
    if (!delta.allFinite() || std::abs(delta.z()) > options.angle_tolerance_rad) return t;
    t = {t.x + delta.x(), t.y + delta.y(), NormalizeAngle(t.theta + delta.z())};
  }
  return t;
}

bool SamePose(const RelocalizeOptions& options, const Pose2& a, const Pose2& b) {
  return std::hypot(a.x - b.x, a.y - b.y) < options.distinct_m &&
         std::abs(NormalizeAngle(a.theta - b.theta)) < options.distinct_rad;
}

// A translation candidate, before it is scored fully.
struct Candidate {
  Pose2 t;  // local -> saved axis frame
  double explained;
};

// The candidates for the local map turned by `rotation` onto the saved axes:
// the best offsets per coordinate from the line votes, combined.
void AddCandidates(const RelocalizeOptions& options, const SavedMap& saved,
                   const LocalEvidence& local, double rotation,
                   std::vector<std::pair<double, double>>* scratch,
                   std::vector<Candidate>* candidates) {
  const Rigid turn(Pose2{0, 0, rotation});
  std::vector<Vote> votes[2];   // [k]: offsets along coordinate k (from lines with dir 1 - k)
  std::vector<Vote> slides[2];  // [k]: end-to-end alignments along coordinate k (lines with dir k)
  Vec2 path_mean = Vec2::Zero();
  for (const Vec2& p : local.path) path_mean += turn(p) / static_cast<double>(local.path.size());
  for (const LocalLine& l : local.lines) {
    const AxisSegment s = Place(options, turn, l).seg;
    if (s.dir < 0) continue;
    for (const AxisSegment& m : saved.segments) {
      if (m.dir != s.dir || !SidesAgree(m.side, s.side)) continue;
      const double w = std::min(s.length(), m.length());
      votes[1 - s.dir].push_back({m.offset - s.offset, w});
      slides[s.dir].push_back({m.lo - s.lo, w});
      slides[s.dir].push_back({m.hi - s.hi, w});
    }
  }
  std::vector<double> offsets[2];
  for (int k = 0; k < 2; ++k) {
    offsets[k] =
        BestOffsets(std::move(votes[k]), options.line_tolerance_m, options.offsets_per_axis);
    // No line constrains this coordinate (lines of one direction only, never
    // committed): the local lines slid along the saved ones, ends aligned.
    if (offsets[k].empty()) {
      offsets[k] =
          BestOffsets(std::move(slides[k]), options.line_tolerance_m, options.offsets_per_axis);
    }
    if (offsets[k].empty()) offsets[k].push_back((saved.min[k] + saved.max[k]) / 2 - path_mean[k]);
  }
  for (double x : offsets[0]) {
    for (double y : offsets[1]) {
      const Pose2 t{x, y, rotation};
      candidates->push_back({t, ExplainedOnly(options, saved, local, t, scratch)});
    }
  }
}

// The best `count` distinct candidates by explained length.
std::vector<Pose2> BestDistinct(const RelocalizeOptions& options, std::vector<Candidate> candidates,
                                size_t count) {
  std::stable_sort(
      candidates.begin(), candidates.end(),
      [](const Candidate& a, const Candidate& b) { return a.explained > b.explained; });
  std::vector<Pose2> chosen;
  for (const Candidate& c : candidates) {
    if (chosen.size() >= count) break;
    if (std::none_of(chosen.begin(), chosen.end(),
                     [&](const Pose2& p) { return SamePose(options, p, c.t); })) {
      chosen.push_back(c.t);
    }
  }
  return chosen;
}

void SortByScore(std::vector<PoseHypothesis>* hypotheses) {
  std::stable_sort(
      hypotheses->begin(), hypotheses->end(),
      [](const PoseHypothesis& a, const PoseHypothesis& b) { return a.score > b.score; });
}

// The first `count` hypotheses (in their order) that are not the same pose as
// one before them.
std::vector<PoseHypothesis> Distinct(const RelocalizeOptions& options,
                                     const std::vector<PoseHypothesis>& hypotheses, size_t count) {
  std::vector<PoseHypothesis> distinct;
  for (const PoseHypothesis& h : hypotheses) {
    if (distinct.size() >= count) break;
    if (std::none_of(distinct.begin(), distinct.end(), [&](const PoseHypothesis& k) {
          return SamePose(options, k.local_to_map, h.local_to_map);
        })) {
      distinct.push_back(h);
    }
  }
  return distinct;
}

}  // namespace

options::Table<RelocalizeOptions> RelocalizeKeys() {
  using R = RelocalizeOptions;
  static constexpr options::Key<R> kKeys[] = {
      {"min_evidence_m", &R::min_evidence_m, 0, 1000, "m",
       "local line length needed before any commit"},
      {"min_line_m", &R::min_line_m, 0, 10, "m", "shorter local lines are not evidence"},
      {"side_range_m", &R::side_range_m, 0.1, 10, "m",
       "the side a line was seen from is voted by trajectory points at most this far from it"},
      {"line_tolerance_m", &R::line_tolerance_m, 0.005, 1, "m",
       "a local line lies on a saved one within this offset (also the vote cluster width)"},
      {"angle_tolerance_rad", &R::angle_tolerance_rad, 0.005, 0.78, "rad",
       "a line is along a map axis within this angle"},
      {"commit_score", &R::commit_score, 0, 1, "",
       "the committed hypothesis explains at least this fraction ..."},
      {"commit_margin", &R::commit_margin, 0, 2, "",
       "... and this much more than the runner-up ..."},
      {"anchor_line_m", &R::anchor_line_m, 0, 100, "m",
       "saved lines at least this long (walls) must pin the committed pose on each axis ..."},
      {"min_anchor_m", &R::min_anchor_m, 0, 100, "m", "... with at least this much evidence on them per axis"},
      {"margin_evidence_m", &R::margin_evidence_m, 0.1, 1000, "m",
       "... over at most this much evidence (then a fixed length: not diluted by a long walk)"},
      {"distinct_m", &R::distinct_m, 0.01, 10, "m",
       "hypotheses nearer than this (and distinct_rad) are one"},
      {"distinct_rad", &R::distinct_rad, 0.01, 3.2, "rad",
       "hypotheses turned less than this (and distinct_m) are one"},
      {"offsets_per_axis", &R::offsets_per_axis, 1, 64, "",
       "1-D translation candidates kept per axis and rotation"},
      {"max_hypotheses", &R::max_hypotheses, 1, 64, "", "hypotheses kept and reported, best first"},
      {"max_time_s", &R::max_time_s, 1, 86400, "s",
       "relocalising longer than this gives up (mission fault)"},
      {"min_direction_m", &R::min_direction_m, 0, 100, "m",
       "each of the two directions needs this much local evidence before a commit"},
      {"free_margin_m", &R::free_margin_m, 0.01, 5, "m",
       "saved free space (conflict): inside the saved map, farther than this from every saved "
       "line"},
      {"crossing_conflict_m", &R::crossing_conflict_m, 0, 100, "m",
       "conflict counted for each saved line the local trajectory crosses ..."},
      {"short_crossing_conflict_m", &R::short_crossing_conflict_m, 0, 100, "m",
       "... if it is shorter than anchor_line_m (a furniture side, which may have moved)"},
  };
  return kKeys;
}

PoseHypothesis ScoreHypothesis(const RelocalizeOptions& options, const Pose2& local_to_map,
                               const std::vector<LineFeature>& saved_lines,
                               const std::vector<TimedPose>& saved_trajectory,
                               const std::vector<LineFeature>& local_lines,
                               const std::vector<TimedPose>& local_trajectory) {
  const SavedMap saved = PrepareSaved(options, saved_lines, saved_trajectory);
  const LocalEvidence local = PrepareLocal(options, local_lines, local_trajectory);
  PoseHypothesis h =
      Score(options, saved, local, Compose(Pose2{0, 0, -saved.axis_rad}, local_to_map));
  h.local_to_map = local_to_map;
  return h;
}

Relocalizer::Relocalizer(RelocalizeOptions options, std::vector<LineFeature> saved_lines,
                         std::vector<TimedPose> saved_trajectory)
    : options_(options),
      saved_lines_(std::move(saved_lines)),
      saved_trajectory_(std::move(saved_trajectory)),
      saved_(std::make_shared<const SavedMap>(
          PrepareSaved(options_, saved_lines_, saved_trajectory_))) {}

bool Relocalizer::both_directions() const {
  return evidence_by_direction_m_[0] >= options_.min_direction_m &&
         evidence_by_direction_m_[1] >= options_.min_direction_m &&
         evidence_by_direction_m_[0] > 0 && evidence_by_direction_m_[1] > 0;
}

void Relocalizer::Update(const std::vector<LineFeature>& local_lines,
                         const std::vector<TimedPose>& local_trajectory) {
  const SavedMap& saved = *saved_;
  const LocalEvidence local = PrepareLocal(options_, local_lines, local_trajectory);
  evidence_m_ = local.evidence_m;
  evidence_by_direction_m_ = local.by_direction_m;
  hypotheses_.clear();
  if (local.lines.empty() || saved.segments.empty()) return;

  std::vector<Candidate> candidates;
  std::vector<std::pair<double, double>> scratch;
  for (int r = 0; r < 4; ++r) {
    AddCandidates(options_, saved, local, NormalizeAngle(-local.axis_rad + r * M_PI / 2), &scratch,
                  &candidates);
  }
  // The best distinct candidates by explained length are scored fully.
  const std::vector<Pose2> chosen = BestDistinct(options_, std::move(candidates),
                                                 3 * static_cast<size_t>(options_.max_hypotheses));
  std::vector<PoseHypothesis> scored;
  scored.reserve(chosen.size());
  for (const Pose2& t : chosen) scored.push_back(Score(options_, saved, local, t));
  SortByScore(&scored);
  hypotheses_ = Distinct(options_, scored, static_cast<size_t>(options_.max_hypotheses));
  // The kept ones refined (unless that lowers the score by more than a
  // rounding of the explained intervals), and those that met merged again.
  const Pose2 to_axis{0, 0, -saved.axis_rad};
  for (PoseHypothesis& h : hypotheses_) {
    const Pose2 refined = Refine(options_, saved, local, Compose(to_axis, h.local_to_map));
    const PoseHypothesis r = Score(options_, saved, local, refined);
    if (r.score >= h.score - 0.02) h = r;
  }
  SortByScore(&hypotheses_);
  hypotheses_ = Distinct(options_, hypotheses_, hypotheses_.size());
}

std::optional<PoseHypothesis> Relocalizer::Decision() const {
  if (hypotheses_.empty() || evidence_m_ < options_.min_evidence_m || !both_directions())
    return std::nullopt;
  const PoseHypothesis& best = hypotheses_[0];
  const double second = hypotheses_.size() > 1 ? hypotheses_[1].score : 0.0;
  // The runner-up beaten by a length: a fraction of the evidence up to margin_evidence_m.
  const double beats_m = (best.score - second) * evidence_m_;
  const double needed_m =
      options_.commit_margin * std::min(evidence_m_, options_.margin_evidence_m);
  if (best.score < options_.commit_score || beats_m < needed_m) return std::nullopt;
  // Both axes pinned by wall-length saved lines: a piece of furniture moved
  // since the map was made cannot shift the pose by its move.
  if (std::min(best.anchored_m[0], best.anchored_m[1]) < options_.min_anchor_m) return std::nullopt;
  return best;
}

}  // namespace irslam::slam
