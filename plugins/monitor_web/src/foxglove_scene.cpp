#include "foxglove_scene.hpp"

#include <plr/sim/unaligned.hpp>

#include <nlohmann/json.hpp>

#include <algorithm>

namespace plr::monitor_web {

namespace {

using nlohmann::json;

// ---- The JSON Schema, built from Foxglove's message definitions ----------
// (https://github.com/foxglove/schemas: SceneUpdate and the types it holds).
// Foxglove lists every field and requires none; a JSON message may omit any.

json typed(const char* type, const char* description) {
  return {{"type", type}, {"description", description}};
}

json integer(std::optional<std::int64_t> minimum, std::optional<std::int64_t> maximum) {
  json j = {{"type", "integer"}};
  if (minimum) j["minimum"] = *minimum;
  if (maximum) j["maximum"] = *maximum;
  return j;
}

json object(const char* title, const char* description, json properties) {
  return {{"title", title},
          {"description", description},
          {"type", "object"},
          {"properties", std::move(properties)}};
}

json array(json items, const char* description) {
  return {{"type", "array"}, {"items", std::move(items)}, {"description", description}};
}

struct Choice {
  const char* name;
  int value;
  const char* description;
};

json one_of(const char* title, const char* description, std::initializer_list<Choice> choices) {
  json list = json::array();
  for (const auto& c : choices)
    list.push_back({{"title", c.name}, {"const", c.value}, {"description", c.description}});
  return {{"title", title}, {"description", description}, {"oneOf", std::move(list)}};
}

// Foxglove's `time` (sec >= 0) and `duration` (sec of either sign).
json time_schema(const char* title, bool signed_seconds, const char* description) {
  return {{"type", "object"},
          {"title", title},
          {"properties",
           {{"sec", signed_seconds ? integer({}, {}) : integer(0, {})},
            {"nsec", integer(0, 999'999'999)}}},
          {"description", description}};
}

json vector3(const char* description) {
  return object("foxglove.Vector3", description,
                {{"x", typed("number", "x coordinate length")},
                 {"y", typed("number", "y coordinate length")},
                 {"z", typed("number", "z coordinate length")}});
}

json point3(const char* description) {
  return object("foxglove.Point3", description,
                {{"x", typed("number", "x coordinate position")},
                 {"y", typed("number", "y coordinate position")},
                 {"z", typed("number", "z coordinate position")}});
}

json pose(const char* description) {
  return object(
      "foxglove.Pose", description,
      {{"position", vector3("Point denoting position in 3D space")},
       {"orientation", object("foxglove.Quaternion", "Quaternion denoting orientation in 3D space",
                              {{"x", typed("number", "x value")},
                               {"y", typed("number", "y value")},
                               {"z", typed("number", "z value")},
                               {"w", typed("number", "w value")}})}});
}

json color(const char* description) {
  return object("foxglove.Color", description,
                {{"r", typed("number", "Red value between 0 and 1")},
                 {"g", typed("number", "Green value between 0 and 1")},
                 {"b", typed("number", "Blue value between 0 and 1")},
                 {"a", typed("number", "Alpha value between 0 and 1")}});
}

json indices() {
  return array(integer(0, {}), "Indices into `points` and `colors`; empty: every point in order");
}

json build_schema() {
  const json arrow =
      object("foxglove.ArrowPrimitive", "A primitive representing an arrow",
             {{"pose", pose("Position of the tail and orientation; identity points along +x")},
              {"shaft_length", typed("number", "Length of the arrow shaft")},
              {"shaft_diameter", typed("number", "Diameter of the arrow shaft")},
              {"head_length", typed("number", "Length of the arrow head")},
              {"head_diameter", typed("number", "Diameter of the arrow head")},
              {"color", color("Color of the arrow")}});
  const json cube =
      object("foxglove.CubePrimitive", "A primitive representing a cube or rectangular prism",
             {{"pose", pose("Position of the centre and orientation of the cube")},
              {"size", vector3("Size of the cube along each axis")},
              {"color", color("Color of the cube")}});
  const json sphere =
      object("foxglove.SpherePrimitive", "A primitive representing a sphere or ellipsoid",
             {{"pose", pose("Position of the centre and orientation of the sphere")},
              {"size", vector3("Size (diameter) of the sphere along each axis")},
              {"color", color("Color of the sphere")}});
  const json cylinder = object(
      "foxglove.CylinderPrimitive",
      "A primitive representing a cylinder, elliptic cylinder, or truncated cone",
      {{"pose", pose("Position of the centre and orientation; the flat faces are normal to z")},
       {"size", vector3("Size of the cylinder's bounding box")},
       {"bottom_scale", typed("number", "0-1, diameter of the bottom face (min z) to the box's")},
       {"top_scale", typed("number", "0-1, diameter of the top face (max z) to the box's")},
       {"color", color("Color of the cylinder")}});
  const json line = object(
      "foxglove.LinePrimitive", "A primitive representing a series of points connected by lines",
      {{"type", one_of("foxglove.LineType", "Drawing primitive to use for lines",
                       {{"LINE_STRIP", 0, "Connected segments: 0-1, 1-2, ..."},
                        {"LINE_LOOP", 1, "Closed polygon: 0-1, 1-2, ..., n-0"},
                        {"LINE_LIST", 2, "Separate segments: 0-1, 2-3, ..."}})},
       {"pose", pose("Origin of lines relative to reference frame")},
       {"thickness", typed("number", "Line thickness")},
       {"scale_invariant",
        typed("boolean", "Thickness in screen pixels (true) or in world units (false)")},
       {"points",
        array(point3("A point representing a position in 3D space"), "Points along the line")},
       {"color", color("Solid color of the whole line; `color` or `colors` is required")},
       {"colors", array(color("A color in RGBA format"), "Per-point colors, as many as points")},
       {"indices", indices()}});
  const json triangles = object(
      "foxglove.TriangleListPrimitive",
      "A primitive representing a set of triangles or a surface tiled by triangles",
      {{"pose", pose("Origin of triangles relative to reference frame")},
       {"points", array(point3("A point representing a position in 3D space"),
                        "Vertices, taken three by three")},
       {"color", color("Solid color of the whole shape; `color` or `colors` is required")},
       {"colors", array(color("A color in RGBA format"), "Per-vertex colors, as many as points")},
       {"indices", indices()}});
  const json text =
      object("foxglove.TextPrimitive", "A primitive representing a text label",
             {{"pose", pose("Position of the centre of the text box and orientation of the text")},
              {"billboard", typed("boolean", "Always face the camera (true) or follow the pose")},
              {"font_size", typed("number", "Font size (height of one line of text)")},
              {"scale_invariant",
               typed("boolean", "Font size in screen pixels (true) or in world units (false)")},
              {"color", color("Color of the text")},
              {"text", typed("string", "Text")}});
  json model_data = typed("string", "Embedded model; `url` or `data` should be provided");
  model_data["contentEncoding"] = "base64";
  const json model = object(
      "foxglove.ModelPrimitive",
      "A primitive representing a 3D model file loaded from an external URL or embedded data",
      {{"pose", pose("Origin of model relative to reference frame")},
       {"scale", vector3("Scale factor to apply to the model along each axis")},
       {"color", color("Solid color of the whole model if `override_color` is true")},
       {"override_color", typed("boolean", "Use `color` instead of the model's materials")},
       {"url", typed("string", "URL of the model file; `url` or `data` should be provided")},
       {"media_type", typed("string", "Media type of the model, required with `data`")},
       {"data", std::move(model_data)}});
  const json entity = object(
      "foxglove.SceneEntity",
      "A visual element in a 3D scene, its primitives sharing one frame of reference",
      {{"timestamp", time_schema("time", false, "Timestamp of the entity")},
       {"frame_id", typed("string", "Frame of reference")},
       {"id", typed("string", "Identifier; it replaces any earlier entity of the topic with it")},
       {"lifetime",
        time_schema("duration", true, "How long after `timestamp` it is removed; zero: never")},
       {"frame_locked", typed("boolean", "Follow `frame_id` (true) or stay in the fixed frame")},
       {"metadata",
        array(object("foxglove.KeyValuePair", "A key with its associated value",
                     {{"key", typed("string", "Key")}, {"value", typed("string", "Value")}}),
              "Additional metadata; keys are unique")},
       {"arrows", array(arrow, "Arrow primitives")},
       {"cubes", array(cube, "Cube primitives")},
       {"spheres", array(sphere, "Sphere primitives")},
       {"cylinders", array(cylinder, "Cylinder primitives")},
       {"lines", array(line, "Line primitives")},
       {"triangles", array(triangles, "Triangle list primitives")},
       {"texts", array(text, "Text primitives")},
       {"models", array(model, "Model primitives")}});
  const json deletion = object(
      "foxglove.SceneEntityDeletion", "Command to remove previously published entities",
      {{"timestamp", time_schema("time", false, "Only matching entities older are deleted")},
       {"type", one_of("foxglove.SceneEntityDeletionType", "Type of deletion action to perform",
                       {{"MATCHING_ID", 0, "Delete the entity of the topic with `id`"},
                        {"ALL", 1, "Delete every entity of the topic"}})},
       {"id", typed("string", "Identifier to match when `type` is MATCHING_ID")}});
  json schema = object("foxglove.SceneUpdate", "An update to the entities displayed in a 3D scene",
                       {{"deletions", array(deletion, "Scene entities to delete")},
                        {"entities", array(entity, "Scene entities to add or replace")}});
  schema["$comment"] = "foxglove.SceneUpdate of https://github.com/foxglove/schemas";
  return schema;
}

// ---- The scene ------------------------------------------------------------

// Drawn as thick as the trailer octree models its shell (sim::OctreeOptions).
constexpr double kWall = 0.05;

json time_of(std::int64_t ns) {
  ns = std::max<std::int64_t>(ns, 0);
  return {{"sec", ns / 1'000'000'000}, {"nsec", ns % 1'000'000'000}};
}

json vec(const Eigen::Vector3d& v) {
  return {{"x", v.x()}, {"y", v.y()}, {"z", v.z()}};
}

json pose_of(const Eigen::Vector3d& p, const Eigen::Quaterniond& q) {
  return {{"position", vec(p)},
          {"orientation", {{"x", q.x()}, {"y", q.y()}, {"z", q.z()}, {"w", q.w()}}}};
}

json rgba(double r, double g, double b, double a) {
  return {{"r", r}, {"g", g}, {"b", b}, {"a", a}};
}

json entity(const std::string& id, std::int64_t stamp_ns) {
  json e = {{"timestamp", time_of(stamp_ns)},
            {"frame_id", FoxgloveScene::kFrame},
            {"id", id},
            {"lifetime", {{"sec", 0}, {"nsec", 0}}},
            {"frame_locked", false},
            {"metadata", json::array()}};
  for (const char* list :
       {"arrows", "cubes", "spheres", "cylinders", "lines", "triangles", "texts", "models"})
    e[list] = json::array();
  return e;
}

json cube(const Eigen::Vector3d& centre, const Eigen::Quaterniond& q, const Eigen::Vector3d& size,
          const json& color) {
  return {{"pose", pose_of(centre, q)}, {"size", vec(size)}, {"color", color}};
}

// Floor and ceiling across the full outer width, the front wall closing the
// ends; the rear (x = 0) is open. Translucent so the load shows through.
json trailer_entity(const Eigen::Vector3d& trailer, std::int64_t stamp_ns) {
  const double w = trailer.x(), h = trailer.y(), d = trailer.z();
  const Eigen::Quaterniond none = Eigen::Quaterniond::Identity();
  const json floor_color = rgba(0.55, 0.55, 0.58, 0.9);
  const json wall_color = rgba(0.7, 0.75, 0.8, 0.2);
  json e = entity("trailer", stamp_ns);
  auto& cubes = e["cubes"];
  cubes.push_back(cube({d / 2, 0, -kWall / 2}, none, {d, w + 2 * kWall, kWall}, floor_color));
  cubes.push_back(cube({d / 2, 0, h + kWall / 2}, none, {d, w + 2 * kWall, kWall}, wall_color));
  for (const double side : {-1.0, 1.0})
    cubes.push_back(cube({d / 2, side * (w + kWall) / 2, h / 2}, none, {d, kWall, h}, wall_color));
  cubes.push_back(
      cube({d + kWall / 2, 0, h / 2}, none, {kWall, w + 2 * kWall, h + 2 * kWall}, wall_color));
  return e;
}

std::string box_entity_id(std::uint32_t id) {
  return "box/" + std::to_string(id);
}

Eigen::Vector3d vec3(const msg::Vec3& v) {
  return {v.x(), v.y(), v.z()};
}

}  // namespace

FoxgloveScene::FoxgloveScene(std::optional<sim::RobotModel> robot) : robot_(std::move(robot)) {}

const std::string& FoxgloveScene::json_schema() {
  static const std::string schema = build_schema().dump();
  return schema;
}

void FoxgloveScene::update(const msg::WorldState& w, std::int64_t stamp_ns) {
  std::vector<std::uint32_t> held;
  if (w.held_box_ids()) held = sim::elements(*w.held_box_ids());
  std::vector<Box> boxes;
  if (w.boxes()) {
    boxes.reserve(w.boxes()->size());
    for (flatbuffers::uoffset_t i = 0; i < w.boxes()->size(); ++i) {
      const msg::BoxState b = sim::element(*w.boxes(), i);
      const auto& q = b.pose().orientation();
      boxes.push_back({b.id(), vec3(b.size()), vec3(b.pose().position()),
                       Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z()),
                       std::find(held.begin(), held.end(), b.id()) != held.end()});
    }
  }
  std::optional<sim::JointVector> joints;
  if (const auto* q = w.robot() ? w.robot()->positions() : nullptr;
      q && q->size() == sim::kNumJoints) {
    joints.emplace();
    for (int i = 0; i < sim::kNumJoints; ++i)
      (*joints)[i] = sim::element(*q, static_cast<flatbuffers::uoffset_t>(i));
  }
  std::lock_guard lock(m_);
  trailer_ = w.trailer_size() ? vec3(*w.trailer_size()) : Eigen::Vector3d::Zero();
  boxes_ = std::move(boxes);
  joints_ = joints;
  stamp_ns_ = stamp_ns;
  have_world_ = fresh_ = true;
}

void FoxgloveScene::resend() {
  std::lock_guard lock(m_);
  resend_ = true;
}

std::optional<FoxgloveScene::Message> FoxgloveScene::take() {
  std::lock_guard lock(m_);
  if (!have_world_ || !(fresh_ || resend_)) return std::nullopt;
  fresh_ = resend_ = false;

  json entities = json::array();
  entities.push_back(trailer_entity(trailer_, stamp_ns_));
  std::set<std::string> shown;
  const json box_color = rgba(0.78, 0.6, 0.4, 1.0);
  const json held_color = rgba(0.95, 0.75, 0.2, 1.0);
  for (const auto& b : boxes_) {
    auto e = entity(box_entity_id(b.id), stamp_ns_);
    e["cubes"].push_back(cube(b.position, b.orientation, b.size, b.held ? held_color : box_color));
    e["metadata"].push_back({{"key", "held"}, {"value", b.held ? "true" : "false"}});
    shown.insert(e["id"].get<std::string>());
    entities.push_back(std::move(e));
  }
  if (robot_ && joints_) {
    std::vector<Eigen::Isometry3d> poses;
    robot_->forward_kinematics(*joints_, poses);
    const json link_color = rgba(0.3, 0.45, 0.7, 1.0);
    for (std::size_t l = 0; l < robot_->links().size(); ++l) {
      const auto& link = robot_->links()[l];
      if (link.shapes.empty()) continue;
      auto e = entity("robot/" + link.name, stamp_ns_);
      for (const auto& shape : link.shapes) {
        const Eigen::Isometry3d at = poses[l] * shape.origin;
        const Eigen::Quaterniond q(at.rotation());
        const Eigen::Vector3d& s = shape.size;
        switch (shape.type) {
          case sim::CollisionShape::Type::kBox:
            e["cubes"].push_back(cube(at.translation(), q, s, link_color));
            break;
          case sim::CollisionShape::Type::kCylinder:  // (radius, length), along local z
            e["cylinders"].push_back({{"pose", pose_of(at.translation(), q)},
                                      {"size", vec({2 * s.x(), 2 * s.x(), s.y()})},
                                      {"bottom_scale", 1.0},
                                      {"top_scale", 1.0},
                                      {"color", link_color}});
            break;
          case sim::CollisionShape::Type::kSphere:
            e["spheres"].push_back({{"pose", pose_of(at.translation(), q)},
                                    {"size", vec(Eigen::Vector3d::Constant(2 * s.x()))},
                                    {"color", link_color}});
            break;
        }
      }
      entities.push_back(std::move(e));
    }
  }
  json deletions = json::array();
  for (const auto& id : shown_boxes_)
    if (!shown.count(id))
      deletions.push_back({{"timestamp", time_of(stamp_ns_)}, {"type", 0}, {"id", id}});
  shown_boxes_ = std::move(shown);
  return Message{
      stamp_ns_,
      json{{"deletions", std::move(deletions)}, {"entities", std::move(entities)}}.dump()};
}

}  // namespace plr::monitor_web
