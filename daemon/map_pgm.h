// The map (contracts §4) as an occupancy grid for ROS map_server: a binary PGM and
// its YAML (irslamctl map --pgm, irslam-sim run --pgm, irslam-replay --pgm). In the
// map frame; row 0 is the top (largest y). Cells: every mapped line (the walls and
// the furniture's sides) occupied (0), the room's inside free (254), the rest
// unknown (205, map_saver's value): outside the room and inside the furniture.
// Rendering is a pure function of the map JSON; WritePgmMap is the file shell.
#ifndef IRSLAM_DAEMON_MAP_PGM_H_
#define IRSLAM_DAEMON_MAP_PGM_H_

#include <cstdint>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

namespace irslam {

inline constexpr double kDefaultPgmResolutionM = 0.05;
inline constexpr uint8_t kPgmOccupied = 0, kPgmFree = 254, kPgmUnknown = 205;

struct PgmImage {
  int width = 0, height = 0;
  double resolution_m = kDefaultPgmResolutionM;
  double origin_x = 0, origin_y = 0;  // map-frame position of the lower-left corner
  std::vector<uint8_t> cells;         // row-major, row 0 at the top
  uint8_t at(int col, int row) const { return cells[static_cast<size_t>(row) * width + col]; }
};

// nullopt with *error on a map without lines or a room, or one too large (over
// 200 m a side).
std::optional<PgmImage> RenderPgm(const nlohmann::json& map, double resolution_m, std::string* error);
std::string EncodePgm(const PgmImage& image);
// ROS map_server's YAML; image_file as written in it (the PGM's file name).
std::string MapServerYaml(const PgmImage& image, const std::string& image_file);
// The YAML's path for FILE.pgm: FILE.yaml (any other name: NAME.yaml).
std::string PgmYamlPath(const std::string& pgm_path);
// Renders and writes pgm_path and its YAML; false with *error.
bool WritePgmMap(const nlohmann::json& map, const std::string& pgm_path, double resolution_m, std::string* error);

}  // namespace irslam

#endif  // IRSLAM_DAEMON_MAP_PGM_H_
