// The JSON views of RobotCore's status and map: the core part of the API's
// `status` (contracts §6; the daemon adds its own keys) and the map the API's
// `map`, irslamctl map --out and irslam-sim run --map-out serve (contracts §4).
#ifndef IRSLAM_DAEMON_CORE_JSON_H_
#define IRSLAM_DAEMON_CORE_JSON_H_

#include <nlohmann/json.hpp>
#include <optional>

#include "robot/status.h"

namespace irslam {

nlohmann::json ToJson(const robot::CoreStatus& status);
nlohmann::json ToJson(const robot::MapSnapshot& map);

// The odometry calibration's JSON view (status slam.calibration, the map's
// "calibration"): {"scale": [left, right, base], "std": [3], "ratio", "ratio_std"}
// with the scale factors of the nominal left/right wheel radius and track width.
nlohmann::json CalibrationJson(const slam::CalibrationEstimate& c);
// The calibration kept in a map, when it has one that checks out (scale factors
// within [0.5, 1.5], standard deviations within [0, 0.5]); else nullopt.
std::optional<slam::CalibrationEstimate> CalibrationFromMap(const nlohmann::json& map);

}  // namespace irslam

#endif  // IRSLAM_DAEMON_CORE_JSON_H_
