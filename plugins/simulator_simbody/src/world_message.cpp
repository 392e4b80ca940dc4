#include "world_message.hpp"

#include <plr/sim/octree.hpp>

#include <octomap/OcTree.h>

#include <sstream>

namespace plr::simulator {

std::string trailer_octree_bytes(const sim::Trailer& trailer, double resolution) {
  sim::OctreeOptions options;
  options.resolution = resolution;
  auto tree = sim::build_trailer_octree(trailer, options);
  std::ostringstream out;
  tree->writeBinary(out);
  return out.str();
}

void build_world_state(flatbuffers::FlatBufferBuilder& fbb, const sim::World& world,
                       const RobotState& robot, const std::string& octree, double resolution,
                       std::uint32_t boxes_unloaded, bool true_state, std::int64_t stamp_ns) {
  std::vector<msg::BoxState> boxes;
  boxes.reserve(world.boxes.size());
  for (const auto& b : world.boxes) {
    const Eigen::Vector3d p = b.pose.translation();
    const Eigen::Quaterniond q(b.pose.rotation());
    boxes.emplace_back(
        b.id, msg::Vec3(b.size.x(), b.size.y(), b.size.z()),
        msg::Pose(msg::Vec3(p.x(), p.y(), p.z()), msg::Quat(q.x(), q.y(), q.z(), q.w())),
        true_state ? b.mass : 0.0);
  }
  const std::vector<double> q(robot.q.data(), robot.q.data() + robot.q.size());
  const msg::Vec3 size(world.trailer.width, world.trailer.height, world.trailer.depth);
  auto joints = msg::CreateJointStateDirect(fbb, &q);
  auto octree_vec =
      fbb.CreateVector(reinterpret_cast<const std::uint8_t*>(octree.data()), octree.size());
  auto boxes_vec = fbb.CreateVectorOfStructs(boxes);
  auto held = fbb.CreateVector(robot.held);
  fbb.Finish(msg::CreateWorldState(fbb, stamp_ns, &size, octree_vec, resolution, boxes_vec, joints,
                                   held, boxes_unloaded, true_state));
}

}  // namespace plr::simulator
