// The JSON views of RobotCore's status and map: the core part of the API's
// `status` (contracts §6; the daemon adds its own keys) and the map the API's
// `map`, irslamctl map --out and irslam-sim run --map-out serve (contracts §4).
#ifndef IRSLAM_DAEMON_CORE_JSON_H_
#define IRSLAM_DAEMON_CORE_JSON_H_

#include <nlohmann/json.hpp>

#include "robot/status.h"

namespace irslam {

nlohmann::json ToJson(const robot::CoreStatus& status);
nlohmann::json ToJson(const robot::MapSnapshot& map);

}  // namespace irslam

#endif  // IRSLAM_DAEMON_CORE_JSON_H_
