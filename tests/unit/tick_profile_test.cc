// The per-period work budget (robot/tick_profile.h): the fixed-bucket histogram's
// quantiles and the phase attribution, with exact numbers.
#include "robot/tick_profile.h"

#include <gtest/gtest.h>

namespace irslam::robot {
namespace {

TEST(DurationHistogramTest, BucketsAreEighthsOfAnOctave) {
  EXPECT_EQ(DurationHistogram::Bucket(0), 0);
  EXPECT_EQ(DurationHistogram::Bucket(63), 0);
  EXPECT_EQ(DurationHistogram::Bucket(64), 1);
  EXPECT_EQ(DurationHistogram::UpperEdge(1), 72);  // 64 + 64/8
  EXPECT_EQ(DurationHistogram::Bucket(71), 1);
  EXPECT_EQ(DurationHistogram::Bucket(72), 2);
  // 1 ms = 2^19 + 7 * 2^16 + 16960: the 8th eighth of the 2^19 octave.
  const int b = DurationHistogram::Bucket(1'000'000);
  EXPECT_EQ(b, 1 + (19 - 6) * 8 + 7);
  EXPECT_EQ(DurationHistogram::UpperEdge(b), 1 << 20);
  EXPECT_EQ(DurationHistogram::Bucket(int64_t{1} << 40), DurationHistogram::kBuckets - 1);
  for (int64_t ns : {int64_t{100}, int64_t{999}, int64_t{12345}, int64_t{1'000'000}, int64_t{20'000'000},
                     int64_t{3'000'000'000}}) {
    const int64_t edge = DurationHistogram::UpperEdge(DurationHistogram::Bucket(ns));
    EXPECT_GT(edge, ns);
    EXPECT_LE(static_cast<double>(edge), ns * 1.125 + 1) << ns;
  }
}

TEST(DurationHistogramTest, QuantilesOfAThousandPeriods) {
  DurationHistogram h;
  for (int i = 0; i < 990; ++i) h.Add(50'000);  // 50 µs
  for (int i = 0; i < 9; ++i) h.Add(800'000);   // 0.8 ms
  h.Add(5'000'000);                             // one 5 ms period
  EXPECT_EQ(h.count(), 1000u);
  EXPECT_EQ(h.max(), 5'000'000);
  EXPECT_EQ(h.Quantile(0.5), 53'248);   // 50 µs's bucket: [49152, 53248)
  EXPECT_EQ(h.Quantile(0.99), 53'248);  // the 990th value is still 50 µs
  EXPECT_EQ(h.Quantile(0.999), 851'968);  // 0.8 ms's bucket: [786432, 851968)
  EXPECT_EQ(h.Quantile(1.0), 5'000'000);  // never above the largest value
  EXPECT_DOUBLE_EQ(h.mean(), (990 * 50'000.0 + 9 * 800'000.0 + 5'000'000.0) / 1000);
  EXPECT_EQ(DurationHistogram().Quantile(0.5), 0);
  static_assert(sizeof(DurationHistogram) < 2100, "fixed memory, whatever the run's length");
}

TEST(TickProfileTest, KeepsTheWorstPeriodAndWhichPhaseTookIt) {
  TickProfile p;
  TickWork a;
  a[TickPhase::kSlam] = 30'000;
  a[TickPhase::kMission] = 10'000;
  p.Add(a, 1.0);
  TickWork b;
  b[TickPhase::kMission] = 20'000;
  b[TickPhase::kPlanning] = 900'000;
  b[TickPhase::kMapSave] = 5'000;
  p.Add(b, 2.5);
  p.Add(a, 3.0);
  EXPECT_EQ(p.work().count(), 3u);
  EXPECT_EQ(p.work().max(), 925'000);
  EXPECT_EQ(p.worst_phase(), TickPhase::kPlanning);
  EXPECT_DOUBLE_EQ(p.worst_t(), 2.5);
  EXPECT_EQ(p.phase_max(TickPhase::kSlam), 30'000);
  EXPECT_EQ(p.phase_sum(TickPhase::kSlam), 60'000);
  EXPECT_EQ(p.phase_max(TickPhase::kPlanning), 900'000);
  EXPECT_STREQ(ToString(TickPhase::kMapSave), "map_save");
}

}  // namespace
}  // namespace irslam::robot
