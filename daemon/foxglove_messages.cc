#include "daemon/foxglove_messages.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace irslam::foxglove {

using nlohmann::json;

// ---------------------------------------------------------------------------
// JSON Schemas: Foxglove's published schemas (foxglove/schemas, jsonschema/),
// written out field for field with the same titles, types and enums.
namespace {

json Number(const char* description) { return {{"type", "number"}, {"description", description}}; }
json Str(const char* description) { return {{"type", "string"}, {"description", description}}; }
json Bool(const char* description) { return {{"type", "boolean"}, {"description", description}}; }

json TimeSchema(const char* description) {
  return {{"type", "object"},
          {"title", "time"},
          {"properties",
           {{"sec", {{"type", "integer"}, {"minimum", 0}}},
            {"nsec", {{"type", "integer"}, {"minimum", 0}, {"maximum", 999999999}}}}},
          {"description", description}};
}

json DurationSchema(const char* description) {
  return {{"type", "object"},
          {"title", "duration"},
          {"properties",
           {{"sec", {{"type", "integer"}}},
            {"nsec", {{"type", "integer"}, {"minimum", 0}, {"maximum", 999999999}}}}},
          {"description", description}};
}

json Vector3Schema(const char* description) {
  return {{"title", "foxglove.Vector3"},
          {"description", description},
          {"type", "object"},
          {"properties",
           {{"x", Number("x coordinate length")},
            {"y", Number("y coordinate length")},
            {"z", Number("z coordinate length")}}}};
}

json QuaternionSchema(const char* description) {
  return {{"title", "foxglove.Quaternion"},
          {"description", description},
          {"type", "object"},
          {"properties",
           {{"x", Number("x value")},
            {"y", Number("y value")},
            {"z", Number("z value")},
            {"w", Number("w value")}}}};
}

json PoseSchema(const char* description) {
  return {{"title", "foxglove.Pose"},
          {"description", description},
          {"type", "object"},
          {"properties",
           {{"position", Vector3Schema("Point denoting position in 3D space")},
            {"orientation", QuaternionSchema("Quaternion denoting orientation in 3D space")}}}};
}

json ColorSchema(const char* description) {
  return {{"title", "foxglove.Color"},
          {"description", description},
          {"type", "object"},
          {"properties",
           {{"r", Number("Red value between 0 and 1")},
            {"g", Number("Green value between 0 and 1")},
            {"b", Number("Blue value between 0 and 1")},
            {"a", Number("Alpha value between 0 and 1")}}}};
}

json Point3Schema() {
  return {{"title", "foxglove.Point3"},
          {"description", "A point representing a position in 3D space"},
          {"type", "object"},
          {"properties",
           {{"x", Number("x coordinate position")},
            {"y", Number("y coordinate position")},
            {"z", Number("z coordinate position")}}}};
}

json ArrayOf(json items, const char* description) {
  return {{"type", "array"}, {"items", std::move(items)}, {"description", description}};
}

json Primitive(const char* title, const char* description, json properties) {
  return {{"title", title},
          {"description", description},
          {"type", "object"},
          {"properties", std::move(properties)}};
}

json ShapeProperties(const char* pose_description, const char* size_description,
                     const char* color_description) {
  return {{"pose", PoseSchema(pose_description)},
          {"size", Vector3Schema(size_description)},
          {"color", ColorSchema(color_description)}};
}

json IndexArray(const char* description) {
  return ArrayOf({{"type", "integer"}, {"minimum", 0}}, description);
}

json SceneEntitySchema() {
  json line_type = {{"title", "foxglove.LineType"},
                    {"description", "Drawing primitive to use for lines"},
                    {"oneOf",
                     {{{"title", "LINE_STRIP"},
                       {"const", 0},
                       {"description", "Connected line segments: 0-1, 1-2, ..., (n-1)-n"}},
                      {{"title", "LINE_LOOP"},
                       {"const", 1},
                       {"description", "Closed polygon: 0-1, 1-2, ..., (n-1)-n, n-0"}},
                      {{"title", "LINE_LIST"},
                       {"const", 2},
                       {"description", "Individual line segments: 0-1, 2-3, 4-5, ..."}}}}};
  json arrow =
      Primitive("foxglove.ArrowPrimitive", "A primitive representing an arrow",
                {{"pose", PoseSchema("Position of the arrow's tail and orientation of the arrow")},
                 {"shaft_length", Number("Length of the arrow shaft")},
                 {"shaft_diameter", Number("Diameter of the arrow shaft")},
                 {"head_length", Number("Length of the arrow head")},
                 {"head_diameter", Number("Diameter of the arrow head")},
                 {"color", ColorSchema("Color of the arrow")}});
  json cube =
      Primitive("foxglove.CubePrimitive", "A primitive representing a cube or rectangular prism",
                ShapeProperties("Position of the center of the cube and orientation of the cube",
                                "Size of the cube along each axis", "Color of the cube"));
  json sphere = Primitive(
      "foxglove.SpherePrimitive", "A primitive representing a sphere or ellipsoid",
      ShapeProperties("Position of the center of the sphere and orientation of the sphere",
                      "Size (diameter) of the sphere along each axis", "Color of the sphere"));
  json cylinder_props =
      ShapeProperties("Position of the center of the cylinder and orientation of the cylinder",
                      "Size of the cylinder's bounding box", "Color of the cylinder");
  cylinder_props["bottom_scale"] =
      Number("0-1, ratio of the diameter of the cylinder's bottom face");
  cylinder_props["top_scale"] = Number("0-1, ratio of the diameter of the cylinder's top face");
  json cylinder = Primitive(
      "foxglove.CylinderPrimitive",
      "A primitive representing a cylinder, elliptic cylinder, or truncated cone", cylinder_props);
  json line = Primitive(
      "foxglove.LinePrimitive", "A primitive representing a series of points connected by lines",
      {{"type", line_type},
       {"pose", PoseSchema("Origin of lines relative to reference frame")},
       {"thickness", Number("Line thickness")},
       {"scale_invariant",
        Bool("Indicates whether `thickness` is a fixed size in screen pixels (true), or specified "
             "in "
             "world coordinates and scales with distance from the camera (false)")},
       {"points", ArrayOf(Point3Schema(), "Points along the line")},
       {"color",
        ColorSchema(
            "Solid color to use for the whole line. One of `color` or `colors` must be provided.")},
       {"colors", ArrayOf(ColorSchema("A color in RGBA format"),
                          "Per-point colors (if specified, must have the same "
                          "length as `points`). One of `color` or `colors` "
                          "must be provided.")},
       {"indices",
        IndexArray(
            "Indices into the `points` and `colors` attribute arrays, which can be used to avoid "
            "duplicating attribute data.")}});
  json triangles = Primitive(
      "foxglove.TriangleListPrimitive",
      "A primitive representing a set of triangles or a surface tiled by triangles",
      {{"pose", PoseSchema("Origin of triangles relative to reference frame")},
       {"points", ArrayOf(Point3Schema(),
                          "Vertices to use for triangles, interpreted as a list of triples (0-1-2, "
                          "3-4-5, ...)")},
       {"color", ColorSchema("Solid color to use for the whole shape. One of `color` or `colors` "
                             "must be provided.")},
       {"colors", ArrayOf(ColorSchema("A color in RGBA format"), "Per-vertex colors")},
       {"indices", IndexArray("Indices into the `points` and `colors` attribute arrays")}});
  json text = Primitive(
      "foxglove.TextPrimitive", "A primitive representing a text label",
      {{"pose", PoseSchema("Position of the center of the text box and orientation of the text")},
       {"billboard", Bool("Whether the text should respect `pose.orientation` (false) or always "
                          "face the camera (true)")},
       {"font_size", Number("Font size (height of one line of text)")},
       {"scale_invariant", Bool("Indicates whether `font_size` is a fixed size in screen pixels "
                                "(true), or specified in world coordinates")},
       {"color", ColorSchema("Color of the text")},
       {"text", Str("Text")}});
  json model = Primitive(
      "foxglove.ModelPrimitive",
      "A primitive representing a 3D model file loaded from an external URL or embedded data",
      {{"pose", PoseSchema("Origin of model relative to reference frame")},
       {"scale", Vector3Schema("Scale factor to apply to the model along each axis")},
       {"color", ColorSchema("Solid color to use for the whole model")},
       {"override_color", Bool("Whether to use the color specified in `color` instead of any "
                               "materials embedded in the original model.")},
       {"url", Str("URL pointing to model file. One of `url` or `data` should be provided.")},
       {"media_type", Str("Model type")},
       {"data",
        {{"type", "string"}, {"contentEncoding", "base64"}, {"description", "Embedded model"}}}});
  json kv = Primitive("foxglove.KeyValuePair", "A key with its associated value",
                      {{"key", Str("Key")}, {"value", Str("Value")}});
  return Primitive(
      "foxglove.SceneEntity",
      "A visual element in a 3D scene. An entity may be composed of multiple primitives which "
      "all share the same frame of reference.",
      {{"timestamp", TimeSchema("Timestamp of the entity")},
       {"frame_id", Str("Frame of reference")},
       {"id", Str("Identifier for the entity. A entity will replace any prior entity on the same "
                  "topic with the same "
                  "`id`.")},
       {"lifetime",
        DurationSchema(
            "Length of time (relative to `timestamp`) after which the entity should be "
            "automatically removed. Zero value indicates the entity should remain visible "
            "until it is replaced or deleted.")},
       {"frame_locked",
        Bool("Whether the entity should keep its location in the fixed frame (false) or follow the "
             "frame specified in `frame_id` as it moves relative to the fixed frame (true)")},
       {"metadata",
        ArrayOf(
            kv,
            "Additional user-provided metadata associated with the entity. Keys must be unique.")},
       {"arrows", ArrayOf(arrow, "Arrow primitives")},
       {"cubes", ArrayOf(cube, "Cube primitives")},
       {"spheres", ArrayOf(sphere, "Sphere primitives")},
       {"cylinders", ArrayOf(cylinder, "Cylinder primitives")},
       {"lines", ArrayOf(line, "Line primitives")},
       {"triangles", ArrayOf(triangles, "Triangle list primitives")},
       {"texts", ArrayOf(text, "Text primitives")},
       {"models", ArrayOf(model, "Model primitives")}});
}

json SceneUpdateSchema() {
  json deletion_type = {
      {"title", "foxglove.SceneEntityDeletionType"},
      {"description", "Type of deletion action to perform"},
      {"oneOf",
       {{{"title", "MATCHING_ID"},
         {"const", 0},
         {"description",
          "Delete the existing entity on the same topic that has the provided `id`"}},
        {{"title", "ALL"},
         {"const", 1},
         {"description", "Delete all existing entities on the same topic"}}}}};
  json deletion = Primitive(
      "foxglove.SceneEntityDeletion", "Command to remove previously published entities",
      {{"timestamp", TimeSchema("Timestamp of the deletion. Only matching entities earlier than "
                                "this timestamp will be deleted.")},
       {"type", deletion_type},
       {"id", Str("Identifier which must match if `type` is `MATCHING_ID`.")}});
  json s =
      Primitive("foxglove.SceneUpdate", "An update to the entities displayed in a 3D scene",
                {{"deletions", ArrayOf(deletion, "Scene entities to delete")},
                 {"entities", ArrayOf(SceneEntitySchema(), "Scene entities to add or replace")}});
  s["$comment"] = "Foxglove's foxglove.SceneUpdate, as published in foxglove/schemas";
  return s;
}

json FrameTransformSchema() {
  json s =
      Primitive("foxglove.FrameTransform", "A transform between two reference frames in 3D space",
                {{"timestamp", TimeSchema("Timestamp of transform")},
                 {"parent_frame_id", Str("Name of the parent frame")},
                 {"child_frame_id", Str("Name of the child frame")},
                 {"translation", Vector3Schema("Translation component of the transform")},
                 {"rotation", QuaternionSchema("Rotation component of the transform")}});
  return s;
}

json PoseInFrameSchema() {
  return Primitive("foxglove.PoseInFrame",
                   "A timestamped pose for an object or reference frame in 3D space",
                   {{"timestamp", TimeSchema("Timestamp of pose")},
                    {"frame_id", Str("Frame of reference for pose position and orientation")},
                    {"pose", PoseSchema("Pose in 3D space")}});
}

json PosesInFrameSchema() {
  return Primitive(
      "foxglove.PosesInFrame",
      "An array of timestamped poses for an object or reference frame in 3D space",
      {{"timestamp", TimeSchema("Timestamp of pose")},
       {"frame_id", Str("Frame of reference for pose position and orientation")},
       {"poses",
        ArrayOf(
            PoseSchema("A position and orientation for an object or reference frame in 3D space"),
            "Poses in 3D space")}});
}

json StateSchema() {
  json nullable_number = {{"type", {"number", "null"}}};
  return Primitive(
      "irslam.State",
      "irslamd's mission state and cleaning progress (irslam-foxglove, docs/foxglove.md)",
      {{"timestamp", TimeSchema("When irslam-foxglove received the status")},
       {"connected",
        Bool("irslam-foxglove reaches irslamd (false: the other fields but error are empty)")},
       {"error", Str("Why irslamd cannot be reached (empty when connected)")},
       {"state",
        Str("Mission state (contracts §6: idle, wall_follow, model, go_to_p1, contour_follow, "
            "relocalize, "
            "clean, return_home, done, fault); \"disconnected\" when irslamd cannot be reached")},
       {"reason", Str("Why the mission is in this state (e.g. a fault's cause)")},
       {"behaviour", Str("The behaviour that drives the robot")},
       {"robot_time", Number("Robot time of the status, s")},
       {"pose", Primitive("irslam.Pose2", "The pose estimate in the map frame",
                          {{"x", Number("m")}, {"y", Number("m")}, {"theta", Number("rad")}})},
       {"lines", {{"type", "integer"}, {"description", "Lines in the map"}}},
       {"objects", {{"type", "integer"}, {"description", "Objects modelled"}}},
       {"controller_alive", Bool("The motor controller is heard")},
       {"battery_v", Number("Battery voltage the controller reports, V")},
       {"estop", Bool("Emergency stop active")},
       {"cleaning_state", Str("Cleaning progress state (empty when no cleaning ran)")},
       {"cleaning_fraction",
        Number("Part of the cleanable area covered, 0..1 (0 when no cleaning ran)")},
       {"cleaning_covered_m2", Number("Area covered, m^2")},
       {"cleaning_total_m2", Number("Cleanable area, m^2")},
       {"cleaning_eta_s", nullable_number}});
}

}  // namespace

json SchemaFor(const std::string& name) {
  if (name == "foxglove.SceneUpdate") return SceneUpdateSchema();
  if (name == "foxglove.FrameTransform") return FrameTransformSchema();
  if (name == "foxglove.PoseInFrame") return PoseInFrameSchema();
  if (name == "foxglove.PosesInFrame") return PosesInFrameSchema();
  if (name == "irslam.State") return StateSchema();
  return json();
}

std::vector<Channel> IrslamChannels() {
  const auto ch = [](uint32_t id, const char* topic, const char* schema) {
    return Channel{id, topic, schema, SchemaFor(schema)};
  };
  return {ch(kTf, "/tf", "foxglove.FrameTransform"),
          ch(kPose, "/pose", "foxglove.PoseInFrame"),
          ch(kTrajectory, "/trajectory", "foxglove.PosesInFrame"),
          ch(kMapLines, "/map/lines", "foxglove.SceneUpdate"),
          ch(kMapObjects, "/map/objects", "foxglove.SceneUpdate"),
          ch(kMapRoom, "/map/room", "foxglove.SceneUpdate"),
          ch(kIr, "/ir", "foxglove.SceneUpdate"),
          ch(kState, "/state", "irslam.State")};
}

// ---------------------------------------------------------------------------
// Messages.
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
