// Relocalisation in a saved map (issue 14), in process: a map is made by one
// mission, then missions start from it at other poses (the world's start
// replaced) and must relocalise, keep the saved frame and ids, and finish.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <random>

#include "daemon/core_json.h"
#include "robot/robot_core.h"
#include "sim/faults.h"
#include "sim/sim_run.h"
#include "tests/testing/worlds.h"
#include "tests/tools/reloc_eval.h"

namespace irslam {
namespace {

struct Made {
  robot::MapSnapshot map;
  Pose2 world_from_map;  // a map-frame pose -> the world frame
};

// One exploring mission; the map frame relates to the world by the final
// estimated and true poses (the estimate is a few cm off: the tolerances below
// allow for it).
Made MakeMap(const sim::World& world, uint64_t seed) {
  sim::InProcessRun run = sim::RunInProcess(world, robot::DefaultCoreOptions(), seed, 900);
  EXPECT_EQ(run.core->state(), control::MissionState::kDone);
  Made m;
  m.map = run.core->Map();
  const Pose2 est = m.map.pose, truth = run.sim->true_pose();
  const double th = NormalizeAngle(truth.theta - est.theta);
  const double c = std::cos(th), s = std::sin(th);
  m.world_from_map = {truth.x - (c * est.x - s * est.y), truth.y - (s * est.x + c * est.y), th};
  return m;
}

bool Free(const sim::World& w, double x, double y, double margin) {
  const sim::Box b = w.Bounds();
  if (x < b.xmin + margin || x > b.xmax - margin || y < b.ymin + margin || y > b.ymax - margin) return false;
  for (const auto& seg : w.Segments()) {
    sim::Vec2 closest;
    if (sim::PointSegmentDistance({x, y}, seg, &closest) < margin) return false;
  }
  for (const auto& o : w.objects) {
    if (x > o.xmin && x < o.xmax && y > o.ymin && y < o.ymax) return false;
  }
  return true;
}

Pose2 RandomFreePose(const sim::World& w, std::mt19937_64* rng) {
  const sim::Box b = w.Bounds();
  std::uniform_real_distribution<double> ux(b.xmin, b.xmax), uy(b.ymin, b.ymax), ut(-M_PI, M_PI);
  for (int i = 0; i < 10000; ++i) {
    const double x = ux(*rng), y = uy(*rng);
    if (Free(w, x, y, 0.3)) return {x, y, ut(*rng)};
  }
  ADD_FAILURE() << "no free pose";
  return w.start;
}

struct RelocResult {
  bool committed = false;
  double commit_t = -1;
  double err_at_commit_m = 0, err_at_commit_rad = 0;
  double max_err_after_m = 0, max_err_after_rad = 0;  // from 5 s after the commit on
  control::MissionState end = control::MissionState::kIdle;
  robot::MapSnapshot map;
  std::string reason;
  int attempts = 0;
};

RelocResult Relocalise(const sim::World& world, const Made& made, const Pose2& start, uint64_t seed,
                       double max_time_s, bool clean) {
  sim::World w = world;
  w.start = start;
  RelocResult r;
  std::optional<slam::SlamStats> s0;
  std::string last_reason;
  const auto on_tick = [&](const sim::InProcessRun& run) {
    if (!s0 && run.core->state() == control::MissionState::kClean) s0 = run.core->slam().stats();
    if (std::getenv("RELOC_TRACE") && run.core->Status(run.t).mission.reason != last_reason) {
      last_reason = run.core->Status(run.t).mission.reason;
      std::printf("    %.1f %s: %s\n", run.t, control::ToString(run.core->state()), last_reason.c_str());
    }
    const auto st = run.core->Status(run.t);
    if (!st.relocalize || !st.relocalize->committed || !run.core->slam().in_saved_map()) return;
    const Pose2 est = Compose(made.world_from_map, run.core->slam().map_pose());
    const Pose2& truth = run.sim->true_pose();
    const double e = std::hypot(est.x - truth.x, est.y - truth.y);
    const double a = std::abs(NormalizeAngle(est.theta - truth.theta));
    if (!r.committed) {
      r.committed = true;
      r.commit_t = st.relocalize->committed_t;
      r.err_at_commit_m = e;
      r.err_at_commit_rad = a;
    } else if (std::getenv("RELOC_DEBUG") && std::fmod(run.t, 2.0) < 0.02) {
      const auto& ss = run.core->slam().stats();
      std::printf("  t %.1f %s err %.3f %.2f deg upd %d ins %d gate %d lines %zu coll %zu sd %.3f %.2f| %s\n", run.t,
                  control::ToString(run.core->state()), e, a * 180 / M_PI, ss.updates, ss.insertions,
                  ss.rejected_gate, run.core->slam().num_lines(), static_cast<size_t>(run.sim->collisions()),
                  st.slam.pose_std[0], st.slam.pose_std[2] * 180 / M_PI, st.mission.reason.c_str());
    }
    if (r.committed && run.t > r.commit_t + 5) {
      r.max_err_after_m = std::max(r.max_err_after_m, e);
      r.max_err_after_rad = std::max(r.max_err_after_rad, a);
    }
  };
  robot::CoreOptions options = robot::DefaultCoreOptions();
  if (clean) options.mission.mode = "clean";
  if (std::getenv("RELOC_NOCHECK")) options.mission.relocalize.min_agreement = 0;
  sim::InProcessRun run = sim::RunInProcess(w, options, seed, max_time_s, on_tick, nullptr, nullptr, made.map);
  if (s0 && std::getenv("RELOC_DEBUG")) {
    const auto& s = run.core->slam().stats();
    std::printf("reloc clean: windows %d ins %d coll %d declined %d upd %d gate %d angle %d; lines %zu\n",
                s.windows - s0->windows, s.insertions - s0->insertions, s.collinear_insertions - s0->collinear_insertions,
                s.collinear_declined - s0->collinear_declined, s.updates - s0->updates,
                s.rejected_gate - s0->rejected_gate, s.rejected_angle - s0->rejected_angle, run.core->slam().num_lines());
  }
  r.end = run.core->state();
  r.reason = run.core->Status(run.t).mission.reason;
  r.attempts = run.core->Status(run.t).relocalize ? run.core->Status(run.t).relocalize->attempts : 0;
  r.map = run.core->Map();
  return r;
}

TEST(RelocTest, Fig14FromRandomPosesCommitsRightKeepsIdsAndFinishes) {
  const sim::World world = testing::LoadTestWorld("fig14");
  const Made made = MakeMap(world, 1);
  std::mt19937_64 rng(7);
  int right = 0, wrong = 0;
  const int runs = 5;
  for (int i = 0; i < runs; ++i) {
    const Pose2 start = RandomFreePose(world, &rng);
    const RelocResult r = Relocalise(world, made, start, 10 + i, 1500, true);
    SCOPED_TRACE("run " + std::to_string(i) + " start " + std::to_string(start.x) + "," +
                 std::to_string(start.y) + "," + std::to_string(start.theta));
    std::printf("run %d: committed %d at %.1f s, err %.3f m %.2f deg, after %.3f m %.2f deg, end %s (%s), attempts %d\n", i,
                r.committed, r.commit_t, r.err_at_commit_m, r.err_at_commit_rad * 180 / M_PI, r.max_err_after_m,
                r.max_err_after_rad * 180 / M_PI, control::ToString(r.end), r.reason.c_str(), r.attempts);
    if (!r.committed) continue;
    if (r.err_at_commit_m > 0.2 || r.err_at_commit_rad > 10 * M_PI / 180) {
      ++wrong;
      continue;
    }
    ++right;
    EXPECT_EQ(r.end, control::MissionState::kDone);
    EXPECT_LE(r.max_err_after_m, 0.1);
    // The saved lines keep their ids.
    for (const auto& l : made.map.lines) {
      EXPECT_TRUE(metrics::HasLineId(r.map.lines, l.id)) << "line " << l.id;
    }
    EXPECT_TRUE(r.map.relocalized.has_value());
  }
  EXPECT_EQ(wrong, 0);
  EXPECT_GE(right, runs - 1);
}

// Cleaning after a right commit in a room that has not changed: the map's
// agreement check must not send the robot back to relocalising. Before a new
// line merged into a saved one counted as the map seen again, short wall
// pieces a few degrees off far from the origin (beyond eq. (13)'s Hough
// distance, so inserted, then merged) read as "0 % of recent lines matched"
// seconds after the commit: runs 2 and 5 of these (the RelocDebug sweep's
// fig14 starts) relocalised a second time, 6 of 10 over the sweep.
TEST(RelocTest, CleaningAfterARightCommitDoesNotRelocaliseAgain) {
  const sim::World world = testing::LoadTestWorld("fig14");
  const Made made = MakeMap(world, 1);
  std::mt19937_64 rng(99);
  for (int i = 0; i < 6; ++i) {
    const Pose2 start = RandomFreePose(world, &rng);
    const RelocResult r = Relocalise(world, made, start, 100 + i, 1500, true);
    SCOPED_TRACE("run " + std::to_string(i));
    ASSERT_TRUE(r.committed);
    EXPECT_LE(r.err_at_commit_m, 0.2);
    EXPECT_EQ(r.attempts, 1) << r.reason;
    EXPECT_EQ(r.end, control::MissionState::kDone) << r.reason;
  }
}

// The map saved by a cleaning (seed 1) stopped once `cells` cells were done.
robot::MapSnapshot MapOfCleaningStoppedAfter(const sim::World& world, const robot::CoreOptions& options,
                                             int cells) {
  sim::RunSetup first;
  first.stop_when = [cells](const sim::InProcessRun& run) {
    const auto c = run.core->Status(run.t).cleaning;
    return c && c->cells_done >= cells;
  };
  sim::InProcessRun a = sim::RunInProcess(world, options, 1, 2000, nullptr, nullptr, nullptr, first);
  a.core->Stop(a.t);
  return a.core->Map();
}

// Issue 13's resume, through issue 14: a cleaning stopped after two cells (the
// map saved then), a later mission from elsewhere relocalises in that map and
// cleans only the cells left.
TEST(RelocTest, CleaningStoppedAfterTwoCellsResumesTheRestInTheSavedMap) {
  const sim::World world = testing::LoadTestWorld("fig14");
  robot::CoreOptions options = robot::DefaultCoreOptions();
  options.mission.mode = "clean";
  const robot::MapSnapshot saved = MapOfCleaningStoppedAfter(world, options, 2);
  ASSERT_TRUE(saved.cleaning);
  ASSERT_EQ(saved.cleaning->cells_done, 2);
  const int total = saved.cleaning->cells_total;

  sim::World w = world;
  w.start = {2.6, 0.8, 2.0};
  sim::RunSetup second;
  second.saved_map = saved;
  std::string resumed;
  sim::InProcessRun b = sim::RunInProcess(
      w, options, 2, 2000,
      [&](const sim::InProcessRun& run) {
        const std::string& r = run.core->Status(run.t).mission.reason;
        if (r.find("resumed") != std::string::npos) resumed = r;
      },
      nullptr, nullptr, second);
  EXPECT_EQ(b.core->state(), control::MissionState::kDone) << b.core->Status(b.t).mission.reason;
  // The saved model is the one the plan was made in: the same cells again.
  EXPECT_NE(resumed.find("(resumed: 2 done before, same plan)"), std::string::npos) << resumed;
  const auto c = b.core->Map().cleaning;
  ASSERT_TRUE(c);
  EXPECT_EQ(c->cells_total, total);
  EXPECT_EQ(c->cells_done + static_cast<int>(std::count_if(c->cells.begin(), c->cells.end(),
                                                           [](const auto& x) { return x.unreachable; })),
            total);
  // The second mission swept only what was left: its cleaning path is well
  // under a whole cleaning's (the first mission's two cells are not driven again).
  EXPECT_GT(c->fraction, 0.9);
}

// A saved map's cleaning may hold a done cell with neither outline nor route
// (the map reader accepts empty point lists): resuming skips it instead of
// reading past its outline.
TEST(RelocTest, ADoneCellWithoutOutlineOrRouteIsSkippedOnResume) {
  const sim::World world = testing::LoadTestWorld("fig14");
  robot::CoreOptions options = robot::DefaultCoreOptions();
  options.mission.mode = "clean";
  robot::MapSnapshot saved = MapOfCleaningStoppedAfter(world, options, 1);
  ASSERT_TRUE(saved.cleaning);
  control::CleaningProgress::Cell empty;
  empty.id = 99;
  empty.done = true;
  saved.cleaning->cells.push_back(empty);
  sim::RunSetup second;
  second.saved_map = saved;
  second.stop_when = [](const sim::InProcessRun& run) {
    const auto c = run.core->Status(run.t).cleaning;
    return c && c->cells_total > 0 && run.core->Status(run.t).mission.reason.rfind("cleaning ", 0) == 0;
  };
  sim::InProcessRun b = sim::RunInProcess(world, options, 2, 2000, nullptr, nullptr, nullptr, second);
  const auto c = b.core->Status(b.t).cleaning;
  ASSERT_TRUE(c) << b.core->Status(b.t).mission.reason;
  EXPECT_GE(c->cells_done, 1);
  EXPECT_GT(c->covered_m2, 0);
}

// `stop` and `start` in the live map (clean_e2e's StopAndStart, in process):
// the model has not moved, so the plan is made again from the stopped plan's
// room, objects and contacts - the same cells, the same ones done - even when
// the robot has touched things since it planned. Before the plan's inputs were
// kept, the plan was made from the contacts remembered by then and could be cut
// otherwise (CI saw 6 cells, 2 done, where 4 and 1 were saved).
TEST(RelocTest, StopAndStartInTheLiveMapPlansTheSameCells) {
  robot::CoreOptions options = robot::DefaultCoreOptions();
  options.mission.mode = "clean";
  int runs = 0;
  for (const char* name : {"fig14", "fig16", "fig20"}) {
    const sim::World world = testing::LoadTestWorld(name);
    for (int seed = 1; seed <= 2; ++seed) {
      SCOPED_TRACE(std::string(name) + " seed " + std::to_string(seed));
      std::optional<control::CleaningProgress> stopped;
      std::optional<control::CleaningProgress> resumed;
      std::string reason;
      sim::RunSetup setup;
      setup.stop_and_start_when = [&](const sim::InProcessRun& run) {
        const auto c = run.core->Status(run.t).cleaning;
        if (!c || c->cells_done < 1 || c->cells_total < 3) return false;
        stopped = c;
        return true;
      };
      setup.stop_when = [&](const sim::InProcessRun& run) {
        const auto st = run.core->Status(run.t);
        if (!stopped || st.mission.state != control::MissionState::kClean ||
            st.mission.reason.rfind("cleaning ", 0) != 0)
          return false;
        resumed = st.cleaning;
        reason = st.mission.reason;
        return true;
      };
      sim::RunInProcess(world, options, static_cast<uint64_t>(seed), 3000, nullptr, nullptr, nullptr, setup);
      if (!stopped) continue;  // fewer than 3 cells, or none done
      ++runs;
      ASSERT_TRUE(resumed);
      EXPECT_NE(reason.find(", same plan)"), std::string::npos) << reason;
      EXPECT_EQ(resumed->cells_total, stopped->cells_total);
      EXPECT_EQ(resumed->cells_done, stopped->cells_done);
      ASSERT_EQ(resumed->cells.size(), stopped->cells.size());
      for (size_t i = 0; i < resumed->cells.size(); ++i) {
        // The same cells (the tour may start elsewhere: matched by id).
        const auto same = std::find_if(stopped->cells.begin(), stopped->cells.end(),
                                       [&](const auto& c) { return c.id == resumed->cells[i].id; });
        ASSERT_NE(same, stopped->cells.end()) << "cell " << resumed->cells[i].id;
        EXPECT_EQ(same->polygon, resumed->cells[i].polygon) << "cell " << resumed->cells[i].id;
        EXPECT_EQ(same->done, resumed->cells[i].done) << "cell " << resumed->cells[i].id;
      }
    }
  }
  EXPECT_GE(runs, 4);
}

// Issue 13's resume as the daemon's users do it (clean_e2e's StopAndStart):
// stop and start once cleaning began (the mission continues in its live map),
// stop again a cell later, then a mission from elsewhere relocalises in the
// saved map. Every cell done before must still be done in the plan it cleans
// by, over worlds and seeds (RESUME_RUNS seeds per world; 3 by default).
TEST(RelocTest, StopStartAndRelocaliseKeepTheCellsDoneOverWorldsAndSeeds) {
  robot::CoreOptions options = robot::DefaultCoreOptions();
  options.mission.mode = "clean";
  const int seeds = std::getenv("RESUME_RUNS") ? std::atoi(std::getenv("RESUME_RUNS")) : 3;
  int runs = 0, kept = 0, not_committed = 0;
  for (const char* name : {"fig14", "fig16", "fig17", "fig18", "fig19", "fig20"}) {
    const sim::World world = testing::LoadTestWorld(name);
    for (int seed = 1; seed <= seeds; ++seed) {
      SCOPED_TRACE(std::string(name) + " seed " + std::to_string(seed));
      const auto cleaning = [](const sim::InProcessRun& run) { return run.core->Status(run.t).cleaning; };
      int done_at_restart = -1;
      sim::RunSetup first;
      first.stop_and_start_when = [&](const sim::InProcessRun& run) {
        const auto c = cleaning(run);
        if (!c || c->cells_done < 1 || c->cells_total < 3) return false;
        done_at_restart = c->cells_done;
        return true;
      };
      first.stop_when = [&](const sim::InProcessRun& run) {
        const auto c = cleaning(run);
        return done_at_restart >= 0 && c && c->cells_done > done_at_restart;
      };
      sim::InProcessRun a = sim::RunInProcess(world, options, static_cast<uint64_t>(seed), 3000, nullptr,
                                              nullptr, nullptr, first);
      if (done_at_restart < 0) continue;  // fewer than 3 cells, or none done: nothing to resume
      a.core->Stop(a.t);
      const robot::MapSnapshot saved = a.core->Map();
      ASSERT_TRUE(saved.cleaning);
      if (saved.cleaning->cells_done <= done_at_restart) continue;  // the mission ended first
      std::mt19937_64 rng(static_cast<uint64_t>(seed) * 7919);
      sim::World w = world;
      w.start = RandomFreePose(world, &rng);
      sim::RunSetup second;
      second.saved_map = saved;
      second.stop_when = [&](const sim::InProcessRun& run) {
        const auto st = run.core->Status(run.t);
        return st.mission.state == control::MissionState::kClean && st.mission.reason.rfind("cleaning ", 0) == 0;
      };
      sim::InProcessRun b = sim::RunInProcess(w, options, static_cast<uint64_t>(seed) + 100, 2000, nullptr,
                                              nullptr, nullptr, second);
      const auto c = cleaning(b);
      ASSERT_TRUE(c) << b.core->Status(b.t).mission.reason;
      const auto reloc = b.core->Status(b.t).relocalize;
      if (!reloc || !reloc->committed) {
        ++not_committed;  // a fresh map: nothing done in it (the relocalisation's own rate: docs)
        continue;
      }
      ++runs;
      const bool ok = c->cells_done >= saved.cleaning->cells_done;
      kept += ok;
      if (!ok) {
        std::printf("%s seed %d: saved %d of %d cells, resumed %s, %d of %d\n", name, seed,
                    saved.cleaning->cells_done, saved.cleaning->cells_total,
                    b.core->Status(b.t).mission.reason.c_str(), c->cells_done, c->cells_total);
      }
    }
  }
  std::printf("resume: %d of %d runs kept every cell done (%d more did not relocalise)\n", kept, runs,
              not_committed);
  EXPECT_GE(runs, 3 * seeds);
  // Measured with RESUME_RUNS=20: 78 of 78 since the plan's inputs (room,
  // objects, contacts) are saved with it and planned from again while the
  // model has not moved (cleaning.resume_same_model_m). Before, 75 of 78: the
  // first plans of fig16 seed 1, fig14 seed 20 and fig20 seed 2 were cut round
  // a contact, which was not saved, and the strip planned instead was only
  // ~76 % inside the cells done. Before the overlap and the kept orientation,
  // RESUME_RUNS=10: 31 of 38.
  EXPECT_EQ(kept, runs);
}

// The robot lifted and put down elsewhere (the simulator's kidnap fault) while
// cleaning in a saved map: the map's disagreement is found, the robot
// relocalises again, and the saved lines are not corrupted (their ids kept,
// no line of the mission's own far from every saved one).
struct KidnapCount {
  int detected = 0, recovered = 0;
};

// Kidnap runs `which` (seeds 40 + i) in a map made by one exploring mission of
// `world`: each cleans from a random free pose, is put down elsewhere at 150 s,
// and is checked for corruption (EXPECTs); counted: detected and recovered.
KidnapCount RunKidnaps(const sim::World& world, const std::vector<int>& which) {
  const Made made = MakeMap(world, 1);
  robot::CoreOptions options = robot::DefaultCoreOptions();
  options.mission.mode = "clean";
  KidnapCount c;
  for (int i : which) {
    std::mt19937_64 rng(40 + i);
    const Pose2 start = RandomFreePose(world, &rng);
    const Pose2 drop = RandomFreePose(world, &rng);
    std::string error;
    const auto spec = sim::ParseFaultSpec("kidnap:at=150:x=" + std::to_string(drop.x) + ":y=" +
                                              std::to_string(drop.y) + ":theta=" + std::to_string(drop.theta),
                                          &error);
    EXPECT_TRUE(spec) << error;
    if (!spec) return c;
    sim::World w = world;
    w.start = start;
    sim::RunSetup setup;
    setup.saved_map = made.map;
    int attempts = 0;
    double err_end = 1e9;
    std::string last_reason;
    sim::InProcessRun run = sim::RunInProcess(
        w, options, 50 + i, 2000,
        [&](const sim::InProcessRun& r) {
          const auto st = r.core->Status(r.t);
          if (std::getenv("RELOC_TRACE") && st.mission.reason != last_reason) {
            last_reason = st.mission.reason;
            const Pose2 est = Compose(made.world_from_map, r.core->slam().map_pose());
            const Pose2& truth = r.sim->true_pose();
            std::printf("    %.1f %s: %s (true %.2f %.2f %.2f, estimate %.2f %.2f %.2f, %zu lines)\n", r.t,
                        control::ToString(r.core->state()), last_reason.c_str(), truth.x, truth.y, truth.theta,
                        est.x, est.y, est.theta, r.core->slam().num_lines());
          }
          if (st.relocalize) attempts = st.relocalize->attempts;
          if (st.relocalize && st.relocalize->committed && r.core->slam().in_saved_map()) {
            const Pose2 est = Compose(made.world_from_map, r.core->slam().map_pose());
            err_end = std::hypot(est.x - r.sim->true_pose().x, est.y - r.sim->true_pose().y);
          }
        },
        &*spec, nullptr, setup);
    const robot::MapSnapshot out = run.core->Map();
    std::printf("kidnap run %d: attempts %d, end %s (%s), final error %.3f m\n", i, attempts,
                control::ToString(run.core->state()), run.core->Status(run.t).mission.reason.c_str(), err_end);
    // Recovered: relocalised again, right (within 20 cm) at the end, and the
    // map not given up (before, runs 27 and 43 counted: right, but the map
    // kept disagreeing until the mission gave it up).
    const std::string reason = run.core->Status(run.t).mission.reason;
    const bool given_up = reason.find("giving up") != std::string::npos || reason.find("lost:") != std::string::npos;
    if (attempts >= 2) ++c.detected;
    if (attempts >= 2 && err_end < 0.2 && !given_up) ++c.recovered;
    // Not corrupted: every saved line keeps its id, and every line of the
    // output lies near (within 0.3 m: its ends) a saved line (fig14's saved
    // map has the whole room; nothing in it moved).
    for (const auto& l : made.map.lines) {
      EXPECT_TRUE(metrics::HasLineId(out.lines, l.id)) << "run " << i << " line " << l.id;
    }
    for (const auto& m : out.lines) {
      const auto near = [&](const Eigen::Vector2d& p) {
        return std::any_of(made.map.lines.begin(), made.map.lines.end(), [&](const auto& l) {
          sim::Vec2 closest;
          return sim::PointSegmentDistance({p.x(), p.y()}, {{l.p0.x(), l.p0.y()}, {l.p1.x(), l.p1.y()}}, &closest) <
                 0.3;
        });
      };
      EXPECT_TRUE(near(m.p0) && near(m.p1)) << "run " << i << ": line " << m.id << " (" << m.p0.transpose()
                                            << ") - (" << m.p1.transpose() << ") is far from the saved map";
    }
  }
  return c;
}

TEST(RelocTest, KidnappedWhileCleaningRelocalisesAgainWithoutCorruptingTheMap) {
  // RELOC_KIDNAP_WORLD: another world of tests/worlds, for the measurement.
  const char* name = std::getenv("RELOC_KIDNAP_WORLD");
  // Runs 0-3; 27 and 43: mapped from the wrong pose before the kidnap was
  // found, lines stayed in the map relocalised in, and the robot relocalised
  // again and again until it gave the map up; 16: never found again, the map
  // is restored as it was, once with a line of the local SLAM's in it.
  // RELOC_KIDNAP_RUNS=48: the measurement over seeds 40-87
  // (docs/relocalization.md).
  std::vector<int> which = {0, 1, 2, 3, 16, 27, 43};
  if (const char* n = std::getenv("RELOC_KIDNAP_RUNS")) {
    which.clear();
    for (int i = 0; i < std::atoi(n); ++i) which.push_back(i);
  }
  if (const char* one = std::getenv("RELOC_KIDNAP_RUN")) which = {std::atoi(one)};  // with RELOC_TRACE
  const KidnapCount c = RunKidnaps(testing::LoadTestWorld(name ? name : "fig14"), which);
  // Measured over seeds 40-87 (RELOC_KIDNAP_RUNS=48): recovered 46 of 48
  // (45 before relocalising ignored the contacts remembered in the map's
  // frame: run 16 turned on the spot; 43 before lines of the mission's own
  // that the IR rays contradict left the map: runs 27 and 43), no line far
  // from the saved map in any (4 runs before that and before a map given up
  // was restored without the local SLAM's lines). Over these seven runs:
  // detected 6, recovered 6 (3 before; run 1 is never found kidnapped and
  // waits idle). The floors keep today's rates from dropping. Since the
  // cleaning's boxed_in_corners (2026-12-05): 45 of 48, and 5 of these seven
  // (run 16 again never found kidnapped: it plans through a gap it used to
  // give up, and waits idle where the kidnap put it). Since escapes face away
  // from the contact, not from a wall behind (2026-12-05): 48 of 48, every run
  // detected and back within 10 cm, and 7 of these seven. Since the edge pass at
  // 2 cm (2026-12-07): 48 of 48 recovered, but run 46 reported object 1 moved and
  // its lines left the map (seeds 40-135: one corrupted of 96 with the edge pass
  // at 5 cm too, run 52); since saved lines go back to the commit when
  // relocalising again, 0 of 96 (docs/relocalization.md); 7 of these seven.
  if (std::getenv("RELOC_KIDNAP_RUNS") || std::getenv("RELOC_KIDNAP_RUN")) return;
  EXPECT_GE(c.detected, 6);
  EXPECT_GE(c.recovered, 6);
}

// fig19 is a square room whose four boxes nearly map onto each other under a
// quarter turn. From the map of seed 101, starts 181 and 190 (runs 79 and 88)
// committed 90 degrees off 6-7 s after the start, on 2-3 m of evidence: two
// box faces had been saved with the wrong side (the side a line was seen from
// was voted by trajectory points up to 2 m away, most of them beyond the box),
// so the truth explained less than the quarter turn. With side_range_m 1 every
// one of these 90 starts commits right (and min_evidence_m 3 alone also kept
// these two from committing wrong). docs/relocalization.md, "The side a line
// was seen from".
TEST(RelocTest, ANearlySymmetricRoomIsNotCommittedOnTheFirstCornerSeen) {
  metrics::RelocOptions ro;
  ro.runs = 90;
  ro.seed = 101;
  const sim::World world = testing::LoadTestWorld("fig19");
  const auto count = [&](const robot::CoreOptions& options) {
    const metrics::RelocWorld w = metrics::EvaluateRelocalization(world, options, ro);
    EXPECT_TRUE(w.map_done);
    int wrong = 0, correct = 0;
    for (const auto& r : w.runs) {
      wrong += r.confidently_wrong;
      correct += r.correct;
    }
    std::printf("side_range_m %.1f, min_evidence_m %.1f: correct %d, confidently wrong %d of %zu\n",
                options.mission.relocalize.search.side_range_m, options.mission.relocalize.search.min_evidence_m,
                correct, wrong, w.runs.size());
    return std::make_pair(correct, wrong);
  };
  const auto [correct, wrong] = count(robot::DefaultCoreOptions());
  // Measured 2026-12-06: 90 correct (85 with the sides voted from 2 m).
  EXPECT_EQ(wrong, 0);
  EXPECT_GE(correct, 88);
  robot::CoreOptions before = robot::DefaultCoreOptions();
  before.mission.relocalize.search.side_range_m = 2.0;
  before.mission.relocalize.search.min_evidence_m = 2.0;
  EXPECT_GE(count(before).second, 1) << "these starts no longer commit wrong as before: this test no longer tests it";
}

// fig20's first mission saves the wall at the start in two pieces 1 cm apart
// (section 4.5 merges only overlapping lines); cleaning sees it whole and
// merges them. The wall keeps both ids (LineFeature::merged): before, every
// kidnap run here lost the second one (16 of 16, seeds 40-55; all 16 now keep
// every id and recover).
TEST(RelocTest, KidnappedInASquareRoomKeepsTheIdsOfAWallSavedInPieces) {
  const KidnapCount c = RunKidnaps(testing::LoadTestWorld("fig20"), {0, 1, 2});
  EXPECT_EQ(c.detected, 3);
  EXPECT_EQ(c.recovered, 3);
}

// The moved-furniture measurement's fixed-seed subset (irslam-report --reloc 20
// --reloc-worlds fig14,fig16,fig20 --reloc-move 0.5; docs/relocalization.md
// "Moved furniture"): 20 runs each (seeds 2-21), one piece moved 0.5 m
// (fig16's two desks each move whole), then a whole cleaning in the saved map.
// Measured 20, 18 and 16 of 20 models updated (2026-12-05, late, since the cleaning
// counts failures from one spot once, cleaning.no_plan_spot_m: fig20 17 before;
// over the 90-run measurement 82 -> 81 of 90, docs/cleaning.md; earlier 20, 18
// and 19; 2026-12-05: 18, 18 and 17
// before a side stretched past its complete object's box counted as a move on
// its own, fig20 15/20 before
// a wall-contact piece's contour could start beside a side's end, fig16 16/20
// and fig20 16/20 before a side stretched between its corners counted as not
// where it was; the first 10
// seeds: 3/30 before the IR check's probation, 15/30 before its rays were
// attributed to the saved objects, 22/30 before a piece found moved by the
// side check was noted with its saved size and a given-up piece of that size
// was renamed, 24/30 before that check ended the IR check's probation on the
// piece); the floor keeps the rate from dropping. No run may commit wrong (one
// did, fig20 seed 20, before a crossing of a furniture side counted less than
// one of a wall); one fig16 run (seed 11) does not relocalise within 180 s and
// explores afresh, as designed. Since the eq. (8) threshold 12 (2026-12-06):
// correct 56 of 60, 20, 16 and 18 models updated (fig16's maps have more
// desk sides; seeds 12, 17 and 21 explore afresh too); over the 90-run
// measurement 84 of 90 updated (81 before) and 86 correct (89), with the maps
// of seed 101 85 updated (78 before), 87 correct (87) and none wrong (one
// before): docs/relocalization.md. Since side_range_m 1 (the same day): 20, 19
// and 18 updated; over the 90 runs 86 updated, 89 correct.
TEST(RelocTest, FurnitureMovedHalfAMetreIsFoundMovedAndModelledAtItsNewPlace) {
  metrics::RelocOptions ro;
  ro.runs = 20;
  ro.move_m = 0.5;
  ro.max_time_s = 1500;
  const robot::CoreOptions options = robot::DefaultCoreOptions();
  int updated = 0, correct = 0, runs = 0;
  for (const char* name : {"fig14", "fig16", "fig20"}) {
    const metrics::RelocWorld w = metrics::EvaluateRelocalization(testing::LoadTestWorld(name), options, ro);
    ASSERT_TRUE(w.map_done) << name;
    int here = 0;
    for (const auto& r : w.runs) {
      EXPECT_FALSE(r.confidently_wrong) << name << " seed " << r.seed;
      EXPECT_GE(r.moved.world_index, 0) << name << " seed " << r.seed;
      correct += r.correct;
      ++runs;
      here += r.moved.updated;
      // An updated model is noted as moved: the piece kept its id.
      if (r.moved.updated) {
        EXPECT_TRUE(r.moved.noted) << name << " seed " << r.seed;
      }
    }
    std::printf("%s: model updated in %d of %zu runs\n", name, here, w.runs.size());
    updated += here;
  }
  EXPECT_EQ(runs, 60);
  EXPECT_GE(correct, 56);
  EXPECT_GE(updated, 54);
}

TEST(RelocTest, FurnitureMovedHalfAMetreIsDetectedAndKeepsItsId) {
  if (!std::getenv("RELOC_DEBUG")) GTEST_SKIP() << "an experiment (docs/relocalization.md)";
  const sim::World world = testing::LoadTestWorld(std::getenv("RELOC_WORLD") ? std::getenv("RELOC_WORLD") : "fig14");
  const Made made = MakeMap(world, 1);
  for (const auto& o : world.objects)
    std::printf("world object [%.2f %.2f %.2f %.2f]\n", o.xmin, o.ymin, o.xmax, o.ymax);
  for (const auto& o : made.map.objects)
    std::printf("map object %d [%.2f %.2f %.2f %.2f] %s\n", o.id, o.box.xmin, o.box.ymin, o.box.xmax, o.box.ymax,
                control::ToString(o.kind));
  const int which = std::getenv("RELOC_MOVE") ? std::atoi(std::getenv("RELOC_MOVE")) : 0;
  const double dx = std::getenv("RELOC_DX") ? std::atof(std::getenv("RELOC_DX")) : 0.5;
  const double dy = std::getenv("RELOC_DY") ? std::atof(std::getenv("RELOC_DY")) : 0.0;
  sim::World moved = world;
  moved.objects[static_cast<size_t>(which)].xmin += dx;
  moved.objects[static_cast<size_t>(which)].xmax += dx;
  moved.objects[static_cast<size_t>(which)].ymin += dy;
  moved.objects[static_cast<size_t>(which)].ymax += dy;
  std::mt19937_64 rng(5);
  for (int i = 0; i < 3; ++i) {
    const Pose2 start = RandomFreePose(moved, &rng);
    const RelocResult r = Relocalise(moved, made, start, 30 + i, 1500, true);
    std::printf("moved run %d: committed %d err %.3f attempts %d, end %s (%s)\n", i, r.committed, r.err_at_commit_m, r.attempts,
                control::ToString(r.end), r.reason.c_str());
    for (const auto& o : r.map.objects)
      std::printf("  object %d [%.2f %.2f %.2f %.2f] %s %s\n", o.id, o.box.xmin, o.box.ymin, o.box.xmax, o.box.ymax,
                  o.complete ? "complete" : "incomplete", o.note.c_str());
  }
}

}  // namespace
}  // namespace irslam
namespace irslam {
TEST(RelocDebug, Sweep) {
  const char* worlds = std::getenv("RELOC_WORLDS");
  if (!worlds) GTEST_SKIP();
  const int runs = std::atoi(std::getenv("RELOC_RUNS") ? std::getenv("RELOC_RUNS") : "10");
  std::string list = worlds;
  size_t pos = 0;
  while (pos <= list.size()) {
    const size_t end = std::min(list.find(',', pos), list.size());
    const std::string name = list.substr(pos, end - pos);
    pos = end + 1;
    const sim::World world = testing::LoadTestWorld(name);
    const Made made = MakeMap(world, 1);
    std::mt19937_64 rng(99);
    int right = 0, wrong = 0, none = 0;
    std::vector<double> times;
    double worst_after = 0, worst_after_deg = 0;
    for (int i = 0; i < runs; ++i) {
      const Pose2 start = RandomFreePose(world, &rng);
      const RelocResult r = Relocalise(world, made, start, 100 + i, 1500, true);
      if (!r.committed) { ++none; std::printf("  %s run %d: no commit (%s)\n", name.c_str(), i, r.reason.c_str()); continue; }
      if (r.err_at_commit_m > 0.2 || r.err_at_commit_rad > 10 * M_PI / 180) {
        ++wrong;
        std::printf("  %s run %d: WRONG %.2f m %.1f deg attempts %d end %s\n", name.c_str(), i, r.err_at_commit_m,
                    r.err_at_commit_rad * 180 / M_PI, r.attempts, r.reason.c_str());
        continue;
      }
      ++right;
      times.push_back(r.commit_t);
      worst_after = std::max(worst_after, r.max_err_after_m);
      worst_after_deg = std::max(worst_after_deg, r.max_err_after_rad * 180 / M_PI);
      if (r.attempts > 1 || r.end != control::MissionState::kDone)
        std::printf("  %s run %d: attempts %d end %s (%s)\n", name.c_str(), i, r.attempts, control::ToString(r.end), r.reason.c_str());
    }
    std::sort(times.begin(), times.end());
    std::printf("%s: right %d wrong %d none %d; t median %.1f max %.1f; worst after %.3f m %.2f deg\n", name.c_str(),
                right, wrong, none, times.empty() ? 0 : times[times.size() / 2], times.empty() ? 0 : times.back(),
                worst_after, worst_after_deg);
  }
}

}  // namespace irslam
