#include "tests/tools/clean_report.h"

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <thread>

#include "sim/generator.h"
#include "tests/tools/clean_eval.h"
#include "tests/tools/metrics.h"
#include "tests/tools/svg_chart.h"

namespace irslam::report {
namespace {

std::string F(double v, int prec = 1) {
  char b[32];
  std::snprintf(b, sizeof b, "%.*f", prec, v);
  return b;
}

struct Job {
  std::string label;  // world name or "profile/seed"
  std::string profile;  // "paper" or the noise profile
  sim::World world;
  uint64_t seed = 1;
};

std::string Row(const Job& j, const metrics::CleanScore& s) {
  std::ostringstream r;
  r << "| " << j.label << " | " << j.seed << " | " << s.end_state << " | " << F(s.reachable_m2, 2) << " | "
    << F(100 * s.coverage) << " % | " << F(100 * s.covered_total) << " % | " << F(100 * s.estimated_fraction)
    << " % | " << F(s.path_m) << " | " << F(s.path_ratio, 2) << " | " << F(s.clean_s, 0) << " | "
    << s.cells_done << "/" << s.cells << " | " << F(s.unreachable_m2, 2) << " | " << s.contacts_cleaning << " | "
    << F(100 * s.rms_position_m) << " | " << F(100 * s.home_error_m) << " | " << F(100 * s.bounce_coverage)
    << " % | " << s.contacts_clutter << " |\n";
  return r.str();
}

struct Summary {
  int runs = 0, done = 0, cov97 = 0, cov93 = 0, no_contact = 0, pose_ok = 0, home_ok = 0;
  int no_mapped_contact = 0;  // runs whose contacts were all with clutter (or none)
  int contacts = 0, clutter = 0;
  double coverage = 0, min_coverage = 1, ratio = 0, bounce = 0;
};

void Add(Summary* m, const metrics::CleanScore& s) {
  ++m->runs;
  m->done += s.cleaned;
  m->cov97 += s.coverage >= 0.97;
  m->cov93 += s.coverage >= 0.93;
  m->no_contact += s.contacts_cleaning == 0;
  m->no_mapped_contact += s.contacts_cleaning == s.contacts_clutter;
  m->contacts += s.contacts_cleaning;
  m->clutter += s.contacts_clutter;
  m->pose_ok += s.rms_position_m <= 0.05;
  m->home_ok += s.home_error_m <= 0.10;
  m->coverage += s.coverage;
  m->min_coverage = std::min(m->min_coverage, s.coverage);
  m->ratio += s.path_ratio;
  m->bounce += s.bounce_coverage;
}

}  // namespace

int RunCleanReport(const robot::CoreOptions& options, const std::string& worlds_dir,
                   const std::vector<std::string>& worlds, int seeds, int generated, const std::string& profiles,
                   uint64_t first_seed, int jobs, const std::string& out_dir, const std::string& noise_nominal) {
  std::vector<Job> list;
  for (const auto& name : worlds) {
    std::string error;
    auto w = sim::LoadWorldFile(worlds_dir + "/" + name + ".json", &error);
    if (!w) {
      std::fprintf(stderr, "irslam-report: %s\n", error.c_str());
      return 2;
    }
    for (int k = 1; k <= seeds; ++k) list.push_back({name, "paper", *w, static_cast<uint64_t>(k)});
  }
  std::stringstream pl(profiles);
  for (std::string name; generated > 0 && std::getline(pl, name, ',');) {
    const auto profile = sim::ParseNoiseProfile(name);
    if (!profile) {
      std::fprintf(stderr, "irslam-report: unknown profile '%s'\n", name.c_str());
      return 2;
    }
    for (int i = 0; i < generated; ++i) {
      const uint64_t seed = first_seed + static_cast<uint64_t>(i);
      sim::World world = sim::GenerateWorld(seed, *profile);
      std::string unused;
      metrics::SetNoiseNominal(noise_nominal, &world.noise, &unused);
      list.push_back({name + "/" + std::to_string(seed), name, std::move(world), seed});
    }
  }
  std::vector<metrics::CleanScore> scores(list.size());
  std::atomic<size_t> next{0};
  const double max_time = options.mission.max_time_s + options.mission.cleaning.max_time_s;
  const auto work = [&] {
    for (size_t i = next++; i < list.size(); i = next++) {
      scores[i] = metrics::RunAndScoreClean(list[i].world, options, list[i].seed, max_time, true);
      std::fprintf(stderr, "%s", Row(list[i], scores[i]).c_str());
    }
  };
  std::vector<std::thread> threads;
  for (int j = 0; j < std::max(1, jobs); ++j) threads.emplace_back(work);
  for (auto& t : threads) t.join();

  std::ostringstream md;
  md << "| world | seed | end | reachable m² | covered (cleaning) | covered (whole run) | estimated | path m | "
        "path ratio | cleaning s | cells | unreachable m² | contacts | pose RMS cm | end to start cm | bounce | "
        "contacts with clutter |\n"
        "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  std::vector<std::pair<std::string, Summary>> sums;
  const auto sum_of = [&](const std::string& p) -> Summary& {
    for (auto& [k, v] : sums)
      if (k == p) return v;
    sums.emplace_back(p, Summary{});
    return sums.back().second;
  };
  for (size_t i = 0; i < list.size(); ++i) {
    md << Row(list[i], scores[i]);
    Add(&sum_of(list[i].profile), scores[i]);
  }
  md << "\n| set | runs | done | mean coverage | worst | >= 97 % | >= 93 % | mean path ratio | no contact | pose RMS "
        "<= 5 cm | home <= 10 cm | bounce mean | contacts per run (with clutter) | no contact but with clutter "
        "|\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const auto& [k, m] : sums) {
    const double n = std::max(1, m.runs);
    md << "| " << k << " | " << m.runs << " | " << m.done << " | " << F(100 * m.coverage / n) << " % | "
       << F(100 * m.min_coverage) << " % | " << m.cov97 << " | " << m.cov93 << " | " << F(m.ratio / n, 2) << " | "
       << m.no_contact << " | " << m.pose_ok << " | " << m.home_ok << " | " << F(100 * m.bounce / n) << " % | "
       << F(m.contacts / n, 2) << " (" << F(m.clutter / n, 2) << ") | " << m.no_mapped_contact << " |\n";
  }
  std::ofstream out(out_dir + "/cleaning-results.md");
  out << md.str();
  // Coverage over time, clean against bounce, on the first run (a paper world).
  if (!scores.empty()) {
    std::vector<Series> series;
    const char* colors[] = {"#2a6", "#36c", "#c60", "#a3a"};
    for (size_t i = 0; i < std::min<size_t>(list.size(), 4); ++i) {
      const size_t k = i * std::max<size_t>(1, static_cast<size_t>(seeds));
      if (k >= list.size()) break;
      auto scale = [](std::vector<std::pair<double, double>> v) {
        for (auto& p : v) p.second *= 100;
        return v;
      };
      series.push_back({list[k].label + " clean", colors[i], scale(scores[k].curve), false});
      series.push_back({list[k].label + " bounce", colors[i], scale(scores[k].bounce_curve), true});
    }
    std::ofstream svg(out_dir + "/cleaning-coverage.svg");
    svg << LineChart("Coverage of the reachable floor over time: planned cleaning (solid) vs random bounce (dashed)",
                     "s since cleaning began", "% of reachable floor swept (truth)", series);
  }
  std::fprintf(stderr, "%s", md.str().c_str());
  return out ? 0 : 1;
}

}  // namespace irslam::report
