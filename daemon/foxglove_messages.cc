#include "daemon/foxglove_messages.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace irslam::foxglove {

using nlohmann::json;

// The messages (the channels' schemas are in foxglove_schemas.cc).
namespace {

constexpr const char* kMapFrame = "map";
constexpr const char* kRobotFrame = "base_link";

struct Rgba {
  double r, g, b, a;
};
constexpr Rgba kBlack{0.05, 0.05, 0.05, 1};
constexpr Rgba kMagenta{0.8, 0.0, 0.8, 1};
constexpr Rgba kGreen{0.1, 0.7, 0.2, 1};
constexpr Rgba kOrange{1.0, 0.55, 0.0, 1};
constexpr Rgba kRed{0.9, 0.1, 0.1, 1};
constexpr Rgba kGrey{0.6, 0.6, 0.6, 0.6};
constexpr Rgba kBlue{0.2, 0.4, 0.8, 1};

json Color(const Rgba& c) { return {{"r", c.r}, {"g", c.g}, {"b", c.b}, {"a", c.a}}; }
json Color(const Rgba& c, double a) { return {{"r", c.r}, {"g", c.g}, {"b", c.b}, {"a", a}}; }
json Vec3(double x, double y, double z) { return {{"x", x}, {"y", y}, {"z", z}}; }
json YawQuaternion(double theta) {
  return {{"x", 0.0}, {"y", 0.0}, {"z", std::sin(theta / 2)}, {"w", std::cos(theta / 2)}};
}
json PoseJson(double x, double y, double theta, double z = 0) {
  return {{"position", Vec3(x, y, z)}, {"orientation", YawQuaternion(theta)}};
}
json IdentityPose() { return PoseJson(0, 0, 0); }

bool IsNumber(const json& j) { return j.is_number() && std::isfinite(j.get<double>()); }

// [x, y, theta] of status/map "pose".
std::optional<std::array<double, 3>> Pose3(const json& j) {
  if (!j.is_object() || !j.contains("pose")) return std::nullopt;
  const json& p = j["pose"];
  if (!p.is_array() || p.size() != 3 || !IsNumber(p[0]) || !IsNumber(p[1]) || !IsNumber(p[2]))
    return std::nullopt;
  return std::array<double, 3>{p[0].get<double>(), p[1].get<double>(), p[2].get<double>()};
}

std::optional<std::array<double, 2>> Point2(const json& j) {
  if (!j.is_array() || j.size() < 2 || !IsNumber(j[0]) || !IsNumber(j[1])) return std::nullopt;
  return std::array<double, 2>{j[0].get<double>(), j[1].get<double>()};
}

// [xmin, ymin, xmax, ymax]
std::optional<std::array<double, 4>> Box(const json& j) {
  if (!j.is_array() || j.size() != 4) return std::nullopt;
  std::array<double, 4> b{};
  for (size_t i = 0; i < 4; ++i) {
    if (!IsNumber(j[i])) return std::nullopt;
    b[i] = j[i].get<double>();
  }
  return b;
}

double NumberOr(const json& j, const char* key, double fallback) {
  if (!j.is_object() || !j.contains(key) || !IsNumber(j[key])) return fallback;
  return j[key].get<double>();
}
std::string StringOr(const json& j, const char* key) {
  if (!j.is_object() || !j.contains(key) || !j[key].is_string()) return "";
  return j[key].get<std::string>();
}
json ArrayOr(const json& j, const char* key) {
  if (!j.is_object() || !j.contains(key) || !j[key].is_array()) return json::array();
  return j[key];
}

json Point(double x, double y, double z = 0) { return Vec3(x, y, z); }

enum LineType { kLineStrip = 0, kLineLoop = 1, kLineList = 2 };

json LinePrimitive(LineType type, json points, const Rgba& color, double thickness) {
  return {{"type", static_cast<int>(type)}, {"pose", IdentityPose()},      {"thickness", thickness},
          {"scale_invariant", false},       {"points", std::move(points)}, {"color", Color(color)},
          {"colors", json::array()},        {"indices", json::array()}};
}

json TextPrimitive(double x, double y, const std::string& text, const Rgba& color) {
  return {{"pose", PoseJson(x, y, 0, 0.05)}, {"billboard", true},     {"font_size", 12.0},
          {"scale_invariant", true},         {"color", Color(color)}, {"text", text}};
}

// A scene entity with every primitive list present (empty where unused).
json Entity(const std::string& id, const char* frame, uint64_t t_ns, bool frame_locked = false) {
  return {{"timestamp", TimeJson(t_ns)},
          {"frame_id", frame},
          {"id", id},
          {"lifetime", {{"sec", 0}, {"nsec", 0}}},
          {"frame_locked", frame_locked},
          {"metadata", json::array()},
          {"arrows", json::array()},
          {"cubes", json::array()},
          {"spheres", json::array()},
          {"cylinders", json::array()},
          {"lines", json::array()},
          {"triangles", json::array()},
          {"texts", json::array()},
          {"models", json::array()}};
}

void AddMetadata(json* entity, const std::string& key, const std::string& value) {
  (*entity)["metadata"].push_back({{"key", key}, {"value", value}});
}

// A SceneUpdate that replaces everything on its topic: delete all, then the entities.
json ReplacingSceneUpdate(json entities, uint64_t t_ns) {
  return {{"deletions", {{{"timestamp", TimeJson(t_ns)}, {"type", 1}, {"id", ""}}}},
          {"entities", std::move(entities)}};
}

std::string IdText(const json& j) {
  if (j.is_object() && j.contains("id") && j["id"].is_number_integer())
    return std::to_string(j["id"].get<int64_t>());
  return "?";
}

std::string Fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

json BoxLoop(const std::array<double, 4>& b, double z = 0) {
  return json::array(
      {Point(b[0], b[1], z), Point(b[2], b[1], z), Point(b[2], b[3], z), Point(b[0], b[3], z)});
}

}  // namespace

std::optional<json> FrameTransformMessage(const json& status, uint64_t t_ns) {
  const auto p = Pose3(status);
  if (!p) return std::nullopt;
  return json{{"timestamp", TimeJson(t_ns)},
              {"parent_frame_id", kMapFrame},
              {"child_frame_id", kRobotFrame},
              {"translation", Vec3((*p)[0], (*p)[1], 0)},
              {"rotation", YawQuaternion((*p)[2])}};
}

std::optional<json> PoseMessage(const json& status, uint64_t t_ns) {
  const auto p = Pose3(status);
  if (!p) return std::nullopt;
  return json{{"timestamp", TimeJson(t_ns)},
              {"frame_id", kMapFrame},
              {"pose", PoseJson((*p)[0], (*p)[1], (*p)[2])}};
}

std::optional<json> IrMessage(const json& status, const RobotShape& robot, uint64_t t_ns) {
  if (!status.is_object() || !status.contains("ir_ranges") || !status["ir_ranges"].is_array())
    return std::nullopt;
  const json& ranges = status["ir_ranges"];
  json hits = json::array(), misses = json::array(), spheres = json::array();
  json rays = Entity("ir", kRobotFrame, t_ns, true);
  for (size_t i = 0; i < robot.mounts.size() && i < ranges.size(); ++i) {
    const SensorMount& m = robot.mounts[i];
    const bool hit = IsNumber(ranges[i]);
    const double r = hit ? ranges[i].get<double>() : robot.max_range_m;
    const double ex = m.x + r * std::cos(m.theta), ey = m.y + r * std::sin(m.theta);
    json& list = hit ? hits : misses;
    list.push_back(Point(m.x, m.y));
    list.push_back(Point(ex, ey));
    if (hit) {
      spheres.push_back({{"pose", PoseJson(ex, ey, 0)},
                         {"size", Vec3(0.04, 0.04, 0.04)},
                         {"color", Color(kRed)}});
    }
    AddMetadata(&rays, "ir" + std::to_string(i), hit ? Fixed(r, 3) : "none");
  }
  if (!hits.empty()) rays["lines"].push_back(LinePrimitive(kLineList, hits, kRed, 0.01));
  if (!misses.empty()) rays["lines"].push_back(LinePrimitive(kLineList, misses, kGrey, 0.005));
  rays["spheres"] = spheres;
  // The body: a circle and a heading tick.
  json body = Entity("body", kRobotFrame, t_ns, true);
  json circle = json::array();
  constexpr int kSegments = 32;
  for (int k = 0; k < kSegments; ++k) {
    const double a = 2 * M_PI * k / kSegments;
    circle.push_back(Point(robot.radius_m * std::cos(a), robot.radius_m * std::sin(a)));
  }
  body["lines"].push_back(LinePrimitive(kLineLoop, circle, kBlue, 0.01));
  body["lines"].push_back(
      LinePrimitive(kLineList, json::array({Point(0, 0), Point(robot.radius_m, 0)}), kBlue, 0.01));
  return ReplacingSceneUpdate(json::array({rays, body}), t_ns);
}

json StateMessage(const json& status, bool connected, const std::string& error, uint64_t t_ns) {
  const auto p = connected ? Pose3(status) : std::nullopt;
  json cleaning =
      connected && status.is_object() && status.contains("cleaning") ? status["cleaning"] : json();
  json eta = cleaning.is_object() && cleaning.contains("eta_s") && IsNumber(cleaning["eta_s"])
                 ? cleaning["eta_s"]
                 : json();
  const json controller = connected && status.is_object() && status.contains("controller")
                              ? status["controller"]
                              : json();
  const json safety =
      connected && status.is_object() && status.contains("safety") ? status["safety"] : json();
  return {
      {"timestamp", TimeJson(t_ns)},
      {"connected", connected},
      {"error", connected ? "" : error},
      {"state", connected ? StringOr(status, "state") : "disconnected"},
      {"reason", connected ? StringOr(status, "reason") : ""},
      {"behaviour", connected ? StringOr(status, "behaviour") : ""},
      {"robot_time", connected ? NumberOr(status, "robot_time", 0) : 0.0},
      {"pose", {{"x", p ? (*p)[0] : 0.0}, {"y", p ? (*p)[1] : 0.0}, {"theta", p ? (*p)[2] : 0.0}}},
      {"lines", connected ? static_cast<int64_t>(NumberOr(status, "lines", 0)) : 0},
      {"objects", connected ? static_cast<int64_t>(NumberOr(status, "objects", 0)) : 0},
      {"controller_alive", controller.is_object() && controller.value("alive", false)},
      {"battery_v", NumberOr(controller, "battery", 0)},
      {"estop", safety.is_object() && safety.value("estop", false)},
      {"cleaning_state", StringOr(cleaning, "state")},
      {"cleaning_fraction", NumberOr(cleaning, "fraction", 0)},
      {"cleaning_covered_m2", NumberOr(cleaning, "covered_m2", 0)},
      {"cleaning_total_m2", NumberOr(cleaning, "total_m2", 0)},
      {"cleaning_eta_s", eta}};
}

json TrajectoryMessage(const json& map, uint64_t t_ns, size_t max_poses) {
  std::vector<std::array<double, 3>> all;
  for (const auto& s : ArrayOr(map, "trajectory")) {
    if (s.is_array() && s.size() == 4 && IsNumber(s[1]) && IsNumber(s[2]) && IsNumber(s[3])) {
      all.push_back({s[1].get<double>(), s[2].get<double>(), s[3].get<double>()});
    }
  }
  json poses = json::array();
  const size_t n = all.size();
  const size_t keep = std::min(n, std::max<size_t>(max_poses, 2));
  for (size_t k = 0; k < keep; ++k) {
    // Evenly spread indices from 0 to n-1 (the first and the last pose kept).
    const size_t i = keep == 1 ? 0 : (k * (n - 1) + (keep - 1) / 2) / (keep - 1);
    poses.push_back(PoseJson(all[i][0], all[i][1], all[i][2]));
  }
  return {{"timestamp", TimeJson(t_ns)}, {"frame_id", kMapFrame}, {"poses", poses}};
}

std::vector<std::array<double, 2>> LineEllipse(const json& line, int points) {
  std::vector<std::array<double, 2>> out;
  const auto p0 = line.is_object() && line.contains("p0") ? Point2(line["p0"]) : std::nullopt;
  const auto p1 = line.is_object() && line.contains("p1") ? Point2(line["p1"]) : std::nullopt;
  if (!p0 || !p1) return out;
  double srr = 0, stt = 0;
  if (line.contains("cov") && line["cov"].is_array() && line["cov"].size() == 2) {
    const json& c = line["cov"];
    if (c[0].is_array() && c[0].size() == 2 && IsNumber(c[0][0]))
      srr = std::sqrt(std::max(0.0, c[0][0].get<double>()));
    if (c[1].is_array() && c[1].size() == 2 && IsNumber(c[1][1]))
      stt = std::sqrt(std::max(0.0, c[1][1].get<double>()));
  }
  const double dx = (*p1)[0] - (*p0)[0], dy = (*p1)[1] - (*p0)[1];
  const double len = std::hypot(dx, dy);
  const double ux = len > 0 ? dx / len : 1, uy = len > 0 ? dy / len : 0;
  const double cx = 0.5 * ((*p0)[0] + (*p1)[0]), cy = 0.5 * ((*p0)[1] + (*p1)[1]);
  const double a = std::max(0.01, 3 * stt * len / 2);  // along the line
  const double b = std::max(0.005, 3 * srr);           // across it
  for (int k = 0; k < points; ++k) {
    const double phi = 2 * M_PI * k / points;
    const double along = a * std::cos(phi), across = b * std::sin(phi);
    out.push_back({cx + along * ux - across * uy, cy + along * uy + across * ux});
  }
  return out;
}

json LinesMessage(const json& map, uint64_t t_ns) {
  json entities = json::array();
  for (const auto& l : ArrayOr(map, "lines")) {
    const auto p0 = l.is_object() && l.contains("p0") ? Point2(l["p0"]) : std::nullopt;
    const auto p1 = l.is_object() && l.contains("p1") ? Point2(l["p1"]) : std::nullopt;
    if (!p0 || !p1) continue;
    json e = Entity("line/" + IdText(l), kMapFrame, t_ns);
    e["lines"].push_back(LinePrimitive(
        kLineList, json::array({Point((*p0)[0], (*p0)[1]), Point((*p1)[0], (*p1)[1])}), kBlack,
        0.03));
    json ellipse = json::array();
    for (const auto& q : LineEllipse(l)) ellipse.push_back(Point(q[0], q[1]));
    e["lines"].push_back(LinePrimitive(kLineLoop, ellipse, kMagenta, 0.008));
    e["texts"].push_back(
        TextPrimitive(0.5 * ((*p0)[0] + (*p1)[0]), 0.5 * ((*p0)[1] + (*p1)[1]), IdText(l), kBlack));
    AddMetadata(&e, "rho", Fixed(NumberOr(l, "rho", 0), 4));
    AddMetadata(&e, "theta", Fixed(NumberOr(l, "theta", 0), 4));
    AddMetadata(&e, "length", Fixed(NumberOr(l, "length", 0), 3));
    AddMetadata(&e, "observations",
                std::to_string(static_cast<int64_t>(NumberOr(l, "observations", 0))));
    entities.push_back(std::move(e));
  }
  return ReplacingSceneUpdate(std::move(entities), t_ns);
}

json ObjectsMessage(const json& map, uint64_t t_ns) {
  json entities = json::array();
  for (const auto& o : ArrayOr(map, "objects")) {
    const auto b = o.is_object() && o.contains("box") ? Box(o["box"]) : std::nullopt;
    if (!b) continue;
    const bool complete = o.value("complete", false);
    const Rgba& c = complete ? kGreen : kOrange;
    json e = Entity("object/" + IdText(o), kMapFrame, t_ns);
    const double cx = 0.5 * ((*b)[0] + (*b)[2]), cy = 0.5 * ((*b)[1] + (*b)[3]);
    e["cubes"].push_back(
        {{"pose", PoseJson(cx, cy, 0, 0.025)},
         {"size", Vec3(std::max(0.0, (*b)[2] - (*b)[0]), std::max(0.0, (*b)[3] - (*b)[1]), 0.05)},
         {"color", Color(c, 0.35)}});
    e["lines"].push_back(LinePrimitive(kLineLoop, BoxLoop(*b, 0.05), c, 0.02));
    const std::string kind = StringOr(o, "kind");
    e["texts"].push_back(TextPrimitive(
        cx, cy, "object " + IdText(o) + " " + kind + (complete ? "" : " (incomplete)"), c));
    AddMetadata(&e, "kind", kind);
    AddMetadata(&e, "complete", complete ? "true" : "false");
    AddMetadata(&e, "lines", o.contains("lines") ? o["lines"].dump() : "[]");
    entities.push_back(std::move(e));
  }
  return ReplacingSceneUpdate(std::move(entities), t_ns);
}

json RoomMessage(const json& map, uint64_t t_ns) {
  json entities = json::array();
  const json room = map.is_object() && map.contains("room") && map["room"].is_object()
                        ? map["room"]
                        : json::object();
  const json walls =
      room.contains("walls") && room["walls"].is_object() ? room["walls"] : json::object();
  bool every_side = true;
  for (const char* side : {"bottom", "right", "top", "left"}) {
    if (!walls.contains(side) || !walls[side].is_array() || walls[side].empty()) every_side = false;
  }
  const auto box = room.contains("box") ? Box(room["box"]) : std::nullopt;
  const bool complete = box && every_side;
  const Rgba& c = complete ? kGreen : kOrange;
  json e = Entity("room", kMapFrame, t_ns);
  if (box) {
    e["lines"].push_back(LinePrimitive(kLineLoop, BoxLoop(*box, 0.01), c, 0.015));
    e["texts"].push_back(
        TextPrimitive((*box)[0], (*box)[1], complete ? "room" : "room (incomplete)", c));
  }
  // The wall lines by side, drawn over the map's lines.
  json wall_points = json::array();
  for (const auto& [side, ids] : walls.items()) {
    if (!ids.is_array()) continue;
    for (const auto& id : ids) {
      for (const auto& l : ArrayOr(map, "lines")) {
        if (!l.is_object() || !l.contains("id") || l["id"] != id) continue;
        const auto p0 = l.contains("p0") ? Point2(l["p0"]) : std::nullopt;
        const auto p1 = l.contains("p1") ? Point2(l["p1"]) : std::nullopt;
        if (!p0 || !p1) continue;
        wall_points.push_back(Point((*p0)[0], (*p0)[1], 0.01));
        wall_points.push_back(Point((*p1)[0], (*p1)[1], 0.01));
      }
    }
    AddMetadata(&e, side, ids.dump());
  }
  if (!wall_points.empty()) e["lines"].push_back(LinePrimitive(kLineList, wall_points, c, 0.05));
  AddMetadata(&e, "complete", complete ? "true" : "false");
  entities.push_back(std::move(e));
  return ReplacingSceneUpdate(std::move(entities), t_ns);
}

}  // namespace irslam::foxglove
