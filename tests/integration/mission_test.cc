// The whole mission in process (wall following, modelling, go to P1, contour
// following, survey) on the paper's worlds and on the robustness cases.
#include <gtest/gtest.h>

#include <algorithm>
#include <map>

#include "daemon/core_json.h"
#include "robot/robot_core.h"
#include "sim/generator.h"
#include "sim/sim_run.h"
#include "tests/testing/slam_noise.h"
#include "tests/testing/worlds.h"
#include "tests/tools/metrics.h"

namespace irslam {
namespace {

sim::World Load(const std::string& name) { return testing::LoadTestWorld(name); }

// Robot-time limit: the paper's Fig. 14 run took 340 s; ours take 180-500 s
// (docs/accuracy.md), so 900 s leaves room without letting a wandering robot pass.
constexpr double kLimitS = 900;

class PaperWorldTest : public ::testing::TestWithParam<std::string> {};

TEST_P(PaperWorldTest, ReachesDoneFindingAndClassifyingEveryPieceWithoutTouchingAnything) {
  const sim::World world = Load(GetParam());
  for (uint64_t seed : {1, 2}) {
    sim::InProcessRun run = sim::RunInProcess(world, robot::DefaultCoreOptions(), seed, kLimitS);
    EXPECT_EQ(run.core->state(), control::MissionState::kDone) << "seed " << seed;
    EXPECT_LT(run.t, kLimitS);
    EXPECT_EQ(run.sim->collisions(), 0u) << "seed " << seed;
    const auto sc = metrics::ScoreObjects(ToJson(run.core->Map()), run.core->slam(), world, 0);
    EXPECT_EQ(sc.found, sc.pieces) << "seed " << seed;
    EXPECT_EQ(sc.kind_right, sc.pieces) << "seed " << seed;
    EXPECT_EQ(sc.complete, sc.pieces) << "seed " << seed;
    EXPECT_EQ(sc.extra, 0) << "seed " << seed;
    // Box edges within 5 cm (over 20 seeds per world, 77 of 80 runs; the worst,
    // 12 cm, a compound piece whose taller box's top was never mapped:
    // docs/accuracy.md).
    EXPECT_LE(sc.max_edge_m, 0.05) << "seed " << seed;
    // The map's objects all carry the contract's fields.
    const nlohmann::json map = ToJson(run.core->Map());
    for (const auto& o : map["objects"]) {
      EXPECT_TRUE(o["kind"] == "free" || o["kind"] == "wall_contact");
      EXPECT_EQ(o["box"].size(), 4u);
      EXPECT_TRUE(o["complete"].is_boolean());
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Worlds, PaperWorldTest, ::testing::Values("fig14", "fig16", "fig19", "fig20"));

TEST(RobustnessTest, ObjectTooCloseToAWallIsNotClaimedAsACompleteFreeObject) {
  const sim::World world = Load("too_close");
  sim::InProcessRun run = sim::RunInProcess(world, robot::DefaultCoreOptions(), 1, kLimitS);
  EXPECT_EQ(run.core->state(), control::MissionState::kDone);
  EXPECT_EQ(run.sim->collisions(), 0u);
  // The box 0.25 m from the top wall (narrower than the robot) is modelled as
  // wall-contact or left incomplete, never as a complete free object.
  const auto map = ToJson(run.core->Map());
  const double rot = run.core->slam().map_rotation();
  bool seen = false;
  for (const auto& o : map["objects"]) {
    // Map -> world through the start pose: the box centre.
    const double mx = 0.5 * (o["box"][0].get<double>() + o["box"][2].get<double>());
    const double my = 0.5 * (o["box"][1].get<double>() + o["box"][3].get<double>());
    const Pose2 w = Compose(world.start, {std::cos(-rot) * mx - std::sin(-rot) * my,
                                          std::sin(-rot) * mx + std::cos(-rot) * my, 0});
    if (w.y > 2.8) {
      seen = true;
      EXPECT_TRUE(o["kind"] == "wall_contact" || !o["complete"].get<bool>()) << o.dump();
    }
  }
  EXPECT_TRUE(seen);
}

TEST(RobustnessTest, StartFacingACornerOrBesideAFreeObjectStillFinishes) {
  for (const char* name : {"corner_start", "free_start"}) {
    const sim::World world = Load(name);
    sim::InProcessRun run = sim::RunInProcess(world, robot::DefaultCoreOptions(), 1, kLimitS);
    EXPECT_EQ(run.core->state(), control::MissionState::kDone) << name;
    // A box corner between two front beams is found by the bumper at most once.
    EXPECT_LE(run.sim->collisions(), 1u) << name;
    const auto sc = metrics::ScoreObjects(ToJson(run.core->Map()), run.core->slam(), world, 0);
    EXPECT_EQ(sc.found, sc.pieces) << name;
    EXPECT_EQ(sc.complete, sc.pieces) << name;
  }
}

TEST(RobustnessTest, ChairLegsNeitherTrapTheRobotNorBecomeFurniture) {
  const sim::World world = Load("chair_legs");
  sim::InProcessRun run = sim::RunInProcess(world, robot::DefaultCoreOptions(), 1, kLimitS);
  EXPECT_EQ(run.core->state(), control::MissionState::kDone);
  // The 4 cm legs are invisible to most beams: the bumper finds them, the robot
  // backs off and carries on, and never drives into the same leg again (the bump
  // is remembered and seen by the beams from then on).
  EXPECT_LE(run.sim->collisions(), 2u);
  std::map<size_t, int> hits;  // per object of the world: contacts
  for (const auto& c : run.sim->collision_points()) {
    size_t nearest = 0;
    double best = 1e9;
    for (size_t i = 0; i < world.objects.size(); ++i) {
      const auto& o = world.objects[i];
      const double dx = std::max({o.xmin - c[1], 0.0, c[1] - o.xmax});
      const double dy = std::max({o.ymin - c[2], 0.0, c[2] - o.ymax});
      if (std::hypot(dx, dy) < best) {
        best = std::hypot(dx, dy);
        nearest = i;
      }
    }
    ++hits[nearest];
  }
  for (const auto& [object, n] : hits) EXPECT_EQ(n, 1) << "object " << object << " was hit " << n << " times";
  // No object is made of the legs (each is far shorter than the 0.3 m minimum line).
  const auto map = ToJson(run.core->Map());
  for (const auto& o : map["objects"]) {
    const double w = o["box"][2].get<double>() - o["box"][0].get<double>();
    const double h = o["box"][3].get<double>() - o["box"][1].get<double>();
    EXPECT_GT(std::max(w, h), 0.3) << o.dump();
  }
}

}  // namespace
}  // namespace irslam

namespace irslam {
namespace {

// The whole mission with the controller's frames lost, duplicated, reordered,
// delayed and corrupted, an encoder count that jumps and stays, a stuck IR sensor
// and short bursts of loss (docs/reliability.md): bad data is counted by reason,
// none of it reaches SLAM, and the mission still ends done with every piece found.
TEST(FaultRunTest, MissionEndsDoneThroughLossCorruptionReorderingAndGlitches) {
  std::string error;
  const auto faults = sim::ParseFaultSpec(
      "loss:p=0.03,duplicate:p=0.03,reorder:p=0.03,delay:p=0.03:max=0.03,corrupt:p=0.005,"
      "encoder_glitch:at=60:counts=3000,stuck_ir:sensor=6:at=30:for=30,burst:every=20:len=0.05",
      &error);
  ASSERT_TRUE(faults) << error;
  const sim::World world = testing::LoadTestWorld("fig14");
  for (uint64_t seed : {1, 2}) {
    sim::InProcessRun run =
        sim::RunInProcess(world, robot::DefaultCoreOptions(), seed, kLimitS, nullptr, &*faults);
    EXPECT_EQ(run.core->state(), control::MissionState::kDone) << "seed " << seed;
    EXPECT_EQ(run.sim->collisions(), 0u) << "seed " << seed;
    const auto sc = metrics::ScoreObjects(ToJson(run.core->Map()), run.core->slam(), world, 0);
    EXPECT_EQ(sc.found, sc.pieces) << "seed " << seed;
    EXPECT_EQ(sc.kind_right, sc.pieces) << "seed " << seed;
    EXPECT_EQ(sc.complete, sc.pieces) << "seed " << seed;
    EXPECT_LE(sc.max_edge_m, 0.06) << "seed " << seed;
    const nlohmann::json status = ToJson(run.core->Status(run.t));
    const auto& f = status["frames"];
    const auto& injected = run.faults->counters();
    EXPECT_GT(injected.duplicated, 500u);
    EXPECT_GT(f["duplicate"].get<uint64_t>(), 500u) << f;
    EXPECT_GT(f["stale"].get<uint64_t>(), 500u) << f;
    EXPECT_GE(f["implausible_counts"].get<uint64_t>(), 3u) << f;  // the lasting glitch, at least
    EXPECT_GT(f["implausible_time"].get<uint64_t>(), 0u) << f;
    EXPECT_GT(f["ir_stuck"].get<uint64_t>(), 300u) << f;
    EXPECT_GT(f["seq_gap_encoder"].get<uint64_t>(), 500u) << f;
  }
}

}  // namespace
}  // namespace irslam

namespace irslam {
namespace {

// Under 5 % frame loss (seed 4) the wall-following loop passes the top-right
// box of Fig. 14 without mapping it, and the look from the room's middle is too
// far from it: a later survey, from where most of the room was never within
// range, finds it, and it is completed like the others. (With the eq. (8)
// threshold before 2026-12-06, slam.extraction.max_uncertainty 4.5: with
// today's 12 the wall-following loop maps that box itself, and one survey is
// enough.)
TEST(FaultRunTest, ABoxTheWallFollowingLoopMissedIsFoundByALaterSurvey) {
  std::string error;
  const auto faults = sim::ParseFaultSpec("loss:p=0.05", &error);
  ASSERT_TRUE(faults) << error;
  const sim::World world = testing::LoadTestWorld("fig14");
  robot::CoreOptions options = robot::DefaultCoreOptions();
  options.slam.extraction.max_uncertainty = 4.5;
  testing::UseSlamNoiseBefore20261207(&options.slam);  // (and the SLAM's noise before 2026-12-07)
  sim::InProcessRun run = sim::RunInProcess(world, options, 4, 900, nullptr, &*faults);
  EXPECT_EQ(run.core->state(), control::MissionState::kDone);
  const auto sc = metrics::ScoreObjects(ToJson(run.core->Map()), run.core->slam(), world, 0);
  EXPECT_EQ(sc.found, sc.pieces);
  EXPECT_EQ(sc.complete, sc.pieces);
  // Only with the later surveys: without them the box is never seen.
  robot::CoreOptions one = options;
  one.explore.survey.max_surveys = 1;
  sim::InProcessRun once = sim::RunInProcess(world, one, 4, 900, nullptr, &*faults);
  EXPECT_EQ(metrics::ScoreObjects(ToJson(once.core->Map()), once.core->slam(), world, 0).found, sc.pieces - 1);
  // The shipped options: every piece found and completed, with one survey too.
  robot::CoreOptions shipped_once = robot::DefaultCoreOptions();
  shipped_once.explore.survey.max_surveys = 1;
  for (const robot::CoreOptions& o : {robot::DefaultCoreOptions(), shipped_once}) {
    sim::InProcessRun shipped = sim::RunInProcess(world, o, 4, 900, nullptr, &*faults);
    EXPECT_EQ(shipped.core->state(), control::MissionState::kDone);
    const auto ss = metrics::ScoreObjects(ToJson(shipped.core->Map()), shipped.core->slam(), world, 0);
    EXPECT_EQ(ss.found, ss.pieces);
    EXPECT_EQ(ss.complete, ss.pieces);
  }
}

// The campaign's scoring rules (tests/tools/metrics.h) on two generated worlds.
sim::World Furniture(uint64_t seed) {
  sim::World w = sim::GenerateWorld(seed, sim::NoiseProfile::kNominal);
  w.objects.erase(std::remove_if(w.objects.begin(), w.objects.end(),
                                 [](const sim::Box& b) {
                                   return std::min(b.xmax - b.xmin, b.ymax - b.ymin) <= 0.06;
                                 }),
                  w.objects.end());
  return w;
}

TEST(ScoringTest, APieceNearerAWallThanTheRobotCanPassMayBeModelledWallContact) {
  // Nominal seed 14: one piece 5.5 cm from the top wall, modelled wall-contact.
  const sim::World world = Furniture(14);
  ASSERT_EQ(world.objects.size(), 2u);
  EXPECT_NEAR(world.Bounds().ymax - world.objects[1].ymax, 0.055, 0.001);
  sim::InProcessRun run = sim::RunInProcess(world, robot::DefaultCoreOptions(), 14, kLimitS);
  const auto map = ToJson(run.core->Map());
  ASSERT_EQ(map["objects"].size(), 1u);
  EXPECT_EQ(map["objects"][0]["kind"], "wall_contact");
  const double diameter = 2 * robot::DefaultCoreOptions().slam.geometry.radius_m;
  const auto lenient = metrics::ScoreObjects(map, run.core->slam(), world, diameter);
  const auto strict = metrics::ScoreObjects(map, run.core->slam(), world, 0);
  EXPECT_EQ(lenient.pieces, 1);  // two touching boxes: one compound piece
  EXPECT_EQ(lenient.good, 1);
  EXPECT_EQ(strict.kind_right, 0);
  EXPECT_EQ(strict.good, 0);
}

TEST(ScoringTest, BoxesUnderTenCentimetresApartAreOnePiece) {
  // Nominal seed 11: a bed in a corner with its night table 2 cm beside it.
  const sim::World world = Furniture(11);
  int close_pairs = 0;
  for (size_t i = 0; i < world.objects.size(); ++i) {
    for (size_t k = i + 1; k < world.objects.size(); ++k) {
      const auto& a = world.objects[i];
      const auto& b = world.objects[k];
      const double gap = std::max(std::max(a.xmin - b.xmax, b.xmin - a.xmax), std::max(a.ymin - b.ymax, b.ymin - a.ymax));
      close_pairs += gap > 0.001 && gap < 0.10;
    }
  }
  ASSERT_EQ(close_pairs, 1);
  sim::InProcessRun run = sim::RunInProcess(world, robot::DefaultCoreOptions(), 11, kLimitS);
  const auto sc = metrics::ScoreObjects(ToJson(run.core->Map()), run.core->slam(), world, 0);
  // 7 boxes; by touching alone 5 pieces (docs/robustness.md before the rule),
  // with the bed and its night table one: 4.
  EXPECT_EQ(world.objects.size(), 7u);
  EXPECT_EQ(sc.pieces, 4);
}

}  // namespace
}  // namespace irslam
