// The world as a foxglove.SceneUpdate, without a pipeline: what the scene
// holds for a world, its ids across updates, the deletions of boxes that
// left, and the schema check that the pipeline test relies on failing on
// malformed entities.
#include "foxglove_scene.hpp"
#include "json_schema_check.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <map>
#include <set>

namespace plr::monitor_web::testing {
namespace {

using nlohmann::json;

struct TestBox {
  std::uint32_t id;
  msg::Vec3 size;
  msg::Vec3 position;
  msg::Quat orientation;
};

// A WorldState as the simulator publishes it (no octree: the scene draws
// the trailer from its size).
std::string world(const std::vector<TestBox>& boxes, const std::vector<std::uint32_t>& held,
                  const std::vector<double>& joints) {
  flatbuffers::FlatBufferBuilder fbb;
  std::vector<msg::BoxState> states;
  for (const auto& b : boxes)
    states.emplace_back(b.id, b.size, msg::Pose(b.position, b.orientation), 0.0);
  const msg::Vec3 trailer(2.4, 2.6, 6.0);
  const auto robot = msg::CreateJointStateDirect(fbb, &joints);
  fbb.Finish(msg::CreateWorldStateDirect(fbb, 1, &trailer, nullptr, 0.0, &states, robot, &held));
  return {reinterpret_cast<const char*>(fbb.GetBufferPointer()), fbb.GetSize()};
}

const msg::WorldState& root(const std::string& bytes) {
  return *flatbuffers::GetRoot<msg::WorldState>(bytes.data());
}

const std::vector<TestBox> kBoxes = {
    {1, {0.4, 0.5, 0.3}, {5.0, -0.6, 0.15}, {0, 0, 0, 1}},
    {2, {0.4, 0.4, 0.4}, {5.0, 0.6, 0.2}, {0, 0, 0.38268343236508978, 0.92387953251128674}},
    {3, {0.6, 0.4, 0.4}, {4.5, 0.0, 0.65}, {0, 0, 0, 1}}};
const std::vector<double> kJoints = {1.0, 0.2, 0.3, -0.4, 0.1, 0.0, 0.0, 0.0};

std::map<std::string, json> by_id(const json& scene) {
  std::map<std::string, json> out;
  for (const auto& e : scene.at("entities")) out[e.at("id").get<std::string>()] = e;
  return out;
}

json schema() {
  return json::parse(FoxgloveScene::json_schema());
}

TEST(FoxgloveScene, TheSchemaIsFoxglovesSceneUpdate) {
  const auto s = schema();
  EXPECT_EQ(s.at("title"), "foxglove.SceneUpdate");
  const auto& entity = s.at("properties").at("entities").at("items");
  EXPECT_EQ(entity.at("title"), "foxglove.SceneEntity");
  std::set<std::string> fields;
  for (const auto& [name, sub] : entity.at("properties").items()) fields.insert(name);
  EXPECT_EQ(fields, (std::set<std::string>{"timestamp", "frame_id", "id", "lifetime",
                                           "frame_locked", "metadata", "arrows", "cubes", "spheres",
                                           "cylinders", "lines", "triangles", "texts", "models"}));
  const auto& cube = entity.at("properties").at("cubes").at("items");
  EXPECT_EQ(cube.at("title"), "foxglove.CubePrimitive");
  EXPECT_EQ(cube.at("properties").at("pose").at("properties").at("orientation").at("title"),
            "foxglove.Quaternion");
  const auto& deletion = s.at("properties").at("deletions").at("items");
  EXPECT_EQ(deletion.at("properties").at("type").at("oneOf").size(), 2u);
  EXPECT_EQ(deletion.at("properties").at("timestamp").at("properties").at("nsec").at("maximum"),
            999'999'999);
}

TEST(FoxgloveScene, HoldsTheTrailerEachBoxAndTheRobotsLinks) {
  auto robot = sim::load_robot();
  ASSERT_TRUE(robot) << robot.error().message;
  FoxgloveScene scene(*robot);
  EXPECT_FALSE(scene.take()) << "nothing before the first world";
  const auto bytes = world(kBoxes, {3}, kJoints);
  scene.update(root(bytes), 1'700'000'000'123'456'789);
  const auto m = scene.take();
  ASSERT_TRUE(m);
  EXPECT_EQ(m->stamp_ns, 1'700'000'000'123'456'789);
  const auto j = json::parse(m->json);
  EXPECT_EQ(schema_violation(schema(), j, true), "");

  const auto entities = by_id(j);
  ASSERT_TRUE(entities.count("trailer"));
  const auto& floor = entities.at("trailer").at("cubes").at(0);
  EXPECT_DOUBLE_EQ(floor.at("size").at("x"), 6.0);  // depth
  EXPECT_DOUBLE_EQ(floor.at("pose").at("position").at("x"), 3.0);
  EXPECT_EQ(entities.at("trailer").at("cubes").size(), 5u);  // floor, ceiling, 2 sides, front
  for (const auto& b : kBoxes) {
    const auto id = "box/" + std::to_string(b.id);
    ASSERT_TRUE(entities.count(id)) << id;
    const auto& e = entities.at(id);
    EXPECT_EQ(e.at("frame_id"), "trailer");
    EXPECT_EQ(e.at("timestamp"), (json{{"sec", 1'700'000'000}, {"nsec", 123'456'789}}));
    ASSERT_EQ(e.at("cubes").size(), 1u);
    const auto& c = e.at("cubes")[0];
    EXPECT_EQ(c.at("pose").at("position"),
              (json{{"x", b.position.x()}, {"y", b.position.y()}, {"z", b.position.z()}}));
    EXPECT_EQ(c.at("pose").at("orientation"), (json{{"x", b.orientation.x()},
                                                    {"y", b.orientation.y()},
                                                    {"z", b.orientation.z()},
                                                    {"w", b.orientation.w()}}));
    EXPECT_EQ(c.at("size"), (json{{"x", b.size.x()}, {"y", b.size.y()}, {"z", b.size.z()}}));
    EXPECT_EQ(e.at("metadata")[0].at("value"), b.id == 3 ? "true" : "false");
  }
  // Every collision shape of every link, each as its own primitive type.
  std::size_t shapes = 0, drawn = 0, cylinders = 0;
  for (const auto& link : robot->links()) {
    shapes += link.shapes.size();
    for (const auto& s : link.shapes) cylinders += s.type == sim::CollisionShape::Type::kCylinder;
    if (link.shapes.empty()) continue;
    const auto& e = entities.at("robot/" + link.name);
    drawn += e.at("cubes").size() + e.at("cylinders").size() + e.at("spheres").size();
  }
  EXPECT_GT(shapes, 0u);
  EXPECT_EQ(drawn, shapes);
  std::size_t robot_entities = 0, sent_cylinders = 0;
  for (const auto& [id, e] : entities)
    if (id.rfind("robot/", 0) == 0) {
      ++robot_entities;
      sent_cylinders += e.at("cylinders").size();
    }
  EXPECT_EQ(sent_cylinders, cylinders);
  EXPECT_EQ(entities.size(), 1 + kBoxes.size() + robot_entities);
  EXPECT_TRUE(j.at("deletions").empty());
}

TEST(FoxgloveScene, KeepsIdsAndDeletesBoxesThatLeft) {
  FoxgloveScene scene(std::nullopt);
  const auto first = world(kBoxes, {}, kJoints);
  scene.update(root(first), 10);
  const auto a = json::parse(scene.take()->json);
  EXPECT_FALSE(scene.take()) << "the same world is not sent twice";

  const auto second = world({kBoxes[0], kBoxes[2]}, {}, kJoints);
  scene.update(root(second), 20);
  const auto b = json::parse(scene.take()->json);
  EXPECT_EQ(schema_violation(schema(), b, true), "");
  std::set<std::string> ids_a, ids_b;
  for (const auto& [id, e] : by_id(a)) ids_a.insert(id);
  for (const auto& [id, e] : by_id(b)) ids_b.insert(id);
  EXPECT_EQ(ids_a, (std::set<std::string>{"trailer", "box/1", "box/2", "box/3"}));
  EXPECT_EQ(ids_b, (std::set<std::string>{"trailer", "box/1", "box/3"}));
  ASSERT_EQ(b.at("deletions").size(), 1u);
  EXPECT_EQ(b.at("deletions")[0],
            (json{{"timestamp", {{"sec", 0}, {"nsec", 20}}}, {"type", 0}, {"id", "box/2"}}));

  // A new subscriber gets the whole scene again, with nothing to delete.
  scene.resend();
  const auto c = json::parse(scene.take()->json);
  EXPECT_EQ(by_id(c).size(), 3u);
  EXPECT_TRUE(c.at("deletions").empty());
}

// The check the pipeline test relies on: each of these breaks the schema.
TEST(FoxgloveScene, TheSchemaCheckFailsOnMalformedEntities) {
  FoxgloveScene scene(std::nullopt);
  const auto bytes = world(kBoxes, {}, kJoints);
  scene.update(root(bytes), 10);
  scene.take();
  const auto fewer = world({kBoxes[0]}, {}, kJoints);
  scene.update(root(fewer), 20);
  const auto good = json::parse(scene.take()->json);
  const auto s = schema();
  ASSERT_EQ(schema_violation(s, good, true), "");
  ASSERT_FALSE(good.at("deletions").empty());

  struct Case {
    const char* pointer;
    json value;
    const char* says;
  };
  const std::vector<Case> cases = {
      {"/entities/1/cubes/0/size/x", "0.4", "$.entities[1].cubes[0].size.x: expected number"},
      {"/entities/1/timestamp/nsec", 1'000'000'000, "$.entities[1].timestamp.nsec: "},
      {"/entities/1/timestamp/sec", -1, "$.entities[1].timestamp.sec: "},
      {"/entities/0/cubes", json::object(), "$.entities[0].cubes: expected array"},
      {"/entities/1/frame_locked", 0, "$.entities[1].frame_locked: expected boolean"},
      {"/deletions/0/type", 2, "$.deletions[0].type: 2 matches 0 of oneOf"},
      {"/entities/1/cube", json::array(), "$.entities[1]: 'cube' is not in the schema"},
      {"/entities/1/cubes/0/color/a", nullptr, "$.entities[1].cubes[0].color.a: expected number"},
  };
  for (const auto& c : cases) {
    auto bad = good;
    bad[json::json_pointer(c.pointer)] = c.value;
    const auto v = schema_violation(s, bad, true);
    EXPECT_EQ(v.rfind(c.says, 0), 0u) << c.pointer << ": " << v;
  }
  auto missing = good;
  missing["entities"][1].erase("id");
  EXPECT_EQ(schema_violation(s, missing, true), "$.entities[1]: missing 'id'");
  // Plain JSON Schema (no `complete`) allows both, as Foxglove's schema does.
  EXPECT_EQ(schema_violation(s, missing, false), "");
  // A keyword the check does not know fails rather than pass unchecked.
  auto stricter = s;
  stricter["required"] = {"entities"};
  EXPECT_EQ(schema_violation(stricter, good, true),
            "$: schema keyword 'required' is not understood by this check");
}

}  // namespace
}  // namespace plr::monitor_web::testing
