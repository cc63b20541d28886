// IR conditioning: one sample of the seven sensors' raw ADC counts in, a range
// scan out. Each sensor's reading is checked before it becomes a distance: an
// output voltage outside [plausible_min_v, plausible_max_v] is a sensor fault
// (the Sharp output never exceeds ~3 V nor drops to 0 V), and the same raw count
// stuck_samples times in a row is a stuck sensor; either gives "no reading" and
// is counted. Pure: no clock, the sample carries its controller time.
#ifndef IRSLAM_DRIVERS_IR_CONDITIONER_H_
#define IRSLAM_DRIVERS_IR_CONDITIONER_H_

#include <array>
#include <cstdint>

#include "drivers/ir_calibration.h"
#include "types/signals.h"

namespace irslam::drivers {

struct IrConditionerCounters {
  uint64_t out_of_range = 0;  // readings outside the plausible voltage range
  uint64_t stuck = 0;         // readings of a sensor whose raw value did not change
};

class IrConditioner {
 public:
  using Counts = std::array<uint16_t, kNumIrSensors>;

  explicit IrConditioner(IrCalibrationOptions options) : calibration_(std::move(options)) {}

  // The sample `adc` taken at controller time t: returns the scan (also scan()).
  const RangeScan& Add(double t, const Counts& adc);

  // The last scan (all sensors without a reading before the first sample).
  const RangeScan& scan() const { return scan_; }
  // The raw counts of the last sample (zeros before the first).
  const Counts& last_adc() const { return last_adc_; }
  const IrConditionerCounters& counters() const { return counters_; }
  const IrCalibration& calibration() const { return calibration_; }

 private:
  IrCalibration calibration_;
  RangeScan scan_;
  Counts last_adc_{};
  std::array<int, kNumIrSensors> same_adc_{};  // samples in a row with the same raw value
  IrConditionerCounters counters_;
};

}  // namespace irslam::drivers

#endif  // IRSLAM_DRIVERS_IR_CONDITIONER_H_
