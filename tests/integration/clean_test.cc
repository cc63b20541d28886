// Cleaning on the paper's worlds (issue 13), scored against the simulator's
// truth (tests/tools/clean_eval.h). The floors are the numbers reached today
// with a small margin (docs/cleaning.md); where they are below the issue's
// targets (coverage >= 97 % at nominal noise, path <= 1.25 x area / width plus
// transitions) the doc says so.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <iterator>

#include "daemon/core_json.h"
#include "robot/robot_core.h"
#include "sim/sim_run.h"
#include "sim/generator.h"
#include "tests/testing/slam_noise.h"
#include "tests/testing/worlds.h"
#include "tests/tools/clean_eval.h"

namespace irslam {
namespace {

struct Floor {
  const char* world;
  double min_coverage;    // truth: of the reachable floor, swept while cleaning
  double max_path_ratio;  // cleaning path / (reachable area / cleaning width)
  double max_rms_m;       // pose error while cleaning
  int max_cells_lost = 0; // cells given up (reported unreachable)
  double max_home_m = 0.10;  // the target: back within 10 cm of the start
  int max_contacts = 0;      // contacts while cleaning
};

class CleanWorldTest : public ::testing::TestWithParam<Floor> {};

TEST_P(CleanWorldTest, CleansTheReachableFloorAndReturnsHome) {
  const Floor f = GetParam();
  const sim::World world = testing::LoadTestWorld(f.world);
  const robot::CoreOptions o = robot::DefaultCoreOptions();
  const metrics::CleanScore s =
      metrics::RunAndScoreClean(world, o, 1, o.mission.max_time_s + o.mission.cleaning.max_time_s, false);
  EXPECT_EQ(s.end_state, "done") << s.reason;
  EXPECT_TRUE(s.cleaned);
  EXPECT_GE(s.cells_done, s.cells - f.max_cells_lost);
  EXPECT_GE(s.coverage, f.min_coverage);
  EXPECT_LE(s.path_ratio, f.max_path_ratio);
  EXPECT_LE(s.home_error_m, f.max_home_m);
  EXPECT_LE(s.rms_position_m, f.max_rms_m);
  EXPECT_LE(s.contacts_cleaning, f.max_contacts);
  EXPECT_LE(s.cross_track_rms_m, 0.03);
  // The robot's own estimate (of the floor it planned for, from its pose) reads
  // higher than the truth's, by the clearance strip and the pose error.
  EXPECT_GE(s.estimated_fraction, s.coverage);
  EXPECT_LE(s.estimated_fraction, s.coverage + 0.13);
}

INSTANTIATE_TEST_SUITE_P(PaperWorlds, CleanWorldTest,
                         // Measured (seed 1, default configuration, docs/cleaning.md): fig14
                         // 92.0 %, 1.68, 7.9 cm; fig20 91.3 %, 1.72, 2.4 cm; free_start 93.9 %,
                         // 1.51, 3.0 cm; corner_start 92.8 %, 1.47, 2.9 cm, all four cells
                         // (until 2026-12-03 85.0 %, 1.34 with one of four given up, and seed 3
                         // all four; since the go-to's side-beam fix the other way round: one
                         // seed's luck either way, docs/cleaning.md has the 40-run set; the
                         // path ratio with all four cells is 1.47 on seeds 1-3). fig16, fig18,
                         // fig19: one contact each, not asserted.
                         // Since cleaning.boxed_in_corners (2026-12-05): fig14 93.0 %, 9.4 cm;
                         // corner_start 92.5 %, 3.2 cm; fig17 89.1 %, 14.6 cm and back home
                         // 16.2 cm off (the SLAM's drift over that run; seeds 2 and 3: 7.0 and
                         // 4.6 cm; over the 24 paper-world runs 23 end within 10 cm,
                         // docs/cleaning.md).
                         // Since slam.extraction.max_uncertainty 12 (2026-12-06): fig14 92.9 %,
                         // 6.6 cm, but 2 contacts (seeds 1-10: 7 of 10 without one, 6 of 10
                         // before); fig20 4.1 cm (seeds 1-10: mean 2.85, 2.54 before);
                         // corner_start 93.3 %, 2.5 cm, all four cells, path ratio 1.56 (seeds
                         // 1-10: mean 1.50, 1.48 before). Over the 80 paper-world runs of seeds
                         // 1-10: 71 without a contact, 66 before (docs/cleaning.md).
                         // Since the SLAM trusts the odometry more (2026-12-07): fig20's path
                         // ratio 1.88 (1.72 before; over the 24 paper-world runs of seeds 1-3
                         // coverage 91.4 -> 92.1 %, pose RMS <= 5 cm in 24, 16 before).
                         // Since the edge pass 2 cm from the walls (2026-12-07): fig14 96.9 %,
                         // path ratio 1.75, no contact; fig20 95.0 %, 1.93; free_start 96.0 %,
                         // 1.57; corner_start 95.9 %, 1.58, all four cells; fig17 95.3 %
                         // (the 24 paper-world runs of seeds 1-3: 92.1 -> 94.6 %).
                         ::testing::Values(Floor{"fig14", 0.95, 1.80, 0.10, 0, 0.10, 2},
                                           Floor{"fig20", 0.93, 2.0, 0.045},
                                           Floor{"free_start", 0.94, 1.65, 0.04},
                                           Floor{"corner_start", 0.84, 1.65, 0.04, 1},
                                           // 90.4 %, 1.31, 11.4 cm, no contact (seeds 1-20: none);
                                           // the e2e test cleans it through the processes.
                                           Floor{"fig17", 0.93, 1.4, 0.16, 0, 0.17}),
                         [](const ::testing::TestParamInfo<Floor>& p) { return std::string(p.param.world); });

// The options the scenarios of the mechanism tests below were found with: the
// eq. (8) threshold before 2026-12-06 (slam.extraction.max_uncertainty 4.5),
// and the wall-contact distance before the same day (model.wall_contact_m 0.15,
// incomplete objects not merged: model.merge_touching_m 0).
// With today's 12 the exploration maps these rooms differently, and the gaps,
// pockets and lost anchors these tests show do not all form any more (their
// controls without the mechanism then clean as well: nothing would be tested);
// with 0.30, room 1070 is modelled with 14 cells instead of 5 (9 of the 18 cells
// of RoutePointsFailing... done, not 16); with the merge, APocket...'s control
// cleans as well as the mechanism.
// Also the SLAM's noise before 2026-12-07 (the odometry self-calibration off, the
// eq. (7) covariance as it is, four times today's motion noise: docs/error-budget.md,
// "Trusting the odometry more"): with today's, these rooms' poses hold better and
// the defects do not form where the tests look for them.
// And the edge pass as far from the walls as the lanes before 2026-12-07
// (cleaning.edge_clearance_m 0.05, docs/cleaning.md, "The edge pass 2 cm from the
// walls"): with 0.02 the plans differ, and the controls of GapsBetween...,
// APocket... and RoutePointsFailing... clean nearly as well as the mechanisms.
// The same seeds with the shipped options: TheMechanismSeedsCleanWithTheShippedOptions.
robot::CoreOptions ScenarioOptions() {
  robot::CoreOptions o = robot::DefaultCoreOptions();
  testing::UseSlamNoiseBefore20261207(&o.slam);
  o.mission.cleaning.edge_clearance_m = 0.05;
  o.slam.extraction.max_uncertainty = 4.5;
  o.model.wall_contact_m = 0.15;
  o.model.merge_touching_m = 0;
  o.model.narrow_gap_m = 0;
  return o;
}

// Cleans the clean campaign's generated world `seed` at nominal noise (its
// mission and cleaning time limits), printing the outcome.
metrics::CleanScore CleanGenerated(uint64_t seed, const robot::CoreOptions& o) {
  const sim::World world = sim::GenerateWorld(seed, sim::NoiseProfile::kNominal);
  const metrics::CleanScore s =
      metrics::RunAndScoreClean(world, o, seed, o.mission.max_time_s + o.mission.cleaning.max_time_s, false);
  std::printf("nominal/%llu: %s, coverage %.3f, cells %d/%d, contacts %d\n", static_cast<unsigned long long>(seed),
              s.end_state.c_str(), s.coverage, s.cells_done, s.cells, s.contacts_cleaning);
  return s;
}

// A fixed subset of the clean campaign (docs/cleaning.md, generated worlds at
// nominal noise): six seeds where every cell was given up at once (the robot
// boxed in by remembered contacts, or over stale ones: 0.4-8.7 % before the
// cleaning go-to's boxed_in_contacts_m and under_body_contacts_m) and two
// ordinary rooms. A change that makes the distribution worse fails here.
TEST(CleanCampaignSubsetTest, GeneratedRoomsOnceBoxedInAreCleaned) {
  const robot::CoreOptions o = robot::DefaultCoreOptions();
  double sum = 0;
  int rescued = 0;
  const uint64_t boxed_in[] = {1039, 1041, 1047, 1150, 1171, 1176};
  for (const uint64_t seed : {1039, 1041, 1047, 1150, 1171, 1176, 1000, 1001}) {
    const metrics::CleanScore s = CleanGenerated(seed, o);
    sum += s.coverage;
    if (std::find(std::begin(boxed_in), std::end(boxed_in), seed) != std::end(boxed_in) && s.cells_done >= 1 &&
        s.coverage > 0.5) {
      ++rescued;
    }
  }
  // Measured 2026-12-03: mean 0.850 (0.243 before); all six above 50 %.
  EXPECT_GE(sum / 8, 0.82);
  EXPECT_EQ(rescued, 6);
}

// A fixed subset of the clean campaign where the cleaning's plans found no
// way through gaps between pieces of furniture that the robot can pass: the
// mapped sides, extended 15 cm past their convex corners, closed them (seed
// 1025: the robot ended its exploration in a pocket behind such a gap and gave
// up all 5 cells at once). The cleaning's go-tos now plan again with the sides
// extended only to their corners (cleaning.boxed_in_corners).
TEST(CleanCampaignSubsetTest, GapsBetweenConvexCornersAreCleanedThrough) {
  for (const bool corners : {true, false}) {
    robot::CoreOptions o = ScenarioOptions();
    o.mission.cleaning.boxed_in_corners = corners;
    // The control runs without the later fallback too, the robot's own path out
    // (boxed_in_trail_m), which also finds these gaps (mean 0.856 with it alone),
    // and without the count of failures from one spot (no_plan_spot_m), which
    // rescues some of the cells too.
    if (!corners) {
      o.mission.cleaning.boxed_in_trail_m = 0;
      o.mission.cleaning.no_plan_spot_m = 0;
    }
    double sum = 0, pockets = 0;
    std::printf("boxed_in_corners %d:\n", corners);
    for (const uint64_t seed : {1025, 1018, 1163, 1157}) {
      const double c = CleanGenerated(seed, o).coverage;
      sum += c;
      if (seed != 1018) pockets += c;
    }
    // Measured 2026-12-05: mean 0.856 (0.801, 0.871, 0.898, 0.852); without:
    // 0.143 (0.006, 0.143, 0.171, 0.252). (1066 left the subset when the
    // go-to's front check stopped seeing contacts under the body: it cleans
    // 0.935 with or without the corners since.) Since loops close at any
    // anchor, 1018's exploration ends elsewhere and it cleans 0.886 without
    // the corners too: the check without them is on the other three (0.143).
    if (corners) {
      EXPECT_GE(sum / 4, 0.80);
    } else {
      EXPECT_LE(pockets / 3, 0.30) << "the gaps are no longer closed without it: this test no longer tests it";
    }
  }
}

// A fixed subset of the clean campaign where the robot stood still on its way
// to route points: the contacts under its body, which the go-to's plans leave
// out (under_body_contacts_m), still showed in its front check 0.09-0.10 m
// ahead, under front_stop_m, so it backed off and planned the same path until
// stuck_s gave the point up, four points in a row, and the cell with them.
// The front check now leaves those contacts out too, and stuck_s counts from
// the go-to's start for each route point.
TEST(CleanCampaignSubsetTest, ContactsUnderTheBodyNoLongerHoldTheRobotStill) {
  const robot::CoreOptions o = robot::DefaultCoreOptions();
  double sum = 0;
  int cells_done = 0, cells = 0;
  for (const uint64_t seed : {1040, 1064, 1124, 1110, 1197}) {
    const metrics::CleanScore s = CleanGenerated(seed, o);
    sum += s.coverage;
    cells_done += s.cells_done;
    cells += s.cells;
  }
  // Measured 2026-12-05: mean 0.839 (0.917, 0.820, 0.817, 0.752, 0.887), 14
  // cells done; before: 0.075 (0.050, 0.016, 0.015, 0.017, 0.277), 0 cells done.
  // Since escapes face away from the contact: 0.776, 12 cells (1064: 0.505,
  // its plans all fail from where an escape leaves it: docs/cleaning.md).
  // 2026-12-06, before: 0.827, 10 of 11 cells done. Since a free piece's side
  // facing a near wall is inferred (model.narrow_gap_m): 0.835 (0.916, 0.775,
  // 0.834, 0.757, 0.891), 9 of 11 (1197: 2 of 4 cells, 0.879 -> 0.891 covered).
  // The share of cells is asserted: their number follows the room's model.
  EXPECT_GE(sum / 5, 0.75);
  EXPECT_GE(cells_done, 0.75 * cells);
  EXPECT_GE(cells, 5);
}

// A fixed subset of the clean campaign where the exploration never ended: the
// first wall the robot followed steadily was a piece of furniture, the loop
// detector's only anchor lay on it, and the robot, gone on along the room's
// wall, circled the room until the mission's time limit without passing it
// again (nothing cleaned). Anchors are now taken every loop_anchor_spacing_m
// of steady following, and a loop closes at any of them.
TEST(CleanCampaignSubsetTest, RoomLoopsCloseWhenTheFirstWallFollowedWasFurniture) {
  for (const double spacing : {1.0, 1000.0}) {
    robot::CoreOptions o = ScenarioOptions();
    o.mission.loop.loop_anchor_spacing_m = spacing;  // 1000 m: one anchor, as before
    // (One of them closes its loop late with one anchor and then reaches the time
    // limit going to a piece: not cleaned at that limit, as before, it tells the
    // loop detector alone.)
    o.mission.clean_at_time_limit = spacing < 10;
    double sum = 0;
    std::printf("loop_anchor_spacing_m %.0f:\n", spacing);
    for (const uint64_t seed : {1169, 1015, 1037, 1117, 1121}) sum += CleanGenerated(seed, o).coverage;
    // Measured 2026-12-05: mean 0.904 (0.905, 0.911, 0.933, 0.901, 0.870);
    // with one anchor: 0 (all five at the time limit in wall_follow).
    if (spacing < 10) {
      EXPECT_GE(sum / 5, 0.85);
    } else {
      EXPECT_LE(sum / 5, 0.05) << "these loops close with one anchor now: this test no longer tests it";
    }
  }
}

// The clean campaign's room where the wall-following loop closed round a pen:
// floor between furniture and a wall whose gaps the robot could pass but the
// follower turned at (1076: the robot started in one). The room was modelled
// as the pen (0.9 m2 cleaned of 15.9). The beams had seen floor outside it;
// the mission now leaves the pen (mission.pen_check; free_space.h) and follows
// walls again. (The one room of the 200 where it does: README, the mission.)
TEST(CleanCampaignSubsetTest, ALoopRoundAPenIsLeftForTheRoom) {
  for (const bool check : {true, false}) {
    robot::CoreOptions o = robot::DefaultCoreOptions();
    o.mission.pen.pen_check = check;
    const double c = CleanGenerated(1076, o).coverage;
    // Measured 2026-12-07: 0.803; without: 0.061.
    if (check) {
      EXPECT_GE(c, 0.70);
    } else {
      EXPECT_LE(c, 0.10) << "this loop no longer closes round the pen: this test no longer tests it";
    }
  }
}

// The clean campaign's two rooms that never began cleaning (idle at the
// mission's time limit): the follower, turned at a gap onto a free compound
// each time, circled it, left it, and came back to it along the same walls
// (1028, 1070). A free-object loop closing where one closed before, with the
// room's four walls mapped, now ends wall following as the room loop does
// (mission.repeat_free_loop_m).
TEST(CleanCampaignSubsetTest, ASecondLoopRoundTheSameFreeObjectModelsTheRoom) {
  for (const double repeat : {0.5, 0.0}) {
    robot::CoreOptions o = robot::DefaultCoreOptions();
    o.mission.repeat_free_loop_m = repeat;
    for (const uint64_t seed : {1028, 1070}) {
      const metrics::CleanScore s = CleanGenerated(seed, o);
      // Measured 2026-12-07: 1028 0.922, 1070 0.838; without: idle at the time limit, 0.
      if (repeat > 0) {
        EXPECT_EQ(s.end_state, "done") << seed;
        EXPECT_GE(s.coverage, 0.75) << seed;
      } else {
        EXPECT_LE(s.coverage, 0.05) << seed << ": this loop no longer repeats: this test no longer tests it";
      }
    }
  }
}

// Room 1070 with another run seed: the robot, wedged between two legs of a
// chair, turned on the spot at an inner corner from 228 s to the time limit
// (nothing ahead ever as far as front_stop_m + 0.15 in the follower's
// corridor). A whole turn without a clear way now drives out the most open way
// of the turn (wall_follow.squeeze_distance_m).
TEST(CleanCampaignSubsetTest, BoxedInBetweenLegsTheFollowerDrivesOut) {
  for (const double squeeze : {0.5, 0.0}) {
    robot::CoreOptions o = robot::DefaultCoreOptions();
    o.wall.squeeze_distance_m = squeeze;
    const sim::World world = sim::GenerateWorld(1070, sim::NoiseProfile::kNominal);
    const metrics::CleanScore s =
        metrics::RunAndScoreClean(world, o, 1, o.mission.max_time_s + o.mission.cleaning.max_time_s, false);
    std::printf("nominal/1070 run seed 1, squeeze %.1f: %s, coverage %.3f\n", squeeze, s.end_state.c_str(), s.coverage);
    // Measured 2026-12-07: done, 0.913; without: idle at the time limit, 0.
    if (squeeze > 0) {
      EXPECT_EQ(s.end_state, "done");
      EXPECT_GE(s.coverage, 0.80);
    } else {
      EXPECT_LE(s.coverage, 0.05) << "the follower is no longer boxed in here: this test no longer tests it";
    }
  }
}

// A fixed subset of the clean campaign where the robot, wedged at the bottom
// of a dead end with its bumper held, escaped away from the wall behind it -
// forward, into what it touched - and never moved: each go-to gave its goal up
// as blocked after five escapes, cell after cell. The escape now faces away
// from the contact unless a mapped side on the contact's side was what it hit.
TEST(CleanCampaignSubsetTest, EscapesFromADeadEndTurnAwayFromTheContact) {
  const robot::CoreOptions o = robot::DefaultCoreOptions();
  double sum = 0;
  for (const uint64_t seed : {1147, 1029, 1113, 1031, 1180}) sum += CleanGenerated(seed, o).coverage;
  // Measured 2026-12-05: mean 0.899 (0.910, 0.905, 0.920, 0.882, 0.877);
  // before: 0.251 (0.082, 0.380, 0.290, 0.272, 0.230).
  EXPECT_GE(sum / 5, 0.80);
}

// A fixed subset of the clean campaign where the robot, driving a cell's edge
// pass or lanes (routes made from the room model, not planned), came into a
// pocket that the mapped sides close in the planner's grid: a side seen short
// and planned round extended past its end leaves less than the robot's width
// to the wall. Every plan out failed at once, the route points were given up
// in a burst from one spot, and the cell with them. The cleaning's go-tos now
// plan once more along the robot's own path (cleaning.boxed_in_trail_m).
TEST(CleanCampaignSubsetTest, APocketTheMapClosesIsLeftTheWayTheRobotCame) {
  for (const double trail_m : {10.0, 0.0}) {
    robot::CoreOptions o = ScenarioOptions();
    o.mission.cleaning.boxed_in_trail_m = trail_m;
    // The control also counts every failure from one spot (no_plan_spot_m 0),
    // as before both: that alone cleans 1045 (0.841).
    if (trail_m == 0) o.mission.cleaning.no_plan_spot_m = 0;
    double sum = 0;
    std::printf("boxed_in_trail_m %.0f:\n", trail_m);
    for (const uint64_t seed : {1014, 1045, 1074, 1114}) sum += CleanGenerated(seed, o).coverage;
    // Measured 2026-12-05: mean 0.850 (0.885, 0.820, 0.841, 0.855); without
    // the trail 0.349 (0.081, 0.383, 0.532, 0.398). With no_plan_spot_m: 0.843
    // (0.871, 0.801, 0.841, 0.858).
    if (trail_m > 0) {
      EXPECT_GE(sum / 4, 0.80);
    } else {
      EXPECT_LE(sum / 4, 0.45) << "these pockets no longer trap the robot without it: this test no longer tests it";
    }
  }
}

// A fixed subset of the clean campaign where route points that could not be
// planned to were given up one a period from the spot the robot stood on (lane
// ends beside chair legs it had touched, a corner it stood in), four in a row,
// and with them the rest of the cell, most of which it could reach. Such
// failures from one spot now count once (cleaning.no_plan_spot_m).
TEST(CleanCampaignSubsetTest, RoutePointsFailingFromOneSpotDoNotGiveTheCellUp) {
  for (const double spot_m : {0.1, 0.0}) {
    robot::CoreOptions o = ScenarioOptions();
    o.mission.cleaning.no_plan_spot_m = spot_m;
    double sum = 0;
    int cells_done = 0;
    std::printf("no_plan_spot_m %.1f:\n", spot_m);
    for (const uint64_t seed : {1070, 1127, 1080, 1183}) {
      const metrics::CleanScore s = CleanGenerated(seed, o);
      sum += s.coverage;
      cells_done += s.cells_done;
    }
    // Measured 2026-12-05: mean 0.857 (0.896, 0.890, 0.855, 0.786), 18 cells
    // done; counting every failure: 0.616 (0.631, 0.511, 0.701, 0.621), 11.
    if (spot_m > 0) {
      EXPECT_GE(sum / 4, 0.82);
      EXPECT_GE(cells_done, 16);
    } else {
      EXPECT_LE(sum / 4, 0.70) << "these cells are no longer given up from one spot: this test no longer tests it";
    }
  }
}

// The seventeen seeds of the four mechanism tests above, cleaned with the
// shipped options (their rooms mapped with the eq. (8) threshold 12): a change
// that makes these rooms worse fails here.
TEST(CleanCampaignSubsetTest, TheMechanismSeedsCleanWithTheShippedOptions) {
  const robot::CoreOptions o = robot::DefaultCoreOptions();
  double sum = 0;
  int n = 0, done = 0;
  for (const uint64_t seed : {1025, 1018, 1163, 1157, 1169, 1015, 1037, 1117, 1121, 1014, 1045, 1074, 1114, 1070,
                              1127, 1080, 1183}) {
    const metrics::CleanScore s = CleanGenerated(seed, o);
    sum += s.coverage;
    done += s.end_state == "done" && s.cleaned;
    ++n;
  }
  std::printf("mean %.3f, %d of %d cleaned\n", sum / n, done, n);
  // Measured 2026-12-06: mean 0.847, all 17 cleaned (lowest: 1025 0.598, its
  // last cell's lanes short of a wall; 1045 0.752); with the threshold 4.5 and
  // each test's mechanism on, the same seeds cleaned 0.866 on average (these
  // are the seeds that threshold's maps failed on first; over the 200-room
  // campaign the new threshold is -0.64 +- 0.62 points, docs/error-budget.md).
  // Since the SLAM trusts the odometry more (2026-12-07): mean 0.812, 16 of 17
  // (1070 is not: as before until 216 s, its wall following then follows a
  // table's and a chair's legs, takes them for a free object circled and never
  // finds its loop again; the other 16 mean 0.863). Over the 200-room campaign
  // nominal coverage 83.6 -> 84.7 % (+1.12 +- 0.79 paired), done 198 of 200 both
  // (docs/cleaning.md).
  // Since the edge pass 2 cm from the walls (2026-12-07): mean 0.815, 16 of 17
  // (1070 as above); over the 200-room campaign 84.7 -> 87.0 % (+2.28 +- 0.52).
  EXPECT_GE(done, n - 1);
  EXPECT_GE(sum / n, 0.80);
}

TEST(CleanModeTest, PlannedCleaningBeatsRandomBounceOverTheSameTime) {
  const sim::World world = testing::LoadTestWorld("free_start");
  const robot::CoreOptions o = robot::DefaultCoreOptions();
  const metrics::CleanScore s = metrics::RunAndScoreClean(world, o, 1, 4500, true);
  // Measured: 93.9 % against 38.6 %.
  EXPECT_GE(s.coverage, s.bounce_coverage + 0.4);
  ASSERT_GE(s.bounce_curve.size(), 2u);
  EXPECT_NEAR(s.bounce_curve.back().first, s.clean_s, 1.0);
}

// Mode clean: the exploration's time limit reached after the room was modelled
// cleans the room as it is modelled, the pieces still pending given up (the
// campaign's never-cleaned rooms: a piece contour-followed or gone to until the
// limit); clean_at_time_limit false ends the mission there, as it used to.
TEST(CleanModeTest, TheExplorationTimeLimitAfterTheRoomWasModelledStillCleans) {
  const sim::World world = testing::LoadTestWorld("fig14");
  robot::CoreOptions o = robot::DefaultCoreOptions();
  // When the exploration first goes to a piece (the room is modelled by then).
  double to_piece_s = -1;
  sim::RunInProcess(world, o, 1, 900, [&](const sim::InProcessRun& r) {
    if (to_piece_s < 0 && r.core->state() == control::MissionState::kGoToP1) to_piece_s = r.t;
  });
  ASSERT_GT(to_piece_s, 0);
  o.mission.mode = "clean";
  o.mission.max_time_s = to_piece_s + 20;  // cut while it goes to the first piece
  // (Its reason, "mission time limit reached: cleaning the room as modelled",
  // lasts no period: the cleaning is planned in the same one, whose reason says it.)
  std::string cleaning_reason;
  control::MissionState last = control::MissionState::kIdle;
  sim::InProcessRun run = sim::RunInProcess(world, o, 1, 4500, [&](const sim::InProcessRun& r) {
    if (r.core->state() == control::MissionState::kClean && last != control::MissionState::kClean)
      cleaning_reason = r.core->Status(r.t).mission.reason;
    last = r.core->state();
  });
  EXPECT_EQ(cleaning_reason.find("cleaning "), 0u) << cleaning_reason;
  EXPECT_NE(cleaning_reason.find("; the room as modelled at the mission time limit"), std::string::npos)
      << cleaning_reason;
  EXPECT_EQ(run.core->state(), control::MissionState::kDone) << run.core->Status(run.t).mission.reason;
  const nlohmann::json map = ToJson(run.core->Map());
  ASSERT_TRUE(map.contains("cleaning"));
  EXPECT_EQ(map["cleaning"]["state"], "done");
  int given_up = 0;
  for (const auto& obj : map["objects"]) given_up += obj["note"] == "mission time limit reached";
  EXPECT_GE(given_up, 1);
  const metrics::CleanScore cut = metrics::RunAndScoreClean(world, o, 1, 4500, false);
  EXPECT_TRUE(cut.cleaned);
  std::printf("cut at %.0f s: %d pieces given up, coverage %.3f\n", o.mission.max_time_s, given_up,
              cut.coverage);
  EXPECT_GE(cut.coverage, 0.8);  // measured 0.906 (cut at 174 s, 2 pieces given up)
  o.mission.clean_at_time_limit = false;
  const metrics::CleanScore ended = metrics::RunAndScoreClean(world, o, 1, 4500, false);
  EXPECT_FALSE(ended.cleaned);
  EXPECT_EQ(ended.end_state, "idle");
  EXPECT_EQ(ended.reason, "mission time limit reached");
}

TEST(CleanModeTest, ExploreModeNeverCleans) {
  const sim::World world = testing::LoadTestWorld("fig14");
  sim::InProcessRun run = sim::RunInProcess(world, robot::DefaultCoreOptions(), 1, 900);
  EXPECT_EQ(run.core->state(), control::MissionState::kDone);
  EXPECT_FALSE(ToJson(run.core->Map()).contains("cleaning"));
  EXPECT_FALSE(ToJson(run.core->Status(run.t)).contains("cleaning"));
}

TEST(CleanModeTest, TheMapCarriesTheCellsWithDoneFlags) {
  const sim::World world = testing::LoadTestWorld("fig14");
  robot::CoreOptions o = robot::DefaultCoreOptions();
  o.mission.mode = "clean";
  sim::InProcessRun run = sim::RunInProcess(world, o, 1, 4500);
  ASSERT_EQ(run.core->state(), control::MissionState::kDone);
  const nlohmann::json map = ToJson(run.core->Map());
  ASSERT_TRUE(map.contains("cleaning"));
  const auto& c = map["cleaning"];
  EXPECT_EQ(c["state"], "done");
  EXPECT_GT(c["finished_t"].get<double>(), c["started_t"].get<double>());
  EXPECT_GT(c["total_m2"].get<double>(), 10.0);
  ASSERT_GE(c["cells"].size(), 4u);
  for (const auto& cell : c["cells"]) {
    EXPECT_TRUE(cell["done"].get<bool>());
    EXPECT_GE(cell["polygon"].size(), 4u);
    EXPECT_GE(cell["route"].size(), 2u);
  }
}

// Issue 15: the coverage plan made a bounded piece per period (a tiny share
// per period here, so it takes many) is the same plan as the one made in the
// period the cleaning began; the robot holds still meanwhile.
TEST(CleanModeTest, APlanSpreadOverManyPeriodsIsTheSamePlan) {
  const sim::World world = testing::LoadTestWorld("fig14");
  robot::CoreOptions o = robot::DefaultCoreOptions();
  o.mission.mode = "clean";
  struct Planned {
    int planning_periods = 0;
    double still_m = 0;  // driven while planning (true)
    std::optional<control::CleaningProgress> cleaning;
  };
  const auto run = [&](const robot::CoreOptions& options) {
    Planned p;
    sim::RunSetup setup;
    setup.stop_when = [&](const sim::InProcessRun& r) {
      const auto c = r.core->Status(r.t).cleaning;
      return c && c->cells_total > 0 && r.core->state() == control::MissionState::kClean &&
             r.core->Status(r.t).mission.reason.rfind("cleaning ", 0) == 0;
    };
    double at = -1;
    const sim::InProcessRun r = sim::RunInProcess(
        world, options, 1, 2000,
        [&](const sim::InProcessRun& now) {
          if (now.core->Status(now.t).mission.reason != "planning the cleaning") return;
          ++p.planning_periods;
          const double d = now.core->slam().distance_m();
          if (at < 0) at = d;
          p.still_m = std::max(p.still_m, d - at);
        },
        nullptr, nullptr, setup);
    p.cleaning = r.core->Map().cleaning;
    return p;
  };
  const Planned whole = run(o);
  o.mission.cleaning.plan_work_per_period = 1000;
  const Planned spread = run(o);
  EXPECT_EQ(whole.planning_periods, 0);  // the paper's room: planned in the period it began
  EXPECT_GE(spread.planning_periods, 5);
  EXPECT_LT(spread.still_m, 0.01);
  ASSERT_TRUE(whole.cleaning && spread.cleaning);
  ASSERT_EQ(whole.cleaning->cells.size(), spread.cleaning->cells.size());
  EXPECT_GE(whole.cleaning->cells.size(), 4u);
  for (size_t i = 0; i < whole.cleaning->cells.size(); ++i) {
    EXPECT_EQ(whole.cleaning->cells[i].id, spread.cleaning->cells[i].id);
    EXPECT_TRUE(whole.cleaning->cells[i].polygon == spread.cleaning->cells[i].polygon) << i;
    EXPECT_TRUE(whole.cleaning->cells[i].route == spread.cleaning->cells[i].route) << i;
  }
  EXPECT_EQ(whole.cleaning->total_m2, spread.cleaning->total_m2);
}

}  // namespace
}  // namespace irslam
