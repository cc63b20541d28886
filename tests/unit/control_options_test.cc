// The control option tables: one key per member, defaults within bounds, key
// names unique within each config section, existing keys unchanged.
#include <gtest/gtest.h>

#include <map>
#include <set>
#include <string>
#include <variant>

#include "control/mission.h"
#include "control/path_planner.h"
#include "control/room_model.h"
#include "control/wall_follower.h"

namespace irslam::control {
namespace {

struct Seen {
  std::string unit;
  double lo = 0, hi = 0;
};

// Checks one table against a default-constructed struct; records its keys.
template <class T>
void Check(options::Table<T> table, const std::string& section, std::map<std::string, Seen>* keys) {
  const T d{};
  std::set<std::string> members;
  for (const auto& k : table) {
    SCOPED_TRACE(section + "." + std::string(k.name));
    EXPECT_FALSE(k.doc.empty());
    EXPECT_TRUE(
        keys->emplace(section + "." + std::string(k.name), Seen{std::string(k.unit), k.lo, k.hi})
            .second)
        << "duplicate key in its section";
    std::visit(
        [&](auto member) {
          using M = std::remove_cvref_t<decltype(d.*member)>;
          if constexpr (std::is_same_v<M, double> || std::is_same_v<M, int>) {
            EXPECT_LE(k.lo, d.*member);
            EXPECT_GE(k.hi, d.*member);
            EXPECT_LT(k.lo, k.hi);
          }
        },
        k.member);
  }
}

std::map<std::string, Seen> AllKeys() {
  std::map<std::string, Seen> keys;
  Check(WallFollowerKeys(), "wall_follow", &keys);
  Check(MissionKeys(), "mission", &keys);
  Check(LoopKeys(), "mission", &keys);
  Check(BumpMemoryKeys(), "mission", &keys);
  Check(PenKeys(), "mission", &keys);
  Check(GoToKeys(), "exploration", &keys);
  Check(PlannerKeys(), "exploration", &keys);
  Check(ContourKeys(), "exploration", &keys);
  Check(SurveyKeys(), "exploration", &keys);
  Check(ModelKeys(), "model", &keys);
  Check(CleaningKeys(), "cleaning", &keys);
  Check(RelocalizeKeys(), "relocalize", &keys);
  Check(MapChangeKeys(), "relocalize", &keys);
  return keys;
}

TEST(ControlOptionsTest, TablesAreConsistent) {
  const auto keys = AllKeys();
  // wall_follow: 16 (squeeze_*); mission: 7 + mode + clean_at_time_limit + repeat_free_loop_m; loop: 7 (loop_orbit_turn_rad, loop_anchor_spacing_m); pen: 10 (free_space.h); go-to: 41 (tight_clearance_m, plan_pops_per_period, plan_cells_per_pop, blocked_escape_s, boxed_in_contacts_m,
  // under_body_contacts_m);
  // model: 9 (same_size_m, trace_band_m, merge_touching_m, narrow_gap_m); cleaning: 33 (resume_overlap, resume_same_model_m, boxed_in_contacts_m, under_body_contacts_m, boxed_in_corners, boxed_in_trail_m, no_plan_spot_m); relocalize: 13 (scan_min_m; moved_share, moved_confirm_*) + 11 (moved furniture: wall_margin_m, stretched_m, corner_m, past_box_moves).
  EXPECT_EQ(keys.size(), 16u + 10 + 7 + 6 + 10 + 41 + 2 + 6 + 13 + 9 + 33 + 13 + 11);
}

// The keys config.cc read before the tables, with their bounds.
TEST(ControlOptionsTest, ExistingKeysKeepTheirNamesAndBounds) {
  const auto keys = AllKeys();
  const std::map<std::string, std::pair<double, double>> existing = {
      {"wall_follow.follow_distance_m", {0.1, 2.0}},
      {"wall_follow.cruise_speed_mps", {0.01, 2.0}},
      {"wall_follow.front_stop_m", {0.1, 2.0}},
      {"wall_follow.front_slow_m", {0.1, 3.0}},
      {"wall_follow.k_distance", {0, 100}},
      {"wall_follow.k_angle", {0, 100}},
      {"wall_follow.max_turn_rate_rad_s", {0.05, 10}},
      {"wall_follow.turn_rate_rad_s", {0.05, 10}},
      {"wall_follow.lost_wall_margin_m", {0.05, 2.0}},
      {"wall_follow.outer_arc_speed_mps", {0.01, 2.0}},
      {"wall_follow.backoff_speed_mps", {0.01, 1.0}},
      {"wall_follow.backoff_time_s", {0.0, 10.0}},
      {"wall_follow.backoff_turn_rad", {0.0, 3.2}},
      {"mission.max_time_s", {1, 1e6}},
      {"mission.progress_timeout_s", {1, 1e6}},
      {"mission.loop_min_distance_m", {0.1, 1000}},
      {"mission.loop_close_radius_m", {0.01, 10}},
      {"mission.loop_close_angle_rad", {0.01, 3.2}},
      {"mission.max_accel_mps2", {0.01, 20}},
      {"mission.wall_follow_loops", {1, 100}},
      {"exploration.clearance_m", {0, 1}},
      {"exploration.goal_tolerance_m", {0.01, 1}},
      {"exploration.heading_tolerance_rad", {0.01, 1}},
      {"exploration.cruise_speed_mps", {0.01, 2}},
      {"exploration.lookahead_m", {0.05, 2}},
      {"exploration.k_heading", {0.1, 20}},
      {"exploration.replan_period_s", {0.1, 60}},
      {"exploration.front_stop_m", {0.1, 2}},
      {"exploration.go_to_timeout_s", {1, 3600}},
      {"exploration.contour_timeout_s", {1, 3600}},
      {"exploration.contour_leave_m", {0.05, 10}},
      {"exploration.contour_loops", {1, 10}},
      {"exploration.go_to_stuck_s", {1, 3600}},
      {"exploration.max_surveys", {0, 100}},
      {"exploration.survey_range_m", {0.1, 5}},
      {"exploration.survey_min_unseen_m2", {0, 100}},
      {"model.axis_tolerance_rad", {0.001, 0.7}},
      {"model.collinear_m", {0.001, 1}},
      {"model.corner_m", {0.01, 2}},
      {"model.wall_contact_m", {0.01, 2}},
      {"model.wall_reach_m", {0, 2}},
      {"model.trace_band_m", {0.05, 3}},
      {"model.merge_touching_m", {0, 1}},
  };
  for (const auto& [name, bounds] : existing) {
    SCOPED_TRACE(name);
    const auto it = keys.find(name);
    ASSERT_NE(it, keys.end());
    EXPECT_EQ(it->second.lo, bounds.first);
    EXPECT_EQ(it->second.hi, bounds.second);
  }
  EXPECT_TRUE(keys.count("mission.explore"));
  EXPECT_TRUE(keys.count("exploration.survey_centre"));
}

}  // namespace
}  // namespace irslam::control
