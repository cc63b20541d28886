// Survey: choosing the points to look round from, and the turn on the spot.
#include "control/survey.h"

#include <gtest/gtest.h>

namespace irslam::control {
namespace {

const Box kRoom{0, 0, 4, 5};

TEST(SurveyTest, FirstTheMiddleAndRingsRoundIt) {
  Survey s({});
  const auto p = s.MiddlePoints(kRoom);
  ASSERT_EQ(p.size(), 41u);  // the middle, then 8 points on each ring of 0.2 ... 1.0 m
  EXPECT_DOUBLE_EQ(p[0].x(), 2.0);
  EXPECT_DOUBLE_EQ(p[0].y(), 2.5);
  EXPECT_NEAR(p[1].x(), 2.2, 1e-12);
  EXPECT_NEAR((p[40] - p[0]).norm(), 1.0, 1e-12);
  s.Accept(p[0]);
  EXPECT_EQ(s.done(), 1);
  EXPECT_TRUE(s.MiddlePoints(kRoom).empty());  // only before the first survey
}

TEST(SurveyTest, RanksPointsByUnseenRoom) {
  Survey s({});
  // Nothing seen yet: the best points see a full circle of unseen cells; ties go
  // to the one nearest the middle (a cell centre 0.1 m from it).
  auto p = s.RankedPoints(kRoom, {}, {});
  ASSERT_EQ(p.size(), 8u);  // survey_candidates
  EXPECT_NEAR((p[0] - Eigen::Vector2d(2, 2.5)).norm(), 0.1, 1e-9);
  // The trajectory went everywhere: nothing is left to see.
  std::vector<TimedPose> everywhere;
  for (double x = 0; x <= 4; x += 0.3) {
    for (double y = 0; y <= 5; y += 0.3) everywhere.push_back({0, {x, y, 0}});
  }
  EXPECT_TRUE(s.RankedPoints(kRoom, everywhere, {}).empty());
  // What an earlier survey looked at counts as seen too.
  SurveyOptions big;
  big.survey_min_unseen_m2 = 1.4;  // a full circle of 0.7 m holds 37 cells of 0.04 m2: 1.48 m2
  Survey s2(big);
  const auto before = s2.RankedPoints(kRoom, {}, {});
  ASSERT_FALSE(before.empty());
  s2.Accept(before[0]);
  for (const auto& q : s2.RankedPoints(kRoom, {}, {})) EXPECT_GT((q - before[0]).norm(), 0.7);
}

TEST(SurveyTest, TurnsRoundOnceThenIsDone) {
  Survey s({});
  Twist tw;
  int calls = 0;
  double theta = 1.0;
  while (!s.TurnRound(NormalizeAngle(theta), &tw)) {
    EXPECT_DOUBLE_EQ(tw.omega, 0.5);
    theta += 0.1;
    ++calls;
  }
  EXPECT_EQ(calls, 66);  // 6.6 rad > 2 pi + 0.3
}

TEST(SurveyTest, WantedOnlyWithARoomAndSurveysLeft) {
  Survey s({});
  EnvironmentModel m;
  EXPECT_FALSE(s.Wanted(m));
  m.room.box = kRoom;
  EXPECT_TRUE(s.Wanted(m));
  s.Exhaust();
  EXPECT_FALSE(s.Wanted(m));
}

}  // namespace
}  // namespace irslam::control
