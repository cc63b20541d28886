// irslam-foxglove's channels and their messages: the JSON Schemas (Foxglove's own
// foxglove.FrameTransform, PoseInFrame, PosesInFrame and SceneUpdate, with the
// same field names, types and enums; and irslam.State, ours) and the messages
// built from irslamd's status (contracts §6) and map (§4) as the API serves them.
// Pure functions of JSON values and a time: tests compare the output.
// Frames: "map" (the robot's own map frame) and "base_link" (the robot, x forward,
// y left); /tf carries map -> base_link.
#ifndef IRSLAM_DAEMON_FOXGLOVE_MESSAGES_H_
#define IRSLAM_DAEMON_FOXGLOVE_MESSAGES_H_

#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <vector>

#include "daemon/foxglove_protocol.h"
#include "types/robot.h"

namespace irslam::foxglove {

// Channel ids (stable: the same topic keeps its id across restarts).
enum ChannelId : uint32_t {
  kTf = 1,
  kPose = 2,
  kTrajectory = 3,
  kMapLines = 4,
  kMapObjects = 5,
  kMapRoom = 6,
  kIr = 7,
  kState = 8,
};

// The eight channels with their schemas.
std::vector<Channel> IrslamChannels();

// The JSON Schemas by name ("foxglove.SceneUpdate", ..., "irslam.State").
nlohmann::json SchemaFor(const std::string& name);

// What the IR view needs to know about the robot (from the daemon's config).
struct RobotShape {
  std::array<SensorMount, kNumIrSensors> mounts{};
  double max_range_m = 1.2;  // a sensor with no reading is drawn this long, grey
  double radius_m = 0.17;    // the body outline
};

// From a status (contracts §6). nullopt when the status has no usable pose.
std::optional<nlohmann::json> FrameTransformMessage(const nlohmann::json& status, uint64_t t_ns);
std::optional<nlohmann::json> PoseMessage(const nlohmann::json& status, uint64_t t_ns);
// The IR rays of the last scan in base_link (a LINE_LIST from each mount to its
// reading; no reading: grey, max range) plus the body outline.
std::optional<nlohmann::json> IrMessage(const nlohmann::json& status, const RobotShape& robot,
                                        uint64_t t_ns);
// irslam.State: state, reason, cleaning progress (connected=false and the error
// when irslamd cannot be reached: pass a null status).
nlohmann::json StateMessage(const nlohmann::json& status, bool connected, const std::string& error,
                            uint64_t t_ns);

// From a map (contracts §4).
// The trajectory, at most max_poses of it (evenly thinned, the last pose kept).
nlohmann::json TrajectoryMessage(const nlohmann::json& map, uint64_t t_ns, size_t max_poses = 2000);
// Each line as a LINE_LIST segment p0-p1 and its covariance ellipse as a LINE_LOOP
// (at the line's centre: 3 sigma of rho across, 3 sigma of theta times the half
// length along, as the SVG map draws it), one entity per line ("line/ID").
nlohmann::json LinesMessage(const nlohmann::json& map, uint64_t t_ns);
// Each object's box as a flat cube and an outline, green when complete, orange
// when not, with a label ("object/ID").
nlohmann::json ObjectsMessage(const nlohmann::json& map, uint64_t t_ns);
// The room's box as a LINE_LOOP (green when every side has a wall line, orange
// when not) and the wall lines by side ("room").
nlohmann::json RoomMessage(const nlohmann::json& map, uint64_t t_ns);

// Points of the covariance ellipse of a line (exposed for the tests).
std::vector<std::array<double, 2>> LineEllipse(const nlohmann::json& line, int points = 24);

}  // namespace irslam::foxglove

#endif  // IRSLAM_DAEMON_FOXGLOVE_MESSAGES_H_
