#include "plr/sim/robot_links.hpp"

#include <cmath>
#include <optional>

namespace plr::sim {

namespace {

// A real scoop gets under a box because its lip is pressed onto the floor and
// cardboard's bottom edges are rounded. Rigid boxes with sharp edges resting
// on the floor plane would need an edge of zero thickness: a blade of any
// thickness meets their side face and pushes them. So near the floor the
// physics continues the scoop's belt surface with a thin lip, sloped down
// from its leading edge to kLipEdge below the floor plane. The planner does
// not see it: it stands for contact, not for the robot's extent.
constexpr double kLipReach = 0.06;   // m; the lip exists while the edge is this close to the floor
constexpr double kScoopOut = 0.1;    // m; and the scoop is out this far (not a lowered nose)
constexpr double kLipSlope = 0.45;   // rad below horizontal
constexpr double kLipThick = 0.004;  // m
constexpr double kLipEdge = 0.001;   // m below the floor plane
constexpr int kConveyorDrive = 0, kScoopDrive = 1, kBodyDrive = 2;

std::optional<LinkGeometry> scoop_lip(const LinkGeometry& scoop) {
  const Eigen::Vector3d edge =
      scoop.pose * Eigen::Vector3d(0.5 * scoop.size.x(), 0.0, 0.5 * scoop.size.z());
  const double drop = edge.z() + kLipEdge;
  if (drop <= 0.0 || edge.z() > kLipReach) return std::nullopt;
  const double length = drop / std::sin(kLipSlope);
  const Eigen::Vector3d along(std::cos(kLipSlope), 0.0, -std::sin(kLipSlope));
  const Eigen::Vector3d up(std::sin(kLipSlope), 0.0, std::cos(kLipSlope));
  LinkGeometry lip = scoop;
  lip.size = Eigen::Vector3d(length, scoop.size.y(), kLipThick);
  lip.pose.linear() = Eigen::AngleAxisd(kLipSlope, Eigen::Vector3d::UnitY()).toRotationMatrix();
  lip.pose.translation() = edge + 0.5 * length * along - 0.5 * kLipThick * up;
  lip.pose.translation().y() = scoop.pose.translation().y();
  return lip;
}

}  // namespace

std::vector<LinkGeometry> robot_link_geometry(const RobotModel& model, const JointVector& q,
                                              double belt_speed, const std::string& conveyor_link,
                                              const std::string& feeder_link,
                                              const std::string& body_link) {
  std::vector<Eigen::Isometry3d> poses;
  model.forward_kinematics(q, poses);
  const int conveyor = model.link_index(conveyor_link);
  const int feeder = model.link_index(feeder_link);
  const int body = model.link_index(body_link);
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
      const int link = static_cast<int>(i);
      if (link == conveyor || link == feeder || link == body) g.belt_speed = belt_speed;
      g.feeds_belt = link == feeder;
      // Three motors: the nose conveyor's, the scoop's (its lip included)
      // and the body's.
      g.belt_drive = g.feeds_belt ? kScoopDrive : (link == body ? kBodyDrive : kConveyorDrive);
      out.push_back(g);
      if (g.feeds_belt && q[kNose3] > kScoopOut)
        if (auto lip = scoop_lip(g)) out.push_back(*lip);
    }
  }
  return out;
}

SuctionPlate suction_plate_at(const RobotModel& model, const JointVector& q,
                              const SuctionPlate& cups) {
  SuctionPlate p = cups;
  p.pose = model.plate_pose(q) * Eigen::AngleAxisd(0.5 * M_PI, Eigen::Vector3d::UnitY());
  return p;
}

}  // namespace plr::sim
