// Surveying the room from inside: furniture far from every wall is never within
// range of the wall-following loop, so the robot looks round (one full turn on
// the spot) first from the room's middle, then from the free points that would
// see most of what no trajectory point came within survey_range_m of, until
// little is left unseen or max_surveys points were visited. This class chooses
// the points and turns round; GoTo drives there. Pure.
#ifndef IRSLAM_CONTROL_SURVEY_H_
#define IRSLAM_CONTROL_SURVEY_H_

#include <Eigen/Core>
#include <vector>

#include "control/room_model.h"
#include "control/wall_follower.h"
#include "types/options.h"

namespace irslam::control {

struct SurveyOptions {
  // [exploration] keys since the first exploration release.
  bool survey_centre = true;          // look round from inside the room (first its middle)
  int max_surveys = 3;                // ... from at most this many points
  double survey_range_m = 0.7;        // a part of the room within this of the trajectory was seen
  double survey_min_unseen_m2 = 0.4;  // a survey point must see at least this much unseen room
  // Tuning numbers that used to be literals.
  double survey_middle_search_m = 1.2;   // the first point: the reachable one nearest the middle,
  double survey_middle_step_m = 0.2;     // ... on rings this far apart out to this radius
  double survey_cell_m = 0.2;            // grid of the unseen-room count
  double survey_object_margin_m = 0.35;  // cells this close to a known object are not room
  double survey_wall_margin_m = 0.4;     // survey points keep this from the walls
  int survey_trajectory_stride = 2;      // every this-many trajectory points count as seen from
  int survey_candidates = 8;             // best-ranked points tried (planned to) before giving up
  double survey_turn_rate_rad_s = 0.5;   // looking round
  double survey_turn_margin_rad = 0.3;   // one full turn plus this
};
options::Table<SurveyOptions> SurveyKeys();

class Survey {
 public:
  explicit Survey(SurveyOptions options) : options_(options) {}

  // A new mission: no survey done.
  void Reset();
  // Whether another survey is wanted (nothing else pending in the model).
  bool Wanted(const EnvironmentModel& m) const;
  // Candidate survey points (map frame), in order of preference: before the
  // first survey, the middle of the room and rings round it ...
  std::vector<Eigen::Vector2d> MiddlePoints(const Box& room) const;
  // ... then the free points that see most unseen room.
  std::vector<Eigen::Vector2d> RankedPoints(const Box& room,
                                            const std::vector<TimedPose>& trajectory,
                                            const std::vector<ObjectModel>& objects) const;
  // The robot sets off to survey point p.
  void Accept(const Eigen::Vector2d& p);
  // Nothing left worth a look, or nowhere to look from: no more surveys.
  void Exhaust() { done_ = options_.max_surveys; }
  // At the survey point: the turn on the spot; true once it is complete.
  bool TurnRound(double theta, Twist* out);
  int done() const { return done_; }

 private:
  SurveyOptions options_;
  int done_ = 0;
  std::vector<Eigen::Vector2d> points_;  // map frame: where surveys looked from
  double turned_ = -1;                   // >= 0 while turning round
  double last_theta_ = 0;
};

}  // namespace irslam::control

#endif  // IRSLAM_CONTROL_SURVEY_H_
