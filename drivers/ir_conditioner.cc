#include "drivers/ir_conditioner.h"

namespace irslam::drivers {

const RangeScan& IrConditioner::Add(double t, const Counts& adc) {
  const IrCalibrationOptions& o = calibration_.options();
  scan_.t = t;
  for (int i = 0; i < kNumIrSensors; ++i) {
    same_adc_[i] = adc[i] == last_adc_[i] ? same_adc_[i] + 1 : 0;
    const double v = calibration_.CountsToVolts(adc[i]);
    if (v < o.plausible_min_v || v > o.plausible_max_v) {
      ++counters_.out_of_range;  // a sensor fault, not a distance
      scan_.range_m[i].reset();
    } else if (o.stuck_samples > 0 && same_adc_[i] + 1 >= o.stuck_samples) {
      ++counters_.stuck;
      scan_.range_m[i].reset();
    } else {
      scan_.range_m[i] = calibration_.CountsToRange(adc[i]);
    }
  }
  last_adc_ = adc;
  return scan_;
}

}  // namespace irslam::drivers
