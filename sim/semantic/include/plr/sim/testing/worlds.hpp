// Test fixtures: worlds built by hand, and their WorldState messages, for
// the tests of plug-ins that observe or act on a world.
#pragma once

#include <plr/messages.hpp>

#include <cstdint>
#include <vector>

#include "plr/sim/observation.hpp"
#include "plr/sim/world.hpp"

namespace plr::sim::testing {

// Observation thresholds for hand-made scenes of 0.3-0.45 m boxes a few rows
// high (the defaults are set for the generated trailers, whose walls reach
// 2.3 m): a wall from 0.55 m, its boxes' classes split at 1.2 and 1.9 m.
inline sim::ObservationParams small_scene_observation() {
  sim::ObservationParams p;
  p.h_pile = 0.55;
  p.pile_mid = 0.25;
  p.pile_high = 0.4;
  p.wall_mid = 1.2;
  p.wall_high = 1.9;
  return p;
}

// A box resting with its bottom at z0, centred at (x, y).
inline sim::Box make_box(std::uint32_t id, double x, double y, double z0,
                         Eigen::Vector3d size = {0.4, 0.4, 0.4}) {
  sim::Box b;
  b.id = id;
  b.size = size;
  b.pose = Eigen::Isometry3d::Identity();
  b.pose.translation() = Eigen::Vector3d(x, y, z0 + size.z() / 2);
  return b;
}

// `cols` x `rows` boxes of 0.4 m with the front face at x_front, centred on y = 0.
inline void add_wall(sim::World& w, double x_front, int cols, int rows) {
  std::uint32_t id = 1;
  for (const auto& b : w.boxes) id = std::max(id, b.id + 1);
  for (int c = 0; c < cols; ++c)
    for (int r = 0; r < rows; ++r)
      w.boxes.push_back(make_box(id++, x_front + 0.2, (c - (cols - 1) / 2.0) * 0.41, r * 0.4));
}

inline flatbuffers::Offset<msg::WorldState> pack_world(flatbuffers::FlatBufferBuilder& fbb,
                                                       const sim::World& w,
                                                       const std::vector<double>& joints = {},
                                                       const std::vector<std::uint32_t>& held = {},
                                                       std::uint32_t unloaded = 0,
                                                       double sim_time_s = 0.0) {
  const msg::Vec3 size(w.trailer.width, w.trailer.height, w.trailer.depth);
  std::vector<msg::BoxState> boxes;
  for (const auto& b : w.boxes) {
    const Eigen::Quaterniond q(b.pose.linear());
    const Eigen::Vector3d p = b.pose.translation();
    boxes.emplace_back(
        b.id, msg::Vec3(b.size.x(), b.size.y(), b.size.z()),
        msg::Pose(msg::Vec3(p.x(), p.y(), p.z()), msg::Quat(q.x(), q.y(), q.z(), q.w())), b.mass);
  }
  const auto robot = msg::CreateJointStateDirect(fbb, &joints);
  return msg::CreateWorldStateDirect(fbb, static_cast<std::int64_t>(sim_time_s * 1e9), &size,
                                     nullptr, 0.05, &boxes, robot, &held, unloaded);
}

inline std::vector<std::uint8_t> world_bytes(const sim::World& w) {
  flatbuffers::FlatBufferBuilder fbb;
  fbb.Finish(pack_world(fbb, w));
  return {fbb.GetBufferPointer(), fbb.GetBufferPointer() + fbb.GetSize()};
}

}  // namespace plr::sim::testing
