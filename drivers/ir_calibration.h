// IR range sensor calibration: raw ADC counts -> metres, with a Sharp GP2Y0A02-like
// voltage/distance table (paper-notes.md, "Robot and sensors"). The table is
// interpolated (not a power-law fit); readings outside [min_range_m, max_range_m]
// are "no reading".
#ifndef IRSLAM_DRIVERS_IR_CALIBRATION_H_
#define IRSLAM_DRIVERS_IR_CALIBRATION_H_

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "types/options.h"

namespace irslam::drivers {

struct IrCalibrationOptions {
  double adc_vref_v = 3.3;
  int adc_bits = 12;
  // (distance m, output V) pairs, distance strictly increasing, voltage strictly decreasing.
  std::vector<std::pair<double, double>> table = {
      {0.15, 2.75}, {0.20, 2.51}, {0.30, 1.99}, {0.40, 1.52}, {0.50, 1.25}, {0.60, 1.04},
      {0.70, 0.87}, {0.80, 0.79}, {1.00, 0.69}, {1.20, 0.55}, {1.50, 0.45}};
  double min_range_m = 0.20;
  double max_range_m = 1.20;
  // Plausibility (RobotCore): outputs outside [plausible_min_v, plausible_max_v]
  // are a sensor fault (the Sharp output never exceeds ~3 V nor drops to 0 V);
  // the same raw count stuck_samples times in a row is a stuck sensor (0 = off).
  double plausible_min_v = 0.05;
  double plausible_max_v = 3.0;
  int stuck_samples = 50;

  // Empty when valid, else a one-line description of the problem.
  std::string Validate() const;
};

// Config section [sensors] (with the mounts, and the table read by the loader).
options::Table<IrCalibrationOptions> IrCalibrationKeys();

class IrCalibration {
 public:
  explicit IrCalibration(IrCalibrationOptions options);

  // ADC counts -> metres, nullopt outside the usable range.
  std::optional<double> CountsToRange(uint16_t counts) const;
  double CountsToVolts(uint16_t counts) const;
  // Volts -> distance along the table (clamped to the table's ends).
  double VoltsToDistance(double volts) const;
  // Distance -> ideal output voltage, with the fold-back below the table's first
  // point (the simulator's sensor model uses this).
  double DistanceToVolts(double distance_m) const;
  uint16_t VoltsToCounts(double volts) const;

  const IrCalibrationOptions& options() const { return options_; }

 private:
  IrCalibrationOptions options_;
};

}  // namespace irslam::drivers

#endif  // IRSLAM_DRIVERS_IR_CALIBRATION_H_

