// Checks that a map (contracts.md §4) has the fields and JSON types every reader
// relies on (irslamctl map --svg, irslam-sim --map-in), before the daemon serves
// a map it did not make itself (the saved file of a previous run). Pure.
//
// Required: "frame" and "state" (strings), "lines" and "objects" (arrays).
// Checked when present: "pose" [3 numbers], "pose_cov" 3x3 numbers, "room"
// {"walls": {side: [ints]}, "box": null or 4 numbers}, "trajectory" [[4 numbers]].
// Each line: "id" integer, "rho", "theta" numbers, "cov" 2x2 numbers, "p0", "p1"
// [2 numbers], optional "length" number. Optional "calibration" (the odometry's,
// daemon/core_json.h): "scale" and "std" [3 numbers], optional "ratio" and
// "ratio_std" numbers. Each object: "id" integer, "kind"
// string, "lines" [ints], optional "complete" bool and "box" 4 numbers.
// Unknown keys are allowed (§4 is extended compatibly, e.g. "cleaning").
#ifndef IRSLAM_DAEMON_MAP_VALIDATE_H_
#define IRSLAM_DAEMON_MAP_VALIDATE_H_

#include <nlohmann/json.hpp>
#include <string>

namespace irslam {

// True when map checks out; otherwise false and a one-line *error naming the
// first field that does not (e.g. "lines[3].p0: not an array of 2 numbers").
bool ValidateMapBody(const nlohmann::json& map, std::string* error);

}  // namespace irslam

#endif  // IRSLAM_DAEMON_MAP_VALIDATE_H_
