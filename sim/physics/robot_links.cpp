#include "plr/sim/robot_links.hpp"

namespace plr::sim {

std::vector<LinkGeometry> robot_link_geometry(const RobotModel& model, const Config& q,
                                              double belt_speed, const std::string& conveyor_link) {
  std::vector<Eigen::Isometry3d> poses;
  model.forwardKinematics(q, poses);
  const int conveyor = model.linkIndex(conveyor_link);
  std::vector<LinkGeometry> out;
  for (std::size_t i = 0; i < model.links().size(); ++i) {
    for (const CollisionShape& s : model.links()[i].shapes) {
      LinkGeometry g;
      g.pose = poses[i] * s.origin;
      switch (s.type) {
        case CollisionShape::Type::kBox:
          g.size = s.size;
          break;
        case CollisionShape::Type::kCylinder:
          g.shape = LinkGeometry::Shape::kCylinder;
          g.size = Eigen::Vector3d(s.size.x(), s.size.x(), s.size.y());
          break;
        case CollisionShape::Type::kSphere:
          g.size = Eigen::Vector3d::Constant(2.0 * s.size.x());
          break;
      }
      if (static_cast<int>(i) == conveyor) g.belt_speed = belt_speed;
      out.push_back(g);
    }
  }
  return out;
}

SuctionPlate suction_plate_at(const RobotModel& model, const Config& q, const SuctionPlate& cups) {
  SuctionPlate p = cups;
  p.pose = model.platePose(q) * Eigen::AngleAxisd(0.5 * M_PI, Eigen::Vector3d::UnitY());
  return p;
}

}  // namespace plr::sim
