// The JSON views of RobotCore's status and map: the core part of the API's
// `status` (contracts §6; the daemon adds its own keys) and the map the API's
// `map`, irslamctl map --out and irslam-sim run --map-out serve (contracts §4).
#ifndef IRSLAM_DAEMON_CORE_JSON_H_
#define IRSLAM_DAEMON_CORE_JSON_H_

#include <nlohmann/json.hpp>
#include <optional>
#include <string>

#include "robot/status.h"

namespace irslam {

nlohmann::json ToJson(const robot::CoreStatus& status);
nlohmann::json ToJson(const robot::MapSnapshot& map);

// The inverse of ToJson(MapSnapshot): a map file or the API's map (contracts §4,
// §7) back into the typed map, every field ToJson writes (a "length" is
// derived from p0/p1 and not read; unknown keys such as "saved" are allowed).
// So ToJson(*map) == j for any map ToJson wrote. False, and a one-line *why
// naming the first bad field ("map.lines[3].cov[0][1]: not a number"), for
// missing or wrong types, non-finite or absurd numbers, duplicate line or object
// ids, unknown states or kinds, and absurd sizes (kMaxMap* below); *map is then
// unspecified. Never throws. Wall and object side ids that name no line of the
// map are kept, not refused: real maps have them (the model is made at the
// model step; the SLAM merges lines after it), so users of the map skip them.
bool MapFromJson(const nlohmann::json& j, robot::MapSnapshot* map, std::string* why);

// Bounds MapFromJson enforces (a 2-hour mission's map is far below them).
inline constexpr size_t kMaxMapLines = 10000;
inline constexpr size_t kMaxMapObjects = 2000;
inline constexpr size_t kMaxMapTrajectory = 2000000;  // 4 Hz for 5 days
inline constexpr size_t kMaxMapCells = 20000;
inline constexpr size_t kMaxMapPolygon = 20000;       // points of one cell outline or route
inline constexpr double kMaxMapCoordM = 1000;         // |x|, |y|, |rho|

// The odometry calibration's JSON view (status slam.calibration, the map's
// "calibration"): {"scale": [left, right, base], "std": [3], "ratio", "ratio_std"}
// with the scale factors of the nominal left/right wheel radius and track width.
nlohmann::json CalibrationJson(const slam::CalibrationEstimate& c);
// The calibration kept in a map, when it has one that checks out (scale factors
// within [0.5, 1.5], standard deviations within [0, 0.5]); else nullopt.
std::optional<slam::CalibrationEstimate> CalibrationFromMap(const nlohmann::json& map);

}  // namespace irslam

#endif  // IRSLAM_DAEMON_CORE_JSON_H_
