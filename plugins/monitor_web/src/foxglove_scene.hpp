// The world as Foxglove's own 3D scene message, foxglove.SceneUpdate in its
// JSON encoding (https://docs.foxglove.dev/docs/visualization/message-schemas/scene-update):
// the trailer's floor, walls and ceiling as translucent cubes, each box as a
// cube with its pose and size, and each robot link's collision shapes as
// cubes, cylinders and spheres placed by forward kinematics. Entity ids are
// stable ("trailer", "box/<id>", "robot/<link>"), so every update replaces
// what it updates; a box that left is deleted by id in the next update.
// Foxglove's 3D panel draws it without any PLR-specific extension.
#pragma once

#include <plr/messages.hpp>
#include <plr/sim/robot_model.hpp>

#include <Eigen/Geometry>

#include <cstdint>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <vector>

namespace plr::monitor_web {

class FoxgloveScene {
 public:
  static constexpr const char* kSchemaName = "foxglove.SceneUpdate";
  // The world frame: origin on the floor at the middle of the open rear,
  // x towards the front wall, z up (as every PLR world).
  static constexpr const char* kFrame = "trailer";

  // Without a robot model the robot is not drawn.
  explicit FoxgloveScene(std::optional<sim::RobotModel> robot);

  // The JSON Schema of foxglove.SceneUpdate (JSON encoding), as advertised.
  static const std::string& json_schema();

  // Keeps the latest world (stamped with its bus time, in ns).
  void update(const msg::WorldState& world, std::int64_t stamp_ns);
  // The next take() answers even without a new world (a client subscribed).
  void resend();

  struct Message {
    std::int64_t stamp_ns = 0;  // the world's
    std::string json;           // a foxglove.SceneUpdate
  };
  // The scene of the latest world, once per world (or resend); nothing
  // before the first world.
  std::optional<Message> take();

 private:
  struct Box {
    std::uint32_t id = 0;
    Eigen::Vector3d size, position;
    Eigen::Quaterniond orientation;
    bool held = false;
  };

  mutable std::mutex m_;
  std::optional<sim::RobotModel> robot_;
  bool have_world_ = false, fresh_ = false, resend_ = false;
  std::int64_t stamp_ns_ = 0;
  Eigen::Vector3d trailer_ = Eigen::Vector3d::Zero();  // inner width, height, depth
  std::vector<Box> boxes_;
  std::optional<sim::JointVector> joints_;
  std::set<std::string> shown_boxes_;  // entity ids of the boxes in the last scene taken
};

}  // namespace plr::monitor_web
