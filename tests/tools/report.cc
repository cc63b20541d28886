// irslam-report: the accuracy report over the paper's scenarios (docs/accuracy.md
// and its SVG figures). Runs every world in process with several seeds.
//   irslam-report [--worlds DIR] [--seeds N] [--out DIR]
//   irslam-report --reloc N [--reloc-worlds fig14,fig16] [--out DIR]   (relocalization-results.md)
#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "daemon/core_json.h"
#include "robot/robot_core.h"
#include "daemon/config.h"
#include "sim/sim_run.h"
#include "tests/tools/campaign.h"
#include "tests/tools/clean_report.h"
#include "tests/tools/metrics.h"
#include "tests/tools/reloc_eval.h"
#include "tests/tools/reloc_picture.h"
#include "tests/tools/svg_chart.h"

namespace irslam::report {
namespace {

constexpr double kDeg = 180.0 / M_PI;

struct Run {
  bool done = false;
  double t = 0;
  uint64_t collisions = 0;
  metrics::PoseErrors slam, odom;
  double wall_dist_max = 0, wall_angle_max = 0;
  double line_dist_max = 0, line_angle_max = 0;
  double aligned_wall_dist_max = 0, aligned_wall_angle_max = 0;  // map shape, after BestAlignment
  int lines = 0, wall_lines = 0, unmatched = 0;
  std::vector<TimedPose> est, truth, odometry;
  std::vector<double> loop_times;
  // Covariance over time: (t, robot heading sigma), (t, mean line sigma theta), (t, mean line sigma rho)
  std::vector<std::pair<double, double>> pose_sigma, line_sigma_theta, line_sigma_rho;
};

// The control loop's work per period over a world's runs (issue 15): the worst
// run's quantiles, the largest period and the phase that took it, the slowest run.
struct TickRow {
  int runs = 0;
  double robot_s = 0;
  int64_t p99 = 0, p999 = 0, max = 0;
  std::string phase;
  double slowest_x = 0;  // robot time / wall time of the slowest run
};

void AddTicks(TickRow* row, const sim::InProcessRun& run) {
  const auto& w = run.profile.work();
  ++row->runs;
  row->robot_s += run.t;
  row->p99 = std::max(row->p99, w.Quantile(0.99));
  row->p999 = std::max(row->p999, w.Quantile(0.999));
  if (w.max() >= row->max) {
    row->max = w.max();
    row->phase = robot::ToString(run.profile.worst_phase());
  }
  const double x = run.wall_s > 0 ? run.t / run.wall_s : 0;
  if (row->runs == 1 || x < row->slowest_x) row->slowest_x = x;
}

std::vector<TimedPose> FromJson(const nlohmann::json& arr) {
  std::vector<TimedPose> out;
  for (const auto& p : arr) out.push_back({p[0], {p[1], p[2], p[3]}});
  return out;
}

Run RunOne(const sim::World& world, robot::CoreOptions o, uint64_t seed, double max_time) {
  Run r;
  double next_sample = 0;
  auto on_tick = [&](const sim::InProcessRun& run) {
    if (run.t < next_sample) return;
    next_sample = run.t + 0.5;
    const auto& ekf = run.core->slam().ekf();
    r.pose_sigma.emplace_back(run.t, std::sqrt(ekf.PoseCov()(2, 2)) * kDeg);
    if (ekf.num_lines() > 0) {
      double st = 0, sr = 0;
      for (int i = 0; i < ekf.num_lines(); ++i) {
        st += std::sqrt(std::max(0.0, ekf.LineCov(i)(1, 1)));
        sr += std::sqrt(std::max(0.0, ekf.LineCov(i)(0, 0)));
      }
      r.line_sigma_theta.emplace_back(run.t, st / ekf.num_lines() * kDeg);
      r.line_sigma_rho.emplace_back(run.t, sr / ekf.num_lines() * 100);
    }
  };
  sim::InProcessRun run = sim::RunInProcess(world, o, seed, max_time, on_tick);
  r.done = run.core->state() == control::MissionState::kDone;
  r.t = run.t;
  r.collisions = run.sim->collisions();
  const nlohmann::json truth = run.sim->Truth();
  r.truth = FromJson(truth["trajectory"]);
  r.odometry = FromJson(truth["odometry"]);
  r.est = metrics::ToWorld(run.core->slam().trajectory(), world.start);
  r.slam = metrics::ComparePoses(r.est, r.truth);
  r.odom = metrics::ComparePoses(r.odometry, r.truth);
  const auto lines = metrics::CompareLines(run.core->slam().lines(), world.start, world, &r.unmatched);
  r.lines = static_cast<int>(run.core->slam().num_lines());
  for (const auto& l : lines) {
    r.line_dist_max = std::max(r.line_dist_max, l.distance_m);
    r.line_angle_max = std::max(r.line_angle_max, l.angle_rad);
    if (!l.wall) continue;
    ++r.wall_lines;
    r.wall_dist_max = std::max(r.wall_dist_max, l.distance_m);
    r.wall_angle_max = std::max(r.wall_angle_max, l.angle_rad);
  }
  const Pose2 fixed = metrics::RoomFrameStart(run.core->slam().lines(), world);
  int unmatched_aligned;
  for (const auto& l : metrics::CompareLines(run.core->slam().lines(), fixed, world, &unmatched_aligned)) {
    if (!l.wall) continue;
    r.aligned_wall_dist_max = std::max(r.aligned_wall_dist_max, l.distance_m);
    r.aligned_wall_angle_max = std::max(r.aligned_wall_angle_max, l.angle_rad);
  }
  r.loop_times = run.core->loop_times();
  return r;
}

std::string F(double v, int prec = 1) {
  char b[32];
  std::snprintf(b, sizeof b, "%.*f", prec, v);
  return b;
}

bool Write(const std::string& path, const std::string& text) {
  std::ofstream out(path);
  out << text;
  return static_cast<bool>(out);
}

int RunCampaignReport(const robot::CoreOptions& options, const std::string& profiles, uint64_t first_seed,
                      int runs, int jobs, const std::string& out_dir, const std::string& noise_nominal) {
  std::vector<std::vector<campaign::RunScore>> by_profile;
  std::stringstream list(profiles);
  for (std::string name; std::getline(list, name, ',');) {
    const auto profile = sim::ParseNoiseProfile(name);
    if (!profile) {
      std::fprintf(stderr, "irslam-report: unknown profile '%s' (nominal, realistic, harsh)\n", name.c_str());
      return 2;
    }
    by_profile.push_back(campaign::RunCampaign(*profile, first_seed, runs, options, jobs, noise_nominal));
    campaign::RemeasureWorstPeriods(&by_profile.back(), options, 10, 2.0, noise_nominal);
    const campaign::Rates r = campaign::Summarise(by_profile.back());
    std::fprintf(stderr, "irslam-report: %s: %d runs, done %.1f %%, pieces good %.1f %%, complete %.1f %%, pose ok %.1f %%, lost %.1f %% (in the room's frame %.1f %%), contacts/run %.2f\n",
                 name.c_str(), r.runs, 100 * r.done, 100 * r.pieces_good, 100 * r.pieces_complete, 100 * r.pose_ok,
                 100 * r.lost, 100 * r.lost_in_room, r.furniture_contacts_per_run);
  }
  const std::string command = "irslam-report --campaign " + std::to_string(runs) + " --profiles " + profiles +
                              " --first-seed " + std::to_string(first_seed) +
                              (noise_nominal.empty() ? "" : " --noise-nominal " + noise_nominal);
  if (!Write(out_dir + "/robustness.md", campaign::RobustnessReport(by_profile, out_dir, command))) {
    std::fprintf(stderr, "irslam-report: cannot write %s/robustness.md\n", out_dir.c_str());
    return 1;
  }
  return 0;
}

// Issue 14: relocalisation in a saved map (tests/tools/reloc_eval.h); writes
// relocalization-results.md in out_dir.
int RunRelocReport(const robot::CoreOptions& options, const std::string& worlds_dir, const std::string& names,
                   int runs, uint64_t seed, double move_m, const std::string& out_dir) {
  metrics::RelocOptions ro;
  ro.runs = runs;
  ro.seed = seed;
  if (move_m > 0) {
    ro.move_m = move_m;
    ro.max_time_s = 1500;  // a whole cleaning
  }
  std::vector<metrics::RelocWorld> results;
  std::stringstream list(names);
  for (std::string name; std::getline(list, name, ',');) {
    std::string error;
    auto w = sim::LoadWorldFile(worlds_dir + "/" + name + ".json", &error);
    if (!w) {
      std::fprintf(stderr, "irslam-report: %s\n", error.c_str());
      return 2;
    }
    results.push_back(metrics::EvaluateRelocalization(*w, options, ro));
    int committed = 0;
    for (const auto& r : results.back().runs) committed += r.committed;
    std::fprintf(stderr, "irslam-report: %s: map %s (%d lines), %d/%zu runs committed\n", name.c_str(),
                 results.back().map_done ? "done" : "not done", results.back().map_lines, committed,
                 results.back().runs.size());
  }
  const std::string command = "irslam-report --reloc " + std::to_string(runs) + " --reloc-worlds " + names +
                              " --first-seed " + std::to_string(seed) +
                              (move_m > 0 ? " --reloc-move " + F(move_m, 2) : "");
  const std::string path = out_dir + (move_m > 0 ? "/relocalization-moved-results.md" : "/relocalization-results.md");
  if (!Write(path, metrics::RelocMarkdown(results, ro, command))) {
    std::fprintf(stderr, "irslam-report: cannot write %s\n", path.c_str());
    return 1;
  }
  std::fprintf(stderr, "irslam-report: wrote %s\n", path.c_str());
  return 0;
}

// Issue 14: one picture of the pose hypotheses (tests/tools/reloc_picture.h).
int RunRelocPicture(const robot::CoreOptions& options, const std::string& worlds_dir, const std::string& name,
                    uint64_t seed, const std::string& path) {
  std::string error;
  const auto w = sim::LoadWorldFile(worlds_dir + "/" + name + ".json", &error);
  if (!w) {
    std::fprintf(stderr, "irslam-report: %s\n", error.c_str());
    return 2;
  }
  const metrics::RelocPicture p = metrics::CaptureHypotheses(*w, options, seed);
  if (p.snapshot.t < 0) {
    std::fprintf(stderr, "irslam-report: %s: no run went through an ambiguous moment before committing\n",
                 name.c_str());
    return 1;
  }
  if (!Write(path, metrics::HypothesesSvg(p))) {
    std::fprintf(stderr, "irslam-report: cannot write %s\n", path.c_str());
    return 1;
  }
  std::fprintf(stderr, "irslam-report: wrote %s (%s seed %llu: %zu hypotheses at %.1f s, committed at %.1f s)\n",
               path.c_str(), name.c_str(), static_cast<unsigned long long>(p.seed), p.snapshot.hypotheses.size(),
               p.snapshot.t, p.snapshot.commit_t);
  return 0;
}

}  // namespace
}  // namespace irslam::report

int main(int argc, char** argv) {
  using namespace irslam;
  using namespace irslam::report;
  CLI::App app{"irslam-report: SLAM accuracy over the paper's scenarios"};
  std::string worlds_dir = std::string(IRSLAM_SOURCE_DIR) + "/tests/worlds";
  std::string out_dir = "docs";
  int seeds = 5;
  app.add_option("--worlds", worlds_dir, "Directory of world files");
  app.add_option("--out", out_dir, "Where accuracy.md and the figures go");
  app.add_option("--seeds", seeds, "Seeds per world")->check(CLI::Range(1, 100));
  std::string config_path;
  app.add_option("--config", config_path, "irslamd config file to evaluate (default: built-in defaults)");
  int campaign_runs = 0, jobs = 2;
  uint64_t first_seed = 1;
  std::string profiles = "nominal,realistic,harsh";
  app.add_option("--campaign", campaign_runs,
                 "Instead of the accuracy report: the robustness campaign over this many generated worlds per "
                 "profile (robustness.md in --out)")
      ->check(CLI::Range(1, 100000));
  app.add_option("--profiles", profiles, "Campaign noise profiles, comma-separated (nominal,realistic,harsh)");
  app.add_option("--first-seed", first_seed, "Campaign: the first world seed");
  app.add_option("--jobs", jobs, "Campaign: runs in parallel")->check(CLI::Range(1, 64));
  std::string mode = "explore";
  app.add_option("--mode", mode,
                 "clean: the cleaning report instead (cleaning-results.md, cleaning-coverage.svg in --out): the "
                 "paper worlds x --seeds, plus --campaign N generated worlds per profile; docs/cleaning.md")
      ->check(CLI::IsMember({"explore", "clean"}));
  int reloc_runs = 0;
  std::string reloc_worlds = "fig14,fig16,fig17,fig18,fig19,fig20,free_start,corner_start";
  app.add_option("--reloc", reloc_runs,
                 "Instead of the accuracy report: relocalisation in a saved map, this many runs from random start "
                 "poses per world (relocalization-results.md in --out; docs/relocalization.md)")
      ->check(CLI::Range(1, 1000));
  app.add_option("--reloc-worlds", reloc_worlds, "--reloc: the worlds (names in --worlds), comma-separated");
  double reloc_move = 0;
  app.add_option("--reloc-move", reloc_move,
                 "--reloc: move one piece of furniture by this much (m) before each run, which then cleans; "
                 "relocalization-moved-results.md in --out (docs/relocalization.md)")
      ->check(CLI::Range(0.0, 2.0));
  std::string reloc_picture;
  app.add_option("--reloc-picture", reloc_picture,
                 "Instead of the accuracy report: an SVG of relocalisation's pose hypotheses at their last "
                 "ambiguous moment, in the first of --reloc-worlds, from --first-seed (docs/relocalization.md)");
  std::string noise_nominal;
  app.add_option("--noise-nominal", noise_nominal,
                 "Campaign (explore or clean): set these world noise keys (comma-separated, contracts §1) back "
                 "to their nominal values in every generated world: what one effect of the error envelope costs "
                 "(docs/error-budget.md)");
  CLI11_PARSE(app, argc, argv);
  {
    sim::SimNoise check;
    std::string error;
    if (!metrics::SetNoiseNominal(noise_nominal, &check, &error)) {
      std::fprintf(stderr, "irslam-report: --noise-nominal: %s\n", error.c_str());
      return 2;
    }
  }
  robot::CoreOptions defaults = robot::DefaultCoreOptions();
  if (!config_path.empty()) {
    std::string error;
    if (!LoadCoreConfigFile(config_path, &defaults, &error)) {
      std::fprintf(stderr, "irslam-report: %s\n", error.c_str());
      return 2;
    }
  }
  // The reports go to out_dir, made now: not after a campaign of minutes that
  // then has nowhere to write.
  {
    std::error_code ec;
    std::filesystem::create_directories(out_dir, ec);
    if (ec) {
      std::fprintf(stderr, "irslam-report: --out %s: %s\n", out_dir.c_str(), ec.message().c_str());
      return 2;
    }
  }

  if (!reloc_picture.empty()) {
    return RunRelocPicture(defaults, worlds_dir, reloc_worlds.substr(0, reloc_worlds.find(',')), first_seed,
                           reloc_picture);
  }
  if (reloc_runs > 0) return RunRelocReport(defaults, worlds_dir, reloc_worlds, reloc_runs, first_seed, reloc_move, out_dir);
  if (mode == "clean") {
    return RunCleanReport(defaults, worlds_dir,
                          {"fig14", "fig16", "fig17", "fig18", "fig19", "fig20", "free_start", "corner_start"},
                          seeds, campaign_runs, profiles, first_seed, jobs, out_dir, noise_nominal);
  }
  if (campaign_runs > 0) return RunCampaignReport(defaults, profiles, first_seed, campaign_runs, jobs, out_dir,
                                                    noise_nominal);

  const auto load = [&](const std::string& name) {
    std::string error;
    auto w = sim::LoadWorldFile(worlds_dir + "/" + name + ".json", &error);
    if (!w) {
      std::fprintf(stderr, "irslam-report: %s\n", error.c_str());
      std::exit(2);
    }
    return *w;
  };
  std::ostringstream md;
  md << "# SLAM accuracy report\n\n"
     << "Generated by `irslam-report` (README: \"Accuracy report\") from the in-process mission "
        "(`irslam-sim run`: same frames and core as irslamd) on the world files in tests/worlds, "
     << seeds << " seeds each. Errors are against the simulator's ground truth; the estimate is put in the "
        "world frame through the true start pose, exactly like the odometry baseline (contracts §5). "
        "Position in cm, angles in degrees. *Line errors*: the mean distance of a mapped line's end points "
        "from the true wall/box side it lies along, and its angle error; *in start frame*: the map placed in the "
        "world through the true start pose (so the map's small overall rotation, fixed when the first walls were "
        "seen, counts too); *map shape*: after the rigid alignment (rotation about the start, then shift) that best "
        "fits the mapped lines to the true ones - the map frame is defined by the first wall, so this is the "
        "geometry of the map itself.\n\n";

  std::map<std::string, TickRow> tick_rows;  // the whole missions' periods, by world
  // ---- One loop of every scenario.
  md << "## One wall-following loop per scenario\n\n"
     << "| world | seed | done | robot time s | collisions | SLAM final pos | SLAM final hdg | SLAM RMS pos | "
        "SLAM RMS hdg | odometry final pos | odometry RMS pos | lines | wall lines | wall line max dist (start "
        "frame) | wall line max angle (start frame) | all lines max dist | unmatched | wall line max dist (map "
        "shape) | wall line max angle (map shape) |\n"
     << "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  std::map<std::string, std::vector<Run>> all;
  // The SLAM tables judge one wall-following loop (exploration is measured below).
  const robot::CoreOptions with_exploration = defaults;
  defaults.mission.explore = false;
  for (const std::string name : {"fig14", "fig16", "fig19", "fig20", "fig17"}) {
    const sim::World world = load(name);
    for (int s = 1; s <= seeds; ++s) {
      Run r = RunOne(world, defaults, static_cast<uint64_t>(s), 400);
      md << "| " << name << " | " << s << " | " << (r.done ? "yes" : "**no**") << " | " << F(r.t) << " | "
         << r.collisions << " | " << F(r.slam.final_position_m * 100) << " | "
         << F(r.slam.final_heading_rad * kDeg, 2) << " | " << F(r.slam.rms_position_m * 100) << " | "
         << F(r.slam.rms_heading_rad * kDeg, 2) << " | " << F(r.odom.final_position_m * 100) << " | "
         << F(r.odom.rms_position_m * 100) << " | " << r.lines << " | " << r.wall_lines << " | "
         << F(r.wall_dist_max * 100) << " | " << F(r.wall_angle_max * kDeg, 2) << " | "
         << F(r.line_dist_max * 100) << " | " << r.unmatched << " | " << F(r.aligned_wall_dist_max * 100)
         << " | " << F(r.aligned_wall_angle_max * kDeg, 2) << " |\n";
      all[name].push_back(std::move(r));
    }
  }
  // Targets for Fig. 14.
  bool pose_ok = true, shape_ok = true, start_ok = true;
  for (const auto& r : all["fig14"]) {
    pose_ok &= r.done && r.slam.final_position_m <= 0.05 && r.slam.final_heading_rad <= 2 / kDeg;
    shape_ok &= r.aligned_wall_dist_max <= 0.03 && r.aligned_wall_angle_max <= 1 / kDeg;
    start_ok &= r.wall_dist_max <= 0.03 && r.wall_angle_max <= 1 / kDeg;
  }
  md << "\nTargets after one loop of the Fig. 14 room, every seed: final position error <= 5 cm and heading "
        "<= 2 deg: **"
     << (pose_ok ? "met" : "NOT met") << "**; wall lines within 3 cm and 1 deg (map shape): **"
     << (shape_ok ? "met" : "NOT met") << "**; the same in the start frame: **" << (start_ok ? "met" : "not met")
     << "**.\n\n";

  // ---- Exploration: the whole mission, objects against the truth.
  {
    md << "## Environment modelling and exploration (whole mission)\n\n"
       << "The whole mission (wall following, modelling, go to P1, contour following, survey from the room "
          "centre) on each world. Objects are compared with the true furniture (boxes that touch are one "
          "compound piece; a piece touching a wall is wall-contact). Model boxes are put in the world frame "
          "through the start pose and the map-shape alignment. *found*: a model object overlaps the piece; "
          "*edge*: the largest error of the four box edges (cm) over found pieces; robot-time limit 900 s.\n\n"
       << "| world | seed | done | robot time s | collisions | pieces | found | kind right | complete | "
          "max edge error | mean IoU | extra objects |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for (const std::string name : {"fig14", "fig16", "fig19", "fig20"}) {
      const sim::World world = load(name);
      for (int s = 1; s <= seeds; ++s) {
        sim::InProcessRun run = sim::RunInProcess(world, with_exploration, static_cast<uint64_t>(s), 900, nullptr,
                                                  nullptr, metrics::ThreadCpuNs);
        AddTicks(&tick_rows[name], run);
        const metrics::ObjectScores sc = metrics::ScoreObjects(ToJson(run.core->Map()), run.core->slam(), world, 0);
        md << "| " << name << " | " << s << " | " << (run.core->state() == control::MissionState::kDone ? "yes" : "**no**")
           << " | " << F(run.t) << " | " << run.sim->collisions() << " | " << sc.pieces << " | " << sc.found
           << " | " << sc.kind_right << " | " << sc.complete << " | " << F(sc.max_edge_m * 100) << " | "
           << F(sc.mean_iou, 2) << " | " << sc.extra << " |\n";
      }
    }
    md << "\n";
    // The same over 20 seeds, and the robustness worlds (chair legs: only the
    // two pieces of furniture count; the legs are obstacles, not furniture).
    constexpr int kManySeeds = 20;
    md << "### Over " << kManySeeds << " seeds\n\n"
       << "Per world: runs that end `done`; runs with a contact and contacts in all; pieces complete of all "
          "pieces; runs with every piece found, classified right and complete; runs with every box edge within "
          "5 cm; the largest edge error (cm); robot time (mean / largest). *too_close*: the box 0.25 m from "
          "the top wall is modelled as wall-contact (the issue allows wall-contact or incomplete), which the "
          "truth calls free: so its kind and its wall-side edge count against it here.\n\n"
       << "| world | done | runs with a contact / contacts | pieces complete | runs all complete | "
          "runs edges <= 5 cm | max edge | robot time s |\n|---|---|---|---|---|---|---|---|\n";
    for (const std::string name :
         {"fig14", "fig16", "fig19", "fig20", "free_start", "corner_start", "too_close", "chair_legs"}) {
      const sim::World world = load(name);
      int done = 0, touched = 0, contacts = 0, complete = 0, pieces = 0, all_ok = 0, edges_ok = 0;
      double max_edge = 0, t_sum = 0, t_max = 0;
      for (int s = 1; s <= kManySeeds; ++s) {
        sim::InProcessRun run = sim::RunInProcess(world, with_exploration, static_cast<uint64_t>(s), 900);
        metrics::ObjectScores sc = metrics::ScoreObjects(ToJson(run.core->Map()), run.core->slam(), world, 0);
        const int furniture = name == "chair_legs" ? 2 : sc.pieces;
        done += run.core->state() == control::MissionState::kDone;
        touched += run.sim->collisions() > 0;
        contacts += static_cast<int>(run.sim->collisions());
        complete += std::min(sc.complete, furniture);
        pieces += furniture;
        all_ok += sc.found >= furniture && sc.kind_right >= furniture && sc.complete >= furniture;
        edges_ok += sc.max_edge_m <= 0.05;
        max_edge = std::max(max_edge, sc.max_edge_m);
        t_sum += run.t;
        t_max = std::max(t_max, run.t);
      }
      md << "| " << name << " | " << done << "/" << kManySeeds << " | " << touched << " / " << contacts << " | "
         << complete << "/" << pieces << " | " << all_ok << "/" << kManySeeds << " | " << edges_ok << "/"
         << kManySeeds << " | " << F(max_edge * 100) << " | " << F(t_sum / kManySeeds, 0) << " / "
         << F(t_max, 0) << " |\n";
    }
    md << "\n";
  }

  // ---- Design choice: the paper pins theta_1; we estimate it (the start pose is known).
  {
    robot::CoreOptions pinned = defaults;
    pinned.slam.association.pin_first_line = true;
    md << "## Pinned vs estimated first line\n\n"
       << "The paper pins the first line's angle at its first observation. irslam estimates it like any other "
          "line (the start pose is known, so the frame is fixed anyway) and turns the map frame so that it lies "
          "along x. Mean over worlds fig14/16/19/20 and seeds:\n\n"
       << "| first line | SLAM final pos | SLAM RMS pos | SLAM RMS hdg | wall line max angle (start frame) |\n"
       << "|---|---|---|---|---|\n";
    for (int pass = 0; pass < 2; ++pass) {
      double fp = 0, rp = 0, rh = 0, wa = 0;
      int n = 0;
      for (const std::string name : {"fig14", "fig16", "fig19", "fig20"}) {
        const sim::World world = load(name);
        for (int s = 1; s <= seeds; ++s) {
          const Run r = pass == 0 ? all[name][static_cast<size_t>(s - 1)]
                                  : RunOne(world, pinned, static_cast<uint64_t>(s), 400);
          fp += r.slam.final_position_m;
          rp += r.slam.rms_position_m;
          rh += r.slam.rms_heading_rad;
          wa += r.wall_angle_max;
          ++n;
        }
      }
      md << "| " << (pass == 0 ? "estimated (default)" : "pinned (paper)") << " | " << F(fp / n * 100) << " | "
         << F(rp / n * 100) << " | " << F(rh / n * kDeg, 2) << " | " << F(wa / n * kDeg, 2) << " |\n";
    }
    md << "\n";
  }

  // ---- Fig. 15: pose error over time.
  {
    const Run& r = all["fig14"].front();
    Series slam{"SLAM", "#1f5fbf", {}}, odo{"odometry", "#2a9d2a", {}, true};
    for (const auto& p : r.est) slam.points.emplace_back(p.t, metrics::PositionErrorAt(r.est, r.truth, p.t) * 100);
    for (size_t i = 0; i < r.odometry.size(); i += 5) {
      odo.points.emplace_back(r.odometry[i].t, metrics::PositionErrorAt(r.odometry, r.truth, r.odometry[i].t) * 100);
    }
    Write(out_dir + "/fig15_pose_error.svg",
          LineChart("Fig. 15: position error over time (Fig. 14 room, seed 1)", "robot time [s]",
                    "position error [cm]", {slam, odo}));
    md << "## Pose error over time (Fig. 15)\n\n![pose error](fig15_pose_error.svg)\n\n";
  }

  // ---- Fig. 17: constraints on/off at a corner with a 5 deg beam and wheel slip.
  {
    const sim::World world = load("fig17");
    robot::CoreOptions off = defaults;
    off.slam.association.use_constraints = false;
    md << "## Constrained vs unconstrained EKF (Fig. 17)\n\n"
       << "The Fig. 17-like world (3 m x 3 m, 5 deg beams, slip sigma 4 %, 0.4 % wheel-radius mismatch), "
          "same seeds, the geometric constraints on and off. Mean over seeds; line sigmas are the means over "
          "the mapped lines at the end.\n\n"
       << "| constraints | SLAM final pos | SLAM final hdg | SLAM RMS pos | wall line max dist | wall line max "
          "angle | line sigma rho cm | line sigma theta deg | robot sigma theta deg |\n|---|---|---|---|---|---|---|---|---|\n";
    std::vector<Series> curves;
    for (int pass = 0; pass < 2; ++pass) {
      const bool on = pass == 0;
      double fp = 0, fh = 0, rp = 0, wd = 0, wa = 0, sr = 0, st = 0, sp = 0;
      Run first;
      for (int s = 1; s <= seeds; ++s) {
        Run r = RunOne(world, on ? defaults : off, static_cast<uint64_t>(s), 400);
        fp += r.slam.final_position_m;
        fh += r.slam.final_heading_rad;
        rp += r.slam.rms_position_m;
        wd += r.wall_dist_max;
        wa += r.wall_angle_max;
        if (!r.line_sigma_rho.empty()) sr += r.line_sigma_rho.back().second;
        if (!r.line_sigma_theta.empty()) st += r.line_sigma_theta.back().second;
        if (!r.pose_sigma.empty()) sp += r.pose_sigma.back().second;
        if (s == 1) first = std::move(r);
      }
      const double n = seeds;
      md << "| " << (on ? "on" : "off") << " | " << F(fp / n * 100) << " | " << F(fh / n * kDeg, 2) << " | "
         << F(rp / n * 100) << " | " << F(wd / n * 100) << " | " << F(wa / n * kDeg, 2) << " | "
         << F(sr / n, 2) << " | " << F(st / n, 3) << " | " << F(sp / n, 3) << " |\n";
      curves.push_back({std::string("line sigma theta, constraints ") + (on ? "on" : "off"),
                        on ? "#1f5fbf" : "#d9534f", first.line_sigma_theta});
      curves.push_back({std::string("robot sigma theta, constraints ") + (on ? "on" : "off"),
                        on ? "#1f5fbf" : "#d9534f", first.pose_sigma, true});
    }
    Write(out_dir + "/fig17_covariance.svg",
          LineChart("Fig. 17: covariance convergence with and without constraints (seed 1)",
                    "robot time [s]", "sigma [deg]", curves, false));
    md << "\n![covariance convergence](fig17_covariance.svg)\n\n";
  }

  // ---- Fig. 18: five loops.
  {
    const sim::World world = load("fig18");
    robot::CoreOptions five = defaults;
    five.mission.wall_follow_loops = 5;
    md << "## Five wall-following loops (Fig. 18)\n\n"
       << "Position error (cm) at the end of each loop; odometry drifts, the corrected estimate does not.\n\n"
       << "| seed | done | SLAM loop 1..5 | odometry loop 1..5 | SLAM grows? | odometry grows? |\n|---|---|---|---|---|---|\n";
    bool bounded = true;
    Run first;
    for (int s = 1; s <= seeds; ++s) {
      Run r = RunOne(world, five, static_cast<uint64_t>(s), 1200);
      std::string se, oe;
      std::vector<double> sv, ov;
      for (double t : r.loop_times) {
        sv.push_back(metrics::PositionErrorAt(r.est, r.truth, t) * 100);
        ov.push_back(metrics::PositionErrorAt(r.odometry, r.truth, t) * 100);
        se += F(sv.back()) + " ";
        oe += F(ov.back()) + " ";
      }
      const bool slam_grows = sv.size() >= 2 && sv.back() > sv.front() + 3.0;
      const bool odo_grows = ov.size() >= 2 && ov.back() > ov.front();
      bounded &= r.done && r.loop_times.size() == 5 && !slam_grows;
      md << "| " << s << " | " << (r.done ? "yes" : "**no**") << " | " << se << " | " << oe << " | "
         << (slam_grows ? "**yes**" : "no") << " | " << (odo_grows ? "yes" : "no") << " |\n";
      if (s == 1) first = std::move(r);
    }
    md << "\nCorrected error bounded over five loops (last loop within 3 cm of the first, every seed): **"
       << (bounded ? "yes" : "NO") << "**.\n\n";
    Series slam{"SLAM", "#1f5fbf", {}}, odo{"odometry", "#2a9d2a", {}, true};
    for (const auto& p : first.est) slam.points.emplace_back(p.t, metrics::PositionErrorAt(first.est, first.truth, p.t) * 100);
    for (size_t i = 0; i < first.odometry.size(); i += 5) {
      odo.points.emplace_back(first.odometry[i].t,
                              metrics::PositionErrorAt(first.odometry, first.truth, first.odometry[i].t) * 100);
    }
    Write(out_dir + "/fig18_loops.svg", LineChart("Fig. 18: five loops, position error (seed 1)",
                                                  "robot time [s]", "position error [cm]", {slam, odo}));
    md << "![five loops](fig18_loops.svg)\n";
  }
  // ---- The control loop's work per period (issue 15). Wall-clock numbers: they
  // differ from run to run and with the host's load (benchmarks, not accuracy).
  if (!tick_rows.empty()) {
    const sim::World large = load("large_room");
    for (int s = 1; s <= seeds; ++s) {
      AddTicks(&tick_rows["large_room"], sim::RunInProcess(large, with_exploration, static_cast<uint64_t>(s), 900,
                                                           nullptr, nullptr, metrics::ThreadCpuNs));
    }
    const auto ms = [](int64_t ns) { return F(static_cast<double>(ns) * 1e-6, 3); };
    md << "\n## Control-loop work per period (issue 15)\n\n"
          "The whole missions above (and an 8 x 6 m room, tests/worlds/large_room.json) in process: each "
          "control period's work (the frames since the last period, then the tick) in the thread's CPU time "
          "(what the other processes of a loaded host take does not count; the real-time factor does count "
          "it), so these numbers change a little from run to run (docs/benchmarks.md has measured ones). Worst run of each world; *phase*: what took most of the largest period. Targets: largest "
          "<= 2 ms, p99.9 <= 1 ms, every mission >= 500x real time.\n\n"
       << "| world | runs | robot time s | p99 ms | p99.9 ms | max ms | phase | slowest x real time |\n"
       << "|---|---|---|---|---|---|---|---|\n";
    for (const auto& [name, r] : tick_rows) {
      md << "| " << name << " | " << r.runs << " | " << F(r.robot_s) << " | " << ms(r.p99) << " | " << ms(r.p999)
         << " | " << ms(r.max) << " | " << r.phase << " | " << F(r.slowest_x, 0) << " |\n";
    }
  }
  if (!Write(out_dir + "/accuracy.md", md.str())) {
    std::fprintf(stderr, "irslam-report: cannot write %s/accuracy.md\n", out_dir.c_str());
    return 1;
  }
  std::printf("%s", md.str().c_str());
  return 0;
}
