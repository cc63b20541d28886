// IR conditioning (drivers/ir_conditioner.h): counts to a scan, with the
// per-sensor plausibility checks and their counters.
#include <gtest/gtest.h>

#include "drivers/ir_conditioner.h"

namespace irslam::drivers {
namespace {

using Counts = IrConditioner::Counts;

Counts Filled(uint16_t c) {
  Counts a;
  a.fill(c);
  return a;
}

TEST(IrConditionerTest, ConvertsCountsToRangesWithTheCalibration) {
  IrConditioner ir{IrCalibrationOptions{}};
  const IrCalibration& cal = ir.calibration();
  Counts adc{};
  const double d[kNumIrSensors] = {0.25, 0.4, 0.5, 0.7, 0.9, 1.1, 1.35};
  for (int i = 0; i < kNumIrSensors; ++i) adc[i] = cal.VoltsToCounts(cal.DistanceToVolts(d[i]));
  const RangeScan& s = ir.Add(12.5, adc);
  EXPECT_DOUBLE_EQ(s.t, 12.5);
  for (int i = 0; i < kNumIrSensors - 1; ++i) {
    ASSERT_TRUE(s.range_m[i]) << i;
    EXPECT_NEAR(*s.range_m[i], d[i], 0.002) << i;
  }
  EXPECT_FALSE(s.range_m[6]) << "beyond max_range_m: no reading, but plausible";
  EXPECT_EQ(ir.counters().out_of_range, 0u);
  EXPECT_EQ(ir.counters().stuck, 0u);
  EXPECT_EQ(ir.last_adc(), adc);
  EXPECT_EQ(&ir.scan(), &s);
}

TEST(IrConditionerTest, VoltagesOutsideThePlausibleRangeAreFaultsNotDistances) {
  IrCalibrationOptions o;  // 12 bits, 3.3 V: 0.05 V = 62 counts, 3.0 V = 3723 counts
  IrConditioner ir{o};
  Counts adc = Filled(ir.calibration().VoltsToCounts(1.25));  // 0.5 m
  adc[0] = 4095;  // 3.3 V
  adc[4] = 10;    // 8 mV
  const RangeScan& s = ir.Add(1.0, adc);
  EXPECT_FALSE(s.range_m[0]);
  EXPECT_FALSE(s.range_m[4]);
  ASSERT_TRUE(s.range_m[3]);
  EXPECT_NEAR(*s.range_m[3], 0.5, 0.002);
  EXPECT_EQ(ir.counters().out_of_range, 2u);
  // A reading inside the range clears it at the next sample.
  adc[0] = adc[1];
  adc[4] = static_cast<uint16_t>(adc[1] + 1);
  ir.Add(1.05, adc);
  EXPECT_TRUE(ir.scan().range_m[0]);
  EXPECT_TRUE(ir.scan().range_m[4]);
  EXPECT_EQ(ir.counters().out_of_range, 2u);
}

TEST(IrConditionerTest, AStuckSensorIsNoReadingOnceItsValueRepeatedStuckSamplesTimes) {
  IrCalibrationOptions o;
  o.stuck_samples = 5;
  IrConditioner ir{o};
  const uint16_t base = ir.calibration().VoltsToCounts(1.25);
  for (int k = 0; k < 6; ++k) {
    Counts adc = Filled(static_cast<uint16_t>(base + k % 2));  // the others move
    adc[2] = base;                                             // sensor 2 never does
    ir.Add(0.05 * k, adc);
    EXPECT_EQ(ir.scan().range_m[2].has_value(), k < 4) << k;  // the 5th equal value on
    EXPECT_TRUE(ir.scan().range_m[3]) << k;
  }
  EXPECT_EQ(ir.counters().stuck, 2u);  // samples 5 and 6
  Counts adc = Filled(base);
  adc[2] = static_cast<uint16_t>(base + 3);  // it moves again
  ir.Add(0.5, adc);
  EXPECT_TRUE(ir.scan().range_m[2]);
}

TEST(IrConditionerTest, ZeroStuckSamplesTurnsTheStuckCheckOff) {
  IrCalibrationOptions o;
  o.stuck_samples = 0;
  IrConditioner ir{o};
  const Counts adc = Filled(ir.calibration().VoltsToCounts(1.25));
  for (int k = 0; k < 100; ++k) ir.Add(0.05 * k, adc);
  EXPECT_TRUE(ir.scan().range_m[0]);
  EXPECT_EQ(ir.counters().stuck, 0u);
}

TEST(IrConditionerTest, BeforeTheFirstSampleTheScanHasNoReadings) {
  IrConditioner ir{IrCalibrationOptions{}};
  for (const auto& r : ir.scan().range_m) EXPECT_FALSE(r);
  EXPECT_EQ(ir.last_adc(), Counts{});
}

}  // namespace
}  // namespace irslam::drivers
