// TEMPORARY (lead): the control/ option tables until the control refactor lands them in control/.
#include "control/mission.h"
#include "control/room_model.h"
#include "control/wall_follower.h"
#include "types/options.h"

namespace irslam::control {

options::Table<WallFollowerOptions> WallFollowerKeys() {
  using T = WallFollowerOptions;
  static constexpr options::Key<T> kKeys[] = {
      {"follow_distance_m", &T::follow_distance_m, 0.1, 2.0, "m", "robot centre to the wall on its right"},
      {"cruise_speed_mps", &T::cruise_speed_mps, 0.01, 2.0, "m/s", ""},
      {"front_stop_m", &T::front_stop_m, 0.1, 2.0, "m", "obstacle this close ahead: turn (inner corner)"},
      {"front_slow_m", &T::front_slow_m, 0.1, 3.0, "m", "slow down below this"},
      {"k_distance", &T::k_distance, 0, 100, "", "rad/s per metre of distance error"},
      {"k_angle", &T::k_angle, 0, 100, "", "rad/s per radian of wall angle"},
      {"max_turn_rate_rad_s", &T::max_turn_rate_rad_s, 0.05, 10, "rad/s", ""},
      {"turn_rate_rad_s", &T::turn_rate_rad_s, 0.05, 10, "rad/s", "in-place turns"},
      {"lost_wall_margin_m", &T::lost_wall_margin_m, 0.05, 2.0, "m", "wall farther than follow + this: outer corner"},
      {"outer_arc_speed_mps", &T::outer_arc_speed_mps, 0.01, 2.0, "m/s", ""},
      {"backoff_speed_mps", &T::backoff_speed_mps, 0.01, 1.0, "m/s", "after a bumper hit: back off ..."},
      {"backoff_time_s", &T::backoff_time_s, 0.0, 10.0, "s", ""},
      {"backoff_turn_rad", &T::backoff_turn_rad, 0.0, 3.2, "rad", "... and turn left this much"},
  };
  return kKeys;
}

options::Table<MissionOptions> MissionKeys() {
  using T = MissionOptions;
  static constexpr options::Key<T> kKeys[] = {
      {"max_time_s", &T::max_time_s, 1, 1e6, "s", "whole mission, robot time"},
      {"progress_timeout_s", &T::progress_timeout_s, 1, 1e6, "s", "no distance covered for this long: stop"},
      {"loop_min_distance_m", &T::loop_min_distance_m, 0.1, 1000, "m", "wall following covers this before a loop can close"},
      {"loop_close_radius_m", &T::loop_close_radius_m, 0.01, 10, "m", ""},
      {"loop_close_angle_rad", &T::loop_close_angle_rad, 0.01, 3.2, "rad", ""},
      {"max_accel_mps2", &T::max_accel_mps2, 0.01, 20, "m/s^2", "wheel acceleration limit of the commands"},
      {"wall_follow_loops", &T::wall_follow_loops, 1, 100, "", "loops of the room before modelling"},
      {"explore", &T::explore, 0, 0, "", "false: model after wall following and stop (a map only)"},
  };
  return kKeys;
}

options::Table<ExploreOptions> ExploreKeys() {
  using T = ExploreOptions;
  static constexpr options::Key<T> kKeys[] = {
      {"clearance_m", &T::clearance_m, 0, 1, "m", "planned paths keep robot radius + this from mapped lines"},
      {"goal_tolerance_m", &T::goal_tolerance_m, 0.01, 1, "m", "P1 reached"},
      {"heading_tolerance_rad", &T::heading_tolerance_rad, 0.01, 1, "rad", ""},
      {"cruise_speed_mps", &T::cruise_speed_mps, 0.01, 2, "m/s", ""},
      {"lookahead_m", &T::lookahead_m, 0.05, 2, "m", "pure pursuit"},
      {"k_heading", &T::k_heading, 0.1, 20, "", ""},
      {"replan_period_s", &T::replan_period_s, 0.1, 60, "s", ""},
      {"front_stop_m", &T::front_stop_m, 0.1, 2, "m", "unmapped obstacle this close ahead: stop, replan"},
      {"go_to_timeout_s", &T::go_to_timeout_s, 1, 3600, "s", "give the object up if P1 is not reached by then ..."},
      {"contour_timeout_s", &T::contour_timeout_s, 1, 3600, "s", "give up completing an object after this"},
      {"contour_leave_m", &T::contour_leave_m, 0.05, 10, "m", "a wall-contact object's free sides are done this far beyond"},
      {"contour_loops", &T::contour_loops, 1, 10, "", "times round an object before giving it up"},
      {"go_to_stuck_s", &T::go_to_stuck_s, 1, 3600, "s", "... or if the robot got no 0.3 m further for this long"},
      {"survey_centre", &T::survey_centre, 0, 0, "", "look round from the room's middle (and more points)"},
      {"max_surveys", &T::max_surveys, 0, 100, "", "... from at most this many points"},
      {"survey_range_m", &T::survey_range_m, 0.1, 5, "m", "room within this of the trajectory counts as seen"},
      {"survey_min_unseen_m2", &T::survey_min_unseen_m2, 0, 100, "m^2", "a later survey point must see this much unseen room"},
  };
  return kKeys;
}

options::Table<ModelOptions> ModelKeys() {
  using T = ModelOptions;
  static constexpr options::Key<T> kKeys[] = {
      {"axis_tolerance_rad", &T::axis_tolerance_rad, 0.001, 0.7, "rad", "lines this close to an axis count as axis-aligned"},
      {"collinear_m", &T::collinear_m, 0.001, 1, "m", "pieces of one wall or side: offsets within this"},
      {"corner_m", &T::corner_m, 0.01, 2, "m", "two sides meet: their corner within this of an end"},
      {"wall_contact_m", &T::wall_contact_m, 0.01, 2, "m", "an object this close to a wall touches it"},
      {"wall_reach_m", &T::wall_reach_m, 0, 2, "m", "a side ending this close to a wall (along it) runs into it"},
  };
  return kKeys;
}

}  // namespace irslam::control
