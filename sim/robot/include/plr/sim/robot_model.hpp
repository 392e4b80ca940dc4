// Kinematic model of the unloader, read from URDF (sim/robots/unloader.urdf).
//
// Configuration q (8 doubles, this order everywhere):
//   [base_x, arm_1, arm_2, arm_3, arm_4, nose_1, nose_2, nose_3]
// The arm is a 4-axis palletizer: yaw (arm_1), shoulder and elbow pitch
// (arm_2, arm_3), and a wrist yaw (arm_4) on a flange that a parallelogram
// keeps level (URDF mimic joints). Its end effector is the suction plate,
// whose frame has its origin on the suction surface and its normal along +x;
// the plate is always vertical. A plate target is a position plus the yaw of
// the normal, which is what makes the closed-form IK possible.
#pragma once

#include <plr/expected.hpp>

#include <Eigen/Geometry>
#include <array>
#include <string>
#include <utility>
#include <vector>

namespace plr::sim {

inline constexpr int kNumJoints = 8;
using JointVector = Eigen::Matrix<double, kNumJoints, 1>;

enum JointIndex : int {
  kBaseX = 0,
  kArm1 = 1,
  kArm2 = 2,
  kArm3 = 3,
  kArm4 = 4,
  kNose1 = 5,
  kNose2 = 6,
  kNose3 = 7,
};

// The robot's home: arm folded, nose raised, the base at `base_x` (0: its
// front edge at the trailer's open rear).
JointVector home_configuration(double base_x = 0.0);

// Joint names in configuration order; the URDF must define all of them.
inline constexpr std::array<const char*, kNumJoints> kJointNames = {
    "base_x", "arm_1", "arm_2", "arm_3", "arm_4", "nose_1", "nose_2", "nose_3"};

struct JointLimits {
  double lower = 0.0;
  double upper = 0.0;
  double velocity = 0.0;      // |qd| max, rad/s or m/s
  double acceleration = 0.0;  // |qdd| max
};

struct CollisionShape {
  enum class Type { kBox, kCylinder, kSphere };
  Type type = Type::kBox;
  // Box: full extents. Cylinder: (radius, length, 0), axis along local z.
  // Sphere: (radius, 0, 0).
  Eigen::Vector3d size = Eigen::Vector3d::Zero();
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();  // in the link frame
};

// How far the shape at `pose` reaches from pose's origin along each world
// axis: exact for every type (a cylinder or a sphere is not its bounding
// box turned with it).
Eigen::Vector3d half_extents(const CollisionShape& shape, const Eigen::Isometry3d& pose);

enum class JointType { kFixed, kRevolute, kPrismatic };

struct Link {
  std::string name;
  int parent_link = -1;  // -1 for the root
  // Index into the configuration of the joint that moves this link relative
  // to its parent, or -1 for a fixed joint / the root. A mimic joint moves by
  // mimic_multiplier * q[joint] + mimic_offset.
  int joint = -1;
  double mimic_multiplier = 1.0;
  double mimic_offset = 0.0;
  JointType joint_type = JointType::kFixed;
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();  // joint frame in the parent link
  Eigen::Vector3d axis = Eigen::Vector3d::UnitX();           // in the joint frame
  std::vector<CollisionShape> shapes;
};

// Plate target: position of the suction surface centre (world frame) and the
// yaw of the plate normal about z (0: facing +x, towards the trailer's front
// wall). The normal is always horizontal.
struct PlateTarget {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  double yaw = 0.0;
};

class RobotModel {
 public:
  // Errors are one line, "<file>: <cause>".
  static plr::Expected<RobotModel> from_urdf_file(const std::string& path);
  // `source` names the text in error messages.
  static plr::Expected<RobotModel> from_urdf_string(const std::string& xml,
                                                    const std::string& source = "<string>");

  const std::vector<Link>& links() const { return links_; }
  int link_index(const std::string& name) const;  // -1 if absent
  int plate_link() const { return plate_link_; }

  // Link pairs allowed to touch besides parent/child (<allow_collision>).
  const std::vector<std::pair<int, int>>& allowed_collisions() const { return allowed_; }

  const JointLimits& limits(int joint) const { return limits_[joint]; }
  const std::array<JointLimits, kNumJoints>& all_limits() const { return limits_; }
  bool within_limits(const JointVector& q, double tol = 1e-9) const;

  // World pose of every link, indexed like links(). `poses` is resized.
  void forward_kinematics(const JointVector& q, std::vector<Eigen::Isometry3d>& poses) const;
  Eigen::Isometry3d plate_pose(const JointVector& q) const;
  PlateTarget plate_target(const JointVector& q) const;

  // Closed-form IK of the arm for a plate target. base_x and the nose joints
  // are copied from `seed`. Returns every solution within joint limits,
  // nearest to the seed (in joint distance) first.
  std::vector<JointVector> arm_ik(const PlateTarget& target, const JointVector& seed) const;

  // Arm dimensions read from the URDF (for reach checks and heuristics).
  struct ArmGeometry {
    Eigen::Vector3d yaw_origin;             // arm_1 axis origin, in base_link
    double shoulder_height;                 // arm_2 above arm_1 origin
    double upper = 0, fore = 0, plate = 0;  // arm_2->arm_3, arm_3->arm_4 axis, arm_4 axis->plate
  };
  const ArmGeometry& arm() const { return arm_; }

 private:
  static RobotModel parse_urdf(const std::string& xml, const std::string& source);

  std::vector<Link> links_;  // parents before children
  std::vector<std::pair<int, int>> allowed_;
  std::array<JointLimits, kNumJoints> limits_{};
  int plate_link_ = -1;
  ArmGeometry arm_{};
};

// The robot in the URDF file `urdf`, or the shipped unloader
// (robots/unloader.urdf, see shipped_files.hpp) when it is empty.
plr::Expected<RobotModel> load_robot(const std::string& urdf = {});

}  // namespace plr::sim
