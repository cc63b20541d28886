// irslam-foxglove's channels and their JSON Schemas (daemon/foxglove_messages.h:
// IrslamChannels, SchemaFor); the messages themselves are built in
// foxglove_messages.cc.
#include "daemon/foxglove_messages.h"

#include <string>

namespace irslam::foxglove {

using nlohmann::json;

// Foxglove's published schemas (foxglove/schemas, jsonschema/),
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

// An object schema: Foxglove's message and primitive schemas all have this form.
json ObjectSchema(const char* title, const char* description, json properties) {
  return {{"title", title},
          {"description", description},
          {"type", "object"},
          {"properties", std::move(properties)}};
}

json Vector3Schema(const char* description) {
  return ObjectSchema("foxglove.Vector3", description,
                      {{"x", Number("x coordinate length")},
                       {"y", Number("y coordinate length")},
                       {"z", Number("z coordinate length")}});
}

json QuaternionSchema(const char* description) {
  return ObjectSchema("foxglove.Quaternion", description,
                      {{"x", Number("x value")},
                       {"y", Number("y value")},
                       {"z", Number("z value")},
                       {"w", Number("w value")}});
}

json PoseSchema(const char* description) {
  return ObjectSchema(
      "foxglove.Pose", description,
      {{"position", Vector3Schema("Point denoting position in 3D space")},
       {"orientation", QuaternionSchema("Quaternion denoting orientation in 3D space")}});
}

json ColorSchema(const char* description) {
  return ObjectSchema("foxglove.Color", description,
                      {{"r", Number("Red value between 0 and 1")},
                       {"g", Number("Green value between 0 and 1")},
                       {"b", Number("Blue value between 0 and 1")},
                       {"a", Number("Alpha value between 0 and 1")}});
}

json Point3Schema() {
  return ObjectSchema("foxglove.Point3", "A point representing a position in 3D space",
                      {{"x", Number("x coordinate position")},
                       {"y", Number("y coordinate position")},
                       {"z", Number("z coordinate position")}});
}

json ArrayOf(json items, const char* description) {
  return {{"type", "array"}, {"items", std::move(items)}, {"description", description}};
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

json LineTypeSchema() {
  return {{"title", "foxglove.LineType"},
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
}

json ArrowSchema() {
  return ObjectSchema(
      "foxglove.ArrowPrimitive", "A primitive representing an arrow",
      {{"pose", PoseSchema("Position of the arrow's tail and orientation of the arrow")},
       {"shaft_length", Number("Length of the arrow shaft")},
       {"shaft_diameter", Number("Diameter of the arrow shaft")},
       {"head_length", Number("Length of the arrow head")},
       {"head_diameter", Number("Diameter of the arrow head")},
       {"color", ColorSchema("Color of the arrow")}});
}

json CubeSchema() {
  return ObjectSchema(
      "foxglove.CubePrimitive", "A primitive representing a cube or rectangular prism",
      ShapeProperties("Position of the center of the cube and orientation of the cube",
                      "Size of the cube along each axis", "Color of the cube"));
}

json SphereSchema() {
  return ObjectSchema(
      "foxglove.SpherePrimitive", "A primitive representing a sphere or ellipsoid",
      ShapeProperties("Position of the center of the sphere and orientation of the sphere",
                      "Size (diameter) of the sphere along each axis", "Color of the sphere"));
}

json CylinderSchema() {
  json cylinder_props =
      ShapeProperties("Position of the center of the cylinder and orientation of the cylinder",
                      "Size of the cylinder's bounding box", "Color of the cylinder");
  cylinder_props["bottom_scale"] =
      Number("0-1, ratio of the diameter of the cylinder's bottom face");
  cylinder_props["top_scale"] = Number("0-1, ratio of the diameter of the cylinder's top face");
  return ObjectSchema("foxglove.CylinderPrimitive",
                      "A primitive representing a cylinder, elliptic cylinder, or truncated cone",
                      cylinder_props);
}

json LineSchema() {
  return ObjectSchema(
      "foxglove.LinePrimitive", "A primitive representing a series of points connected by lines",
      {{"type", LineTypeSchema()},
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
}

json TriangleListSchema() {
  return ObjectSchema(
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
}

json TextSchema() {
  return ObjectSchema(
      "foxglove.TextPrimitive", "A primitive representing a text label",
      {{"pose", PoseSchema("Position of the center of the text box and orientation of the text")},
       {"billboard", Bool("Whether the text should respect `pose.orientation` (false) or always "
                          "face the camera (true)")},
       {"font_size", Number("Font size (height of one line of text)")},
       {"scale_invariant", Bool("Indicates whether `font_size` is a fixed size in screen pixels "
                                "(true), or specified in world coordinates")},
       {"color", ColorSchema("Color of the text")},
       {"text", Str("Text")}});
}

json ModelSchema() {
  return ObjectSchema(
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
}

json KeyValuePairSchema() {
  return ObjectSchema("foxglove.KeyValuePair", "A key with its associated value",
                      {{"key", Str("Key")}, {"value", Str("Value")}});
}

json SceneEntitySchema() {
  return ObjectSchema(
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
            KeyValuePairSchema(),
            "Additional user-provided metadata associated with the entity. Keys must be unique.")},
       {"arrows", ArrayOf(ArrowSchema(), "Arrow primitives")},
       {"cubes", ArrayOf(CubeSchema(), "Cube primitives")},
       {"spheres", ArrayOf(SphereSchema(), "Sphere primitives")},
       {"cylinders", ArrayOf(CylinderSchema(), "Cylinder primitives")},
       {"lines", ArrayOf(LineSchema(), "Line primitives")},
       {"triangles", ArrayOf(TriangleListSchema(), "Triangle list primitives")},
       {"texts", ArrayOf(TextSchema(), "Text primitives")},
       {"models", ArrayOf(ModelSchema(), "Model primitives")}});
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
  json deletion = ObjectSchema(
      "foxglove.SceneEntityDeletion", "Command to remove previously published entities",
      {{"timestamp", TimeSchema("Timestamp of the deletion. Only matching entities earlier than "
                                "this timestamp will be deleted.")},
       {"type", deletion_type},
       {"id", Str("Identifier which must match if `type` is `MATCHING_ID`.")}});
  json s = ObjectSchema(
      "foxglove.SceneUpdate", "An update to the entities displayed in a 3D scene",
      {{"deletions", ArrayOf(deletion, "Scene entities to delete")},
       {"entities", ArrayOf(SceneEntitySchema(), "Scene entities to add or replace")}});
  s["$comment"] = "Foxglove's foxglove.SceneUpdate, as published in foxglove/schemas";
  return s;
}

json FrameTransformSchema() {
  json s = ObjectSchema("foxglove.FrameTransform",
                        "A transform between two reference frames in 3D space",
                        {{"timestamp", TimeSchema("Timestamp of transform")},
                         {"parent_frame_id", Str("Name of the parent frame")},
                         {"child_frame_id", Str("Name of the child frame")},
                         {"translation", Vector3Schema("Translation component of the transform")},
                         {"rotation", QuaternionSchema("Rotation component of the transform")}});
  return s;
}

json PoseInFrameSchema() {
  return ObjectSchema("foxglove.PoseInFrame",
                      "A timestamped pose for an object or reference frame in 3D space",
                      {{"timestamp", TimeSchema("Timestamp of pose")},
                       {"frame_id", Str("Frame of reference for pose position and orientation")},
                       {"pose", PoseSchema("Pose in 3D space")}});
}

json PosesInFrameSchema() {
  return ObjectSchema(
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
  return ObjectSchema(
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
       {"pose", ObjectSchema("irslam.Pose2", "The pose estimate in the map frame",
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

}  // namespace irslam::foxglove
