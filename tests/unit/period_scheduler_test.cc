#include <gtest/gtest.h>

#include <random>

#include "daemon/period_scheduler.h"

namespace irslam {
namespace {

constexpr int64_t kPeriod = 20'000'000;  // 20 ms

TEST(PeriodSchedulerTest, NoDriftOver1000TicksWithRandomLateness) {
  const int64_t start = 1'000'000'000;
  PeriodScheduler s(kPeriod, start);
  std::mt19937 rng(3);
  std::uniform_int_distribution<int64_t> late(0, kPeriod / 2);  // always wakes late
  for (int i = 0; i < 1000; ++i) s.OnWake(s.deadline_ns() + late(rng));
  // expires_after(period) after each wake would have drifted by the sum of the
  // lateness (~5 s here); the grid keeps the 1001st deadline exact.
  EXPECT_EQ(s.deadline_ns(), start + 1001 * kPeriod);
  EXPECT_EQ(s.ticks(), 1000u);
  EXPECT_EQ(s.overruns(), 0u);
  EXPECT_LE(s.max_late_ns(), kPeriod / 2);
  EXPECT_NEAR(s.mean_late_ns(), kPeriod / 4.0, kPeriod * 0.02);
}

TEST(PeriodSchedulerTest, OverrunsAreCountedAndSkippedNotBunched) {
  PeriodScheduler s(kPeriod, 0);
  s.OnWake(kPeriod);               // on time
  s.OnWake(2 * kPeriod + 2.5 * kPeriod);  // 2.5 periods late: missed 3rd and 4th
  EXPECT_EQ(s.overruns(), 2u);
  EXPECT_EQ(s.deadline_ns(), 5 * kPeriod);
  s.OnWake(5 * kPeriod + 1000);
  EXPECT_EQ(s.deadline_ns(), 6 * kPeriod);
  EXPECT_EQ(s.ticks(), 3u);
}

}  // namespace
}  // namespace irslam
