#include "tests/tools/reloc_picture.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <utility>

#include "sim/sim_run.h"
#include "tests/tools/reloc_eval.h"

namespace irslam::metrics {
namespace {

Pose2 Inverse(const Pose2& p) {
  const double c = std::cos(p.theta), s = std::sin(p.theta);
  return {-(c * p.x + s * p.y), s * p.x - c * p.y, -p.theta};
}

// One run from start in the saved map; the last moment before the commit with
// >= 2 hypotheses.
HypothesisSnapshot RunOne(const sim::World& base, const robot::CoreOptions& options,
                          const robot::MapSnapshot& saved, const Pose2& start, uint64_t seed) {
  HypothesisSnapshot last;
  sim::World world = base;
  world.start = start;
  sim::RunSetup setup;
  setup.saved_map = saved;
  std::vector<TimedPose> truth;
  double evidence_seen = -1;
  const auto on_tick = [&](const sim::InProcessRun& run) {
    truth.push_back({run.t, run.sim->true_pose()});
    if (last.commit_t >= 0) return;
    const robot::CoreStatus st = run.core->Status(run.t);
    if (st.relocalize && st.relocalize->committed) {
      last.commit_t = st.relocalize->committed_t;
      return;
    }
    const slam::Relocalizer* r = run.core->relocalizer();
    if (r == nullptr || r->hypotheses().size() < 2 ||
        r->evidence_m() == evidence_seen) {
      return;
    }
    evidence_seen = r->evidence_m();
    last.t = run.t;
    last.hypotheses = r->hypotheses();
    last.local_lines = run.core->slam().lines();
    last.local_trajectory = run.core->slam().trajectory();
    last.truth = truth;
    last.evidence_m = r->evidence_m();
  };
  setup.stop_when = [&](const sim::InProcessRun& run) { return last.commit_t >= 0 && run.t > last.commit_t + 1; };
  sim::RunInProcess(world, options, seed, 200, on_tick, nullptr, nullptr, setup);
  return last;
}

std::string Num(double v, int prec) {
  char b[32];
  std::snprintf(b, sizeof b, "%.*f", prec, v);
  return b;
}

// Map metres to SVG pixels (y up on the page).
struct View {
  double x0, y0, scale, height;
  std::string X(double x) const { return Num((x - x0) * scale + 20, 1); }
  std::string Y(double y) const { return Num(height - ((y - y0) * scale + 20), 1); }
  std::string P(double x, double y) const { return X(x) + "," + Y(y); }
};

}  // namespace

RelocPicture CaptureHypotheses(const sim::World& world, const robot::CoreOptions& options, uint64_t seed,
                               int tries) {
  RelocPicture pic;
  pic.world = world.name;
  robot::CoreOptions explore = options;
  explore.mission.mode = "explore";
  const sim::InProcessRun first = sim::RunInProcess(world, explore, seed, 900);
  const robot::MapSnapshot saved = first.core->Map();
  pic.saved_lines = saved.lines;
  pic.map_to_world = MapToWorldFit(saved.trajectory, Poses(first.sim->Truth()["trajectory"]));
  const double clearance = options.slam.geometry.radius_m + 0.1;
  const std::vector<Pose2> starts = RandomFreeStarts(world, tries, clearance, seed * 7919 + 13);
  for (size_t i = 0; i < starts.size(); ++i) {
    HypothesisSnapshot s = RunOne(world, explore, saved, starts[i], seed + 1 + i);
    if (s.t >= 0 && s.commit_t >= 0) {
      pic.seed = seed + 1 + i;
      pic.start = starts[i];
      pic.snapshot = std::move(s);
      return pic;
    }
  }
  return pic;
}

std::string HypothesesSvg(const RelocPicture& p, int max_shown) {
  static const char* kColors[] = {"#d62728", "#1f77b4", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b"};
  const HypothesisSnapshot& s = p.snapshot;
  const Pose2 world_to_map = Inverse(p.map_to_world);
  // Bounds: the saved lines, and every hypothesis' placement.
  double lo_x = std::numeric_limits<double>::max(), lo_y = lo_x, hi_x = -lo_x, hi_y = -lo_x;
  const auto grow = [&](double x, double y) {
    lo_x = std::min(lo_x, x), lo_y = std::min(lo_y, y), hi_x = std::max(hi_x, x), hi_y = std::max(hi_y, y);
  };
  for (const auto& l : p.saved_lines) grow(l.p0.x(), l.p0.y()), grow(l.p1.x(), l.p1.y());
  const int shown = std::min<int>(max_shown, static_cast<int>(s.hypotheses.size()));
  for (int h = 0; h < shown; ++h) {
    for (const auto& tp : s.local_trajectory) {
      const auto [x, y] = ToParent(s.hypotheses[static_cast<size_t>(h)].local_to_map, tp.pose.x, tp.pose.y);
      grow(x, y);
    }
  }
  lo_x -= 0.3, lo_y -= 0.3, hi_x += 0.3, hi_y += 0.3;
  const double scale = 560.0 / std::max(hi_x - lo_x, hi_y - lo_y);
  const double w = std::max((hi_x - lo_x) * scale + 40, 900.0), plot_h = (hi_y - lo_y) * scale + 40;
  const double legend_h = 22.0 * (shown + 3);
  const View v{lo_x, lo_y, scale, plot_h};
  std::ostringstream o;
  o << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << Num(w, 0) << "\" height=\"" << Num(plot_h + legend_h, 0)
    << "\" font-family=\"sans-serif\" font-size=\"13\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";
  for (const auto& l : p.saved_lines) {
    o << "<polyline points=\"" << v.P(l.p0.x(), l.p0.y()) << " " << v.P(l.p1.x(), l.p1.y())
      << "\" stroke=\"#999\" stroke-width=\"5\" stroke-linecap=\"round\" fill=\"none\"/>\n";
  }
  // The hypotheses, worst first so the best is drawn on top.
  for (int h = shown - 1; h >= 0; --h) {
    const auto& hy = s.hypotheses[static_cast<size_t>(h)];
    const char* c = kColors[h % 6];
    o << "<g stroke=\"" << c << "\" fill=\"none\" opacity=\"" << (h == 0 ? "1" : "0.75") << "\">\n";
    o << "<polyline stroke-dasharray=\"4,3\" stroke-width=\"1.2\" points=\"";
    for (const auto& tp : s.local_trajectory) {
      const auto [x, y] = ToParent(hy.local_to_map, tp.pose.x, tp.pose.y);
      o << v.P(x, y) << " ";
    }
    o << "\"/>\n";
    for (const auto& l : s.local_lines) {
      const auto [ax, ay] = ToParent(hy.local_to_map, l.p0.x(), l.p0.y());
      const auto [bx, by] = ToParent(hy.local_to_map, l.p1.x(), l.p1.y());
      o << "<polyline stroke-width=\"2.2\" points=\"" << v.P(ax, ay) << " " << v.P(bx, by) << "\"/>\n";
    }
    if (!s.local_trajectory.empty()) {
      const Pose2 now = Compose(hy.local_to_map, s.local_trajectory.back().pose);
      const auto [tx, ty] = ToParent(now, 0.25, 0);
      o << "<circle cx=\"" << v.X(now.x) << "\" cy=\"" << v.Y(now.y) << "\" r=\"5\" fill=\"" << c << "\"/>\n";
      o << "<polyline stroke-width=\"2\" points=\"" << v.P(now.x, now.y) << " " << v.P(tx, ty) << "\"/>\n";
      o << "<text x=\"" << v.X(now.x) << "\" y=\"" << v.Y(now.y) << "\" dx=\"8\" dy=\"-8\" fill=\"" << c
        << "\" stroke=\"none\">#" << h + 1 << "</text>\n";
    }
    o << "</g>\n";
  }
  // The truth, in the saved map's frame.
  o << "<polyline fill=\"none\" stroke=\"black\" stroke-width=\"1\" points=\"";
  for (const auto& tp : s.truth) {
    const auto [x, y] = ToParent(world_to_map, tp.pose.x, tp.pose.y);
    o << v.P(x, y) << " ";
  }
  o << "\"/>\n";
  // Legend.
  double y = plot_h + 16;
  o << "<text x=\"20\" y=\"" << Num(y, 0) << "\">" << p.world << ", start " << Num(p.start.x, 2) << ", "
    << Num(p.start.y, 2) << ", " << Num(p.start.theta * 180 / M_PI, 0) << " deg (seed " << p.seed << "): the search at "
    << Num(s.t, 1) << " s, " << Num(s.evidence_m, 1) << " m of evidence, " << s.hypotheses.size()
    << " hypotheses; committed at " << Num(s.commit_t, 1) << " s</text>\n";
  y += 22;
  o << "<text x=\"20\" y=\"" << Num(y, 0) << "\" fill=\"#777\">grey: the saved map's lines; black: the true path so "
       "far; each colour: the lines and path seen so far placed by one hypothesis</text>\n";
  for (int h = 0; h < shown; ++h) {
    const auto& hy = s.hypotheses[static_cast<size_t>(h)];
    y += 22;
    o << "<text x=\"20\" y=\"" << Num(y, 0) << "\" fill=\"" << kColors[h % 6] << "\">#" << h + 1 << ": score "
      << Num(hy.score, 2) << " (explained " << Num(hy.explained_m, 2) << " m, conflicting " << Num(hy.conflict_m, 2)
      << " m; on walls " << Num(hy.anchored_m[0], 1) << " / " << Num(hy.anchored_m[1], 1) << " m per axis)"
      << (h == 0 ? " — best" : "") << "</text>\n";
  }
  o << "</svg>\n";
  return o.str();
}

}  // namespace irslam::metrics
