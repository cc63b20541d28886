#include "tests/tools/clean_eval.h"

#include <cmath>

#include "daemon/core_json.h"
#include "sim/bounce.h"
#include "sim/sim_run.h"
#include "tests/tools/metrics.h"

namespace irslam::metrics {
namespace {

std::vector<TimedPose> Poses(const nlohmann::json& arr) {
  std::vector<TimedPose> out;
  for (const auto& p : arr) out.push_back({p[0], {p[1], p[2], p[3]}});
  return out;
}

std::vector<TimedPose> Between(const std::vector<TimedPose>& v, double t0, double t1) {
  std::vector<TimedPose> out;
  for (const auto& p : v)
    if (p.t >= t0 && p.t <= t1) out.push_back(p);
  return out;
}

}  // namespace

CleanScore RunAndScoreClean(const sim::World& world, const robot::CoreOptions& base, uint64_t seed,
                            double max_time_s, bool with_bounce) {
  robot::CoreOptions options = base;
  options.mission.mode = "clean";
  CleanScore s;
  s.world = world.name;
  s.seed = seed;
  sim::InProcessRun run = sim::RunInProcess(world, options, seed, max_time_s);
  s.end_state = control::ToString(run.core->state());
  const nlohmann::json status = ToJson(run.core->Status(run.t));
  s.reason = status.value("reason", "");
  const nlohmann::json truth = run.sim->Truth();
  const auto true_traj = Poses(truth["trajectory"]);
  if (!true_traj.empty()) {
    s.home_error_m = std::hypot(true_traj.back().pose.x - world.start.x, true_traj.back().pose.y - world.start.y);
  }
  if (!status.contains("cleaning")) return s;
  const auto& cl = status["cleaning"];
  const double t0 = cl["started_t"].get<double>();
  // Cleaning ends where going home begins (swept_t); finished_t is home.
  const double t_end = cl["swept_t"].is_number() ? cl["swept_t"].get<double>() : run.t;
  s.cleaned = s.end_state == "done";
  s.explore_s = t0;
  s.estimated_fraction = cl["fraction"];
  s.path_m = cl["path_m"];
  s.unreachable_m2 = cl["unreachable_m2"];
  s.cells = cl["cells_total"];
  s.cells_done = cl["cells_done"];
  s.cross_track_rms_m = cl["cross_track_rms_m"];
  const double radius = options.slam.geometry.radius_m;
  const CoverageScore cov = ScoreCoverage(world, radius, true_traj, t0, t_end, 0.02, &s.curve);
  s.clean_s = t_end - t0;
  s.reachable_m2 = cov.reachable_m2;
  s.covered_m2 = cov.covered_m2;
  s.coverage = cov.fraction;
  s.covered_total = ScoreCoverage(world, radius, true_traj, 0, t_end).fraction;
  s.path_ratio = s.reachable_m2 > 0 ? s.path_m / (s.reachable_m2 / options.mission.cleaning.cleaning_width_m) : 0;
  for (const auto& c : run.sim->collision_points()) {
    if (c[0] < t0) continue;
    ++s.contacts_cleaning;
    s.contacts_clutter += ContactWithClutter(world, c[1], c[2]);
  }
  const auto est = ToWorld(run.core->slam().trajectory(), world.start);
  s.rms_position_m = ComparePoses(Between(est, t0, t_end), Between(true_traj, t0, t_end)).rms_position_m;
  if (with_bounce && s.clean_s > 0) {
    const auto bounce = sim::RunBounce(world, options, seed, s.clean_s);
    const auto btraj = Poses(bounce->Truth()["trajectory"]);
    s.bounce_coverage = ScoreCoverage(world, radius, btraj, 0, s.clean_s, 0.02, &s.bounce_curve).fraction;
  }
  return s;
}

}  // namespace irslam::metrics
