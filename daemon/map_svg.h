// Renders a map (contracts.md §4) as SVG: mapped lines with covariance ellipses,
// room and objects, the corrected trajectory; and, when given a truth file and a
// world (the simulator), the true room, true and odometry trajectories.
#ifndef IRSLAM_DAEMON_MAP_SVG_H_
#define IRSLAM_DAEMON_MAP_SVG_H_

#include <nlohmann/json.hpp>
#include <string>

namespace irslam {

// truth/world may be null. world is the world file's JSON (room outline, boxes);
// the truth file's trajectories are in the world frame, the map in the map frame:
// the map is drawn in the world frame through the start pose of the truth file.
std::string RenderMapSvg(const nlohmann::json& map, const nlohmann::json& truth,
                         const nlohmann::json& world);

}  // namespace irslam

#endif  // IRSLAM_DAEMON_MAP_SVG_H_
