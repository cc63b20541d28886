#include "drivers/ir_calibration.h"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace irslam::drivers {

std::string IrCalibrationOptions::Validate() const {
  if (adc_bits < 8 || adc_bits > 16) return "sensors.adc_bits must be in [8, 16]";
  if (!(adc_vref_v > 0)) return "sensors.adc_vref_v must be > 0";
  if (table.size() < 2) return "sensors.table needs at least 2 points";
  for (size_t i = 1; i < table.size(); ++i) {
    if (!(table[i].first > table[i - 1].first) || !(table[i].second < table[i - 1].second)) {
      std::ostringstream os;
      os << "sensors.table must have increasing distance and decreasing voltage (point " << i
         << ")";
      return os.str();
    }
  }
  if (!(min_range_m < max_range_m)) return "sensors.min_range_m must be < sensors.max_range_m";
  if (min_range_m < table.front().first || max_range_m > table.back().first) {
    return "sensors.min_range_m/max_range_m must lie inside sensors.table";
  }
  return {};
}

IrCalibration::IrCalibration(IrCalibrationOptions options) : options_(std::move(options)) {}

double IrCalibration::CountsToVolts(uint16_t counts) const {
  const double full = std::ldexp(1.0, options_.adc_bits) - 1;
  return options_.adc_vref_v * static_cast<double>(counts) / full;
}

uint16_t IrCalibration::VoltsToCounts(double volts) const {
  const double full = std::ldexp(1.0, options_.adc_bits) - 1;
  const double c = std::round(volts / options_.adc_vref_v * full);
  return static_cast<uint16_t>(std::clamp(c, 0.0, full));
}

double IrCalibration::VoltsToDistance(double v) const {
  const auto& t = options_.table;
  if (v >= t.front().second) return t.front().first;
  if (v <= t.back().second) return t.back().first;
  for (size_t i = 1; i < t.size(); ++i) {
    if (v >= t[i].second) {
      const double f = (t[i - 1].second - v) / (t[i - 1].second - t[i].second);
      return t[i - 1].first + f * (t[i].first - t[i - 1].first);
    }
  }
  return t.back().first;
}

double IrCalibration::DistanceToVolts(double d) const {
  const auto& t = options_.table;
  if (d < t.front().first) {
    // Fold-back: below the first point the output falls again towards 0 V.
    return t.front().second * std::max(d, 0.0) / t.front().first;
  }
  if (d >= t.back().first) {
    // Beyond the table: the voltage keeps falling as ~1/d.
    return t.back().second * t.back().first / d;
  }
  for (size_t i = 1; i < t.size(); ++i) {
    if (d <= t[i].first) {
      const double f = (d - t[i - 1].first) / (t[i].first - t[i - 1].first);
      return t[i - 1].second + f * (t[i].second - t[i - 1].second);
    }
  }
  return t.back().second;
}

std::optional<double> IrCalibration::CountsToRange(uint16_t counts) const {
  const double v = CountsToVolts(counts);
  // Outside the table's voltage span there is no usable reading.
  if (v > options_.table.front().second || v < options_.table.back().second) return std::nullopt;
  const double d = VoltsToDistance(v);
  if (d < options_.min_range_m || d > options_.max_range_m) return std::nullopt;
  return d;
}

options::Table<IrCalibrationOptions> IrCalibrationKeys() {
  using I = IrCalibrationOptions;
  static constexpr options::Key<I> kKeys[] = {
      {"adc_vref_v", &I::adc_vref_v, 0.1, 24, "V", "ADC reference voltage"},
      {"adc_bits", &I::adc_bits, 8, 16, "", "ADC resolution"},
      {"min_range_m", &I::min_range_m, 0.0, 10.0, "m", "readings outside [min, max] are no reading"},
      {"max_range_m", &I::max_range_m, 0.0, 10.0, "m", "(see min_range_m)"},
      {"plausible_min_v", &I::plausible_min_v, 0.0, 10.0, "V",
       "an output outside [min, max] volts is a sensor fault: dropped, counted (frames.ir_out_of_range)"},
      {"plausible_max_v", &I::plausible_max_v, 0.0, 10.0, "V", "(see plausible_min_v)"},
      {"stuck_samples", &I::stuck_samples, 0, 100000, "",
       "the same raw value this many samples in a row: stuck, dropped until it changes (0 = off)"},
  };
  return kKeys;
}

}  // namespace irslam::drivers
