#include <gtest/gtest.h>

#include "drivers/ir_calibration.h"

namespace irslam::drivers {
namespace {

TEST(IrCalibrationTest, TablePointsMapBackToTheirDistances) {
  IrCalibration cal{IrCalibrationOptions{}};
  EXPECT_NEAR(cal.VoltsToDistance(2.51), 0.20, 1e-12);
  EXPECT_NEAR(cal.VoltsToDistance(1.25), 0.50, 1e-12);
  EXPECT_NEAR(cal.VoltsToDistance(0.55), 1.20, 1e-12);
  // Halfway in voltage between 0.40 m (1.52 V) and 0.50 m (1.25 V).
  EXPECT_NEAR(cal.VoltsToDistance(1.385), 0.45, 1e-12);
}

TEST(IrCalibrationTest, CountsToRangeWithinOneAdcStep) {
  IrCalibration cal{IrCalibrationOptions{}};
  for (double d : {0.25, 0.5, 0.8, 1.1}) {
    const uint16_t counts = cal.VoltsToCounts(cal.DistanceToVolts(d));
    const auto r = cal.CountsToRange(counts);
    ASSERT_TRUE(r.has_value()) << d;
    // One ADC step (0.8 mV) is worth ~0.1 mm at 25 cm and ~1.2 mm at 1.1 m.
    EXPECT_NEAR(*r, d, 0.002) << d;
  }
}

TEST(IrCalibrationTest, OutsideTheUsableRangeIsNoReading) {
  IrCalibration cal{IrCalibrationOptions{}};
  EXPECT_FALSE(cal.CountsToRange(cal.VoltsToCounts(cal.DistanceToVolts(1.35))).has_value());
  EXPECT_FALSE(cal.CountsToRange(cal.VoltsToCounts(cal.DistanceToVolts(0.17))).has_value());
  EXPECT_FALSE(cal.CountsToRange(4095).has_value());  // above the table's top voltage
  EXPECT_FALSE(cal.CountsToRange(0).has_value());
}

TEST(IrCalibrationTest, FoldBackBelowTheFirstTablePoint) {
  IrCalibration cal{IrCalibrationOptions{}};
  // At 7.5 cm the output has fallen back to half of the 15 cm value.
  EXPECT_NEAR(cal.DistanceToVolts(0.075), 1.375, 1e-12);
}

TEST(IrCalibrationTest, ValidateNamesTheProblem) {
  IrCalibrationOptions o;
  EXPECT_EQ(o.Validate(), "");
  o.table = {{0.2, 2.0}, {0.3, 2.5}};
  EXPECT_NE(o.Validate().find("decreasing voltage"), std::string::npos);
  o = IrCalibrationOptions{};
  o.max_range_m = 2.0;
  EXPECT_NE(o.Validate().find("inside sensors.table"), std::string::npos);
}

}  // namespace
}  // namespace irslam::drivers
