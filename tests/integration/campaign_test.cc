// A fixed subset of the robustness campaign (docs/robustness.md): generated
// worlds of all three noise profiles through the whole mission, with the rates
// asserted. The targets of issue 11 are not met yet (docs/robustness.md has the
// numbers); these floors are today's measured rates on these seeds, so a change
// that makes the distribution worse fails here even when the paper worlds pass.
#include <gtest/gtest.h>

#include <cstdio>

#include "robot/robot_core.h"
#include "sim/sim_run.h"
#include "tests/testing/slam_noise.h"
#include "tests/tools/campaign.h"
#include "tests/tools/metrics.h"

namespace irslam::campaign {
namespace {

struct Floor {
  sim::NoiseProfile profile;
  double done, pieces_good, pose_ok, lost_at_most;
  double ratio_within;  // wheel radius ratio estimated within 0.1 % after the first loop
};

class CampaignSubsetTest : public ::testing::TestWithParam<Floor> {};

TEST_P(CampaignSubsetTest, RatesDoNotDropBelowTodays) {
  const Floor f = GetParam();
  // Seeds 1-12 of each profile, both cores, the shipped options (the odometry
  // self-calibration on: before 2026-12-07 it was set here, off in the shipped
  // options).
  const robot::CoreOptions options = robot::DefaultCoreOptions();
  const auto runs = RunCampaign(f.profile, 1, 12, options, 2);
  const Rates r = Summarise(runs);
  EXPECT_EQ(r.runs, 12);
  std::printf(
      "%s: done %.3f, pieces good %.3f, complete %.3f, pose ok %.3f, lost %.3f, contacts/run %.2f, "
      "ratio within 0.1 %% %.3f\n",
      sim::ToString(f.profile), r.done, r.pieces_good, r.pieces_complete, r.pose_ok, r.lost,
      r.furniture_contacts_per_run, r.ratio_within);
  EXPECT_GE(r.done, f.done - 1e-9) << sim::ToString(f.profile);
  EXPECT_GE(r.pieces_good, f.pieces_good - 1e-9) << sim::ToString(f.profile);
  EXPECT_GE(r.pose_ok, f.pose_ok - 1e-9) << sim::ToString(f.profile);
  EXPECT_LE(r.lost, f.lost_at_most + 1e-9) << sim::ToString(f.profile);
  EXPECT_GE(r.ratio_within, f.ratio_within - 1e-9) << sim::ToString(f.profile);
  // Every run is scored and classified: a failing run names at least one class.
  for (const auto& s : runs) {
    EXPECT_EQ(s.failures.empty(), s.done && s.good == s.pieces && s.complete == s.good &&
                                      s.max_position_m <= 0.20 && s.contacts_furniture == 0)
        << s.world;
  }
}

INSTANTIATE_TEST_SUITE_P(Profiles, CampaignSubsetTest,
                         // Measured 2026-12-02 on seeds 1-12 (done, pieces good, pose ok, lost), with
                         // the odometry self-calibration: nominal 12/12, 0.636, 7/12, 1/12; realistic
                         // 6/12, 0.091, 1/12, 12/12; harsh 2/12, 0, 0, 12/12 (before it: nominal 10/12,
                         // 0.576, 5/12, 4/12; realistic 5/12, 0, 0, 12/12; harsh 1/12, 0, 0, 12/12).
                         // Ratio within 0.1 % after the first loop: 12/12, 4/12, 2/12.
                         // 2026-12-03, with the loop detector's orbit check: nominal 12/12, 0.742,
                         // 7/12, 1/12; realistic 7/12, 0.129, 1/12, 12/12; harsh 3/12, 0, 0, 12/12;
                         // ratio 12/12, 3/12, 2/12 (realistic one run lower here; over 300 realistic
                         // worlds with the calibration on it went 22.3 -> 23.7 %, docs/robustness.md).
                         // 2026-12-05, loops closing at any anchor: nominal 12/12, 0.742, 7/12, 1/12;
                         // realistic 9/12, 0.129, 1/12, 12/12; harsh 7/12, 0, 0, 12/12; ratio 12/12,
                         // 3/12, 1/12: a harsh run whose loop never closed was scored at the time limit,
                         // and is now scored when its loop closes, earlier, with less to estimate from
                         // (over 100 worlds per profile with the calibration on, the ratio row went
                         // 24 -> 26 % realistic, 7 -> 8 % harsh: docs/robustness.md).
                         // 2026-12-06, the eq. (8) threshold 4.5 -> 12 (slam.extraction.max_uncertainty):
                         // nominal 12/12, 0.806, 5/12, 0/12; realistic 10/12, 0.226, 0/12, 10/12; harsh
                         // 4/12, 0, 0, 12/12; ratio 12/12, 2/12, 3/12. A trade, measured over 100 worlds
                         // per profile with the calibration on (docs/error-budget.md): pieces good 73.2 ->
                         // 76.8 / 19.6 -> 35.3 / 3.6 -> 5.8 %, lost 8 -> 15 / 97 -> 86 / 99 -> 99 %, pose ok
                         // 42 -> 35 / 5 -> 7 / 0 -> 1 %, done 95 -> 98 / 82 -> 84 / 56 -> 45 %; with the
                         // calibration off (the shipped options, 200 worlds) nominal pose ok 53.5 % both.
                         // 2026-12-06, model.wall_contact_m 0.15 -> 0.30 and the last side of a wall-contact
                         // object inferred along the wall: nominal 12/12, 0.806, 4/12, 0/12,
                         // complete 0.710. Over 100 worlds with the calibration on:
                         // complete 55.8 -> 63.8 %, pose ok 35 -> 32 %, lost 15 % both; with it off (the
                         // shipped options, seeds 1-400) pose ok 107 -> 107 and 120 -> 119 of 200.
                         // 2026-12-07, the SLAM trusts the odometry more (calibration on, eq. (7) x 4,
                         // motion noise x 0.25: docs/error-budget.md): nominal 12/12, 0.903, 11/12,
                         // 0/12, complete 0.774; realistic 11/12, 0.129, 1/12, 11/12, ratio 1/12 (these
                         // 12 lose pieces; over 200 realistic worlds pieces good 24.5 -> 27.0 %, ratio
                         // within 0.1 % 17.0 %, 9.5 % with it off: docs/robustness.md); harsh 4/12, 0, 0,
                         // 12/12.
                         // Raise these as the robustness work lands.
                         ::testing::Values(Floor{sim::NoiseProfile::kNominal, 12 / 12.0, 0.88, 10 / 12.0, 1 / 12.0, 12 / 12.0},
                                           Floor{sim::NoiseProfile::kRealistic, 10 / 12.0, 0.12, 0.0, 1.0, 1 / 12.0},
                                           Floor{sim::NoiseProfile::kHarsh, 4 / 12.0, 0.0, 0.0, 1.0, 1 / 12.0}),
                         [](const ::testing::TestParamInfo<Floor>& p) { return std::string(sim::ToString(p.param.profile)); });

// Generated nominal rooms with a free piece 0.4-0.7 m from a wall (docs/error-budget.md,
// "A free piece's side facing a near wall inferred"): the contour follower meets the
// wall in the gap and follows it away, and the side facing the wall is never mapped.
// With model.narrow_gap_m it is inferred; without, the contour times out after 150 s.
TEST(CampaignMechanismTest, AFreePiecesSideFacingANearWallIsInferred) {
  const std::vector<uint64_t> seeds = {17, 40, 45, 62, 66};
  const auto run = [&](double narrow_gap_m, int* complete, double* time_s) {
    robot::CoreOptions o = robot::DefaultCoreOptions();
    o.model.narrow_gap_m = narrow_gap_m;
    *complete = 0;
    *time_s = 0;
    for (const uint64_t seed : seeds) {
      const RunScore s = RunAndScore(seed, sim::NoiseProfile::kNominal, o, o.mission.max_time_s);
      std::printf("narrow_gap_m %.1f, nominal/%llu: %s, pieces %d, good %d, complete %d, %.0f s\n", narrow_gap_m,
                  static_cast<unsigned long long>(seed), s.end_state.c_str(), s.pieces, s.good, s.complete,
                  s.robot_time_s);
      EXPECT_TRUE(s.done) << seed;
      *complete += s.complete;
      *time_s += s.robot_time_s;
    }
  };
  int with = 0, without = 0;
  double with_s = 0, without_s = 0;
  run(0.9, &with, &with_s);
  run(0.0, &without, &without_s);
  // Measured 2026-12-06: all 7 pieces found and complete in 1213 s of robot time with it;
  // 2 complete in 1743 s without.
  EXPECT_GE(with, 7);
  EXPECT_LE(without, 3) << "the pieces complete without it: this test no longer tests it";
  EXPECT_LT(with_s, without_s - 300);
}

// Generated nominal rooms where a free piece's contour is drawn off before it
// closes (docs/error-budget.md, "A free piece's side the contour went past
// inferred"): the robot goes round three sides and past the fourth, meets a
// wall or another piece and follows it away. Contour following, leaving the
// piece, asks the model to infer the side its own trace went past
// (ContourFollow::Step, Modeler::CloseAlongWall); without that the piece stays
// incomplete until the contour times out.
TEST(CampaignMechanismTest, AFreePiecesSideItsContourWentPastIsInferred) {
  // Found by running seeds 1-125 with --map-out (2026-12-07, the SLAM trusting
  // the odometry more; 26, 49 and 58 of the first set no longer leave such a
  // piece, 102 leaves one against a wall).
  const std::vector<uint64_t> seeds = {33, 52, 65, 107, 120};
  const robot::CoreOptions o = robot::DefaultCoreOptions();
  int inferred = 0;
  for (const uint64_t seed : seeds) {
    const sim::World world = sim::GenerateWorld(seed, sim::NoiseProfile::kNominal);
    const sim::InProcessRun run = sim::RunInProcess(world, o, seed, o.mission.max_time_s);
    EXPECT_EQ(run.core->state(), control::MissionState::kDone) << seed;
    for (const auto& obj : run.core->Map().objects) {
      if (obj.note.find("one side inferred from the contour that went past it") == std::string::npos) continue;
      std::printf("nominal/%llu: object %d [%.2f %.2f %.2f %.2f] %s\n", static_cast<unsigned long long>(seed),
                  obj.id, obj.box.xmin, obj.box.ymin, obj.box.xmax, obj.box.ymax, obj.note.c_str());
      EXPECT_TRUE(obj.complete) << seed;
      EXPECT_EQ(obj.kind, control::ObjectKind::kFree) << seed;
      ++inferred;
    }
  }
  // Measured 2026-12-07: one such piece in each of the five rooms (both sets).
  EXPECT_GE(inferred, 4);
}

// slam.association.associate_in_robot_frame (docs/error-budget.md): generated
// realistic room 11 with only its correlated slip (every other effect nominal).
// Followed along its walls, the robot's heading drifts by several degrees per
// metre; 5 m from the map's origin that moves a wall's map-frame rho by a few
// decimetres, so the paper's eq. (13) in the map frame stops matching the wall
// being followed and inserts it again and again (merged later), while taken as
// the robot sees the line it keeps matching and updating.
TEST(AssociationFrameTest, TheFollowedWallKeepsMatchingInTheRobotFrameAfterSlip) {
  sim::World world = sim::GenerateWorld(11, sim::NoiseProfile::kRealistic);
  std::string error;
  ASSERT_TRUE(metrics::SetNoiseNominal("wheel_radius_error_left,wheel_radius_error_right,wheel_base_error,"
                                       "ir_voltage_sigma_rel,ir_surface_bias_m,ir_max_incidence_deg,ir_outlier_rate",
                                       &world.noise, &error))
      << error;
  ASSERT_GT(world.noise.slip_correlation_s, 0.0);
  const auto stats = [&](bool robot_frame) {
    robot::CoreOptions options = robot::DefaultCoreOptions();
    options.slam.association.associate_in_robot_frame = robot_frame;
    // The eq. (8) threshold it was traced with (before 2026-12-06): with today's
    // 12 the map-frame run inserts fewer pieces in these 80 s (16 insertions,
    // 20 updates) and the defect shows later.
    options.slam.extraction.max_uncertainty = 4.5;
    const sim::InProcessRun run = sim::RunInProcess(world, options, 11, 80.0);
    return run.core->slam().stats();
  };
  const slam::SlamStats map_frame = stats(false), robot_frame = stats(true);
  std::printf("map frame: %d updates, %d insertions; robot frame: %d updates, %d insertions\n", map_frame.updates,
              map_frame.insertions, robot_frame.updates, robot_frame.insertions);
  EXPECT_GE(robot_frame.updates, 2 * map_frame.updates);
  EXPECT_LT(robot_frame.insertions, map_frame.insertions);
  EXPECT_GE(map_frame.insertions, map_frame.updates + 10);  // the defect it shows
}

// The room's-frame error (docs/error-budget.md) tells a map turned as a whole
// from one bent inside: nominal room 132 is "lost" by 26 cm in the world frame
// but within 5 cm once its map is aligned to the true walls; room 49's map is
// wrong inside (about 1.9 m either way). With the eq. (8) threshold these runs
// were found with (before 2026-12-06): with today's 12, room 49's map is no
// longer bent (21 cm in either frame) and 132's is turned less cleanly.
TEST(RoomFrameErrorTest, AMapTurnedAsAWholeIsNotLostInTheRoomsFrameABentOneIs) {
  robot::CoreOptions options = robot::DefaultCoreOptions();
  options.slam.extraction.max_uncertainty = 4.5;
  // And the SLAM's noise then (before 2026-12-07): with today's, room 132's map
  // is not turned (16 cm at most in either frame) and 49's is not bent.
  testing::UseSlamNoiseBefore20261207(&options.slam);
  const RunScore turned = RunAndScore(132, sim::NoiseProfile::kNominal, options, options.mission.max_time_s);
  EXPECT_GT(turned.max_position_m, 0.20);
  EXPECT_LT(turned.room_max_position_m, 0.08);
  const RunScore bent = RunAndScore(49, sim::NoiseProfile::kNominal, options, options.mission.max_time_s);
  EXPECT_GT(bent.room_max_position_m, 1.0);
  EXPECT_GT(bent.room_max_position_m, 0.8 * bent.max_position_m);
}

// The report's worst periods are measured again one run at a time: only the
// runs with the largest period in the campaign and those over a bound, and the report lists them by
// that second measurement with the campaign's beside it.
TEST(RemeasureWorstPeriodsTest, RunsTheLargestAgainAloneAndReportsBoth) {
  const robot::CoreOptions options = robot::DefaultCoreOptions();
  std::vector<RunScore> runs(3);
  const double campaign_ms[] = {0.5, 100.2, 3.0};  // seed 2: a period charged by the host
  for (size_t i = 0; i < runs.size(); ++i) {
    runs[i].seed = 1 + i;
    runs[i].profile = sim::NoiseProfile::kNominal;
    runs[i].world = "gen-nominal-" + std::to_string(1 + i);
    runs[i].tick_max_ms = campaign_ms[i];
    runs[i].tick_phase = "planning";
  }
  RemeasureWorstPeriods(&runs, options, 1, 2.0);  // the largest, and seed 3 over 2 ms
  EXPECT_LT(runs[0].tick_max_alone_ms, 0);  // neither the largest nor over 2 ms: not re-run
  for (size_t i = 1; i < runs.size(); ++i) {
    EXPECT_GT(runs[i].tick_max_alone_ms, 0);
    EXPECT_FALSE(runs[i].tick_phase_alone.empty());
    EXPECT_DOUBLE_EQ(runs[i].tick_max_ms, campaign_ms[i]);  // the campaign's kept beside
  }
  const std::string md = RobustnessReport({runs}, ::testing::TempDir(), "irslam-report --campaign 3");
  EXPECT_NE(md.find("| 100.200 | "), std::string::npos);
  EXPECT_NE(md.find("| not re-run | 0.500 |"), std::string::npos);
}

}  // namespace
}  // namespace irslam::campaign
