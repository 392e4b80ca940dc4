// Geometric checks on whole worlds (FCL narrow phase behind an AABB test).
#include <fcl/fcl.h>

#include <array>

#include "plr/sim/generators.hpp"

namespace plr::sim {
namespace {

Eigen::Vector3d half_extent_world(const Box& box) {
  return box.pose.linear().cwiseAbs() * (0.5 * box.size);
}

}  // namespace

std::vector<std::pair<std::uint32_t, std::uint32_t>> find_interpenetrations(const World& world,
                                                                            double tolerance) {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> found;
  const Trailer& t = world.trailer;
  const std::size_t n = world.boxes.size();
  std::vector<Eigen::Vector3d> lo(n), hi(n);
  std::vector<fcl::Boxd> shapes;
  shapes.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Box& b = world.boxes[i];
    const Eigen::Vector3d e = half_extent_world(b);
    lo[i] = b.pose.translation() - e;
    hi[i] = b.pose.translation() + e;
    shapes.emplace_back(b.size);
    if (lo[i].z() < -tolerance || hi[i].z() > t.height + tolerance ||
        lo[i].y() < -0.5 * t.width - tolerance || hi[i].y() > 0.5 * t.width + tolerance ||
        hi[i].x() > t.depth + tolerance) {
      found.emplace_back(b.id, b.id);
    }
  }
  fcl::CollisionRequestd request(4, true);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = i + 1; j < n; ++j) {
      if ((lo[i].array() > hi[j].array() - tolerance).any() ||
          (lo[j].array() > hi[i].array() - tolerance).any()) {
        continue;
      }
      fcl::CollisionResultd result;
      fcl::collide(&shapes[i], world.boxes[i].pose, &shapes[j], world.boxes[j].pose, request,
                   result);
      for (std::size_t c = 0; c < result.numContacts(); ++c) {
        if (result.getContact(c).penetration_depth > tolerance) {
          found.emplace_back(world.boxes[i].id, world.boxes[j].id);
          break;
        }
      }
    }
  }
  return found;
}

World without_masses(const World& world) {
  World w = world;
  for (Box& b : w.boxes) b.mass = 0.0;
  return w;
}

}  // namespace plr::sim
