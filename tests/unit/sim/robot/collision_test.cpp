#include "plr/sim/collision.hpp"
#include "plr/sim/octree.hpp"

#include <gtest/gtest.h>

#include <fcl/fcl.h>
#include <octomap/octomap.h>

#include <algorithm>
#include <memory>
#include <random>

using plr::sim::Box;
using plr::sim::CollisionChecker;
using plr::sim::JointVector;
using plr::sim::load_robot;
using plr::sim::RobotModel;
using plr::sim::World;

namespace {

const RobotModel& robot() {
  static const RobotModel m = load_robot().value();
  return m;
}

// Arm folded above the raised nose, robot 1 m inside the trailer.
JointVector home(double base_x = 1.0) {
  JointVector q;
  q << base_x, 0.0, -1.0, 2.0, 0.0, 0.5, 0.0, 0.0;
  return q;
}

Box box(std::uint32_t id, double x, double y, double z, double s = 0.4) {
  Box b;
  b.id = id;
  b.size = Eigen::Vector3d::Constant(s);
  b.pose.translation() = Eigen::Vector3d(x, y, z);
  return b;
}

}  // namespace

TEST(Collision, HomeIsFreeInEmptyTrailer) {
  World w;
  CollisionChecker cc(robot(), w);
  EXPECT_TRUE(cc.is_valid(home())) << cc.describe_collision(home());
  EXPECT_EQ(cc.describe_collision(home()), "");
}

TEST(Collision, LimitsAreReported) {
  World w;
  CollisionChecker cc(robot(), w);
  JointVector q = home();
  q[plr::sim::kArm2] = 3.0;
  EXPECT_FALSE(cc.is_valid(q));
  EXPECT_EQ(cc.describe_collision(q), "arm_2 beyond limits");
}

TEST(Collision, BoxAtThePlateCollides) {
  World w;
  const Eigen::Vector3d plate = robot().plate_pose(home()).translation();
  w.boxes.push_back(box(12, plate.x() + 0.19, plate.y(), plate.z()));
  CollisionChecker cc(robot(), w);
  EXPECT_FALSE(cc.is_valid(home()));
  EXPECT_EQ(cc.describe_collision(home()), "plate - box 12");
  cc.ignore_box(12);
  EXPECT_TRUE(cc.is_valid(home()));
}

TEST(Collision, WallsAndFloorCollide) {
  World w;
  CollisionChecker cc(robot(), w);
  JointVector q = home();
  q[plr::sim::kArm1] = 1.57;  // arm sideways
  q[plr::sim::kArm2] = 0.0;
  q[plr::sim::kArm3] = 0.0;
  q[plr::sim::kArm4] = 0.0;
  EXPECT_FALSE(cc.is_valid(q));
  EXPECT_NE(cc.describe_collision(q).find("trailer"), std::string::npos)
      << cc.describe_collision(q);
  JointVector front = home(15.5);  // nose through the front wall
  EXPECT_FALSE(cc.is_valid(front));
}

TEST(Collision, SelfCollisionButNotAdjacentLinks) {
  World w;
  CollisionChecker cc(robot(), w);
  // Forearm folded back down into the base.
  JointVector q = home(3.0);
  q[plr::sim::kArm2] = 0.3;
  q[plr::sim::kArm3] = 2.5;
  q[plr::sim::kArm4] = 0.0;
  const std::string what = cc.describe_collision(q);
  EXPECT_FALSE(cc.is_valid(q));
  EXPECT_EQ(what.find("trailer"), std::string::npos) << what;
  EXPECT_EQ(what.find("box"), std::string::npos) << what;
}

TEST(Collision, HeldBoxCountsAsArm) {
  World w;
  const JointVector q = home();
  const Eigen::Isometry3d plate = robot().plate_pose(q);
  Box held = box(5, 0, 0, 0, 0.5);
  held.pose = plate * Eigen::Translation3d(0.25, 0.0, 0.0);
  w.boxes.push_back(held);
  CollisionChecker cc(robot(), w);
  EXPECT_FALSE(cc.is_valid(q));
  cc.attach_box(held, q);
  EXPECT_TRUE(cc.is_valid(q)) << cc.describe_collision(q);
  // A box just in front of the held one: moving forward hits it with the
  // held box, not with the plate.
  World w2 = w;
  w2.boxes.push_back(box(6, held.pose.translation().x() + 0.5, held.pose.translation().y(),
                         held.pose.translation().z()));
  CollisionChecker cc2(robot(), w2);
  cc2.attach_box(held, q);
  EXPECT_TRUE(cc2.is_valid(q)) << cc2.describe_collision(q);
  JointVector ahead = q;
  ahead[plr::sim::kBaseX] += 0.3;
  EXPECT_EQ(cc2.describe_collision(ahead), "held box 5 - box 6");
  EXPECT_FALSE(cc2.is_motion_valid(q, ahead));
  cc.detach_all();
  cc.clear_ignored_boxes();
  EXPECT_FALSE(cc.is_valid(q));
}

TEST(Collision, HeldBoxMayTouchWhatItWasTakenFrom) {
  const JointVector q = home();
  Box held = box(5, 0, 0, 0, 0.5);
  held.pose = robot().plate_pose(q) * Eigen::Translation3d(0.25, 0.0, 0.0);
  World w;
  w.boxes.push_back(held);
  // Its neighbour below, face to face: the lift starts from touching it.
  w.boxes.push_back(box(6, held.pose.translation().x(), held.pose.translation().y(),
                        held.pose.translation().z() - 0.5, 0.5));
  CollisionChecker cc(robot(), w);
  cc.attach_box(held, q);
  EXPECT_TRUE(cc.is_valid(q)) << cc.describe_collision(q);
  w.boxes[1].pose.translation().z() += 0.05;  // 5 cm into the held box: a real collision
  CollisionChecker cc2(robot(), w);
  cc2.attach_box(held, q);
  EXPECT_FALSE(cc2.is_valid(q));
}

TEST(Collision, MotionThroughThinObstacleIsCaughtBetweenEndpoints) {
  // A thin board between two free configurations: endpoints are free, the
  // straight motion is not.
  World w;
  JointVector a = home(2.0), b = home(2.0);
  a[plr::sim::kArm1] = -0.8;
  b[plr::sim::kArm1] = 0.8;
  Box board;
  board.id = 1;
  board.size = Eigen::Vector3d(3.0, 0.03, 0.3);
  board.pose.translation() =
      robot().plate_pose(home(2.0)).translation() + Eigen::Vector3d(0.5, 0, 0);
  w.boxes.push_back(board);
  CollisionChecker cc(robot(), w);
  ASSERT_TRUE(cc.is_valid(a)) << cc.describe_collision(a);
  ASSERT_TRUE(cc.is_valid(b)) << cc.describe_collision(b);
  EXPECT_FALSE(cc.is_motion_valid(a, b));
  JointVector c = a;
  c[plr::sim::kArm1] = -0.4;
  EXPECT_TRUE(cc.is_motion_valid(a, c));
}

TEST(Collision, FreeMotionFarFromObstaclesIsCheap) {
  World w;
  CollisionChecker cc(robot(), w);
  cc.reset_stats();
  EXPECT_TRUE(cc.is_motion_valid(home(1.0), home(3.0)));
  // One sweep for the whole 2 m when nothing is near; a few more at most.
  EXPECT_LE(cc.stats().sweep_checks, 8u);
}

TEST(Collision, NoseDownDriveOverTheFloorIsOneSweepAndABoxAheadStillStopsIt) {
  // Nose lowered and pitched (scoop tip just above the floor): a tilted box
  // stretched along its own axes would dip into the floor on a 2 m drive.
  World w;
  JointVector a = home(1.0), b = home(3.0);
  for (JointVector* q : {&a, &b}) {
    (*q)[plr::sim::kNose1] = 0.0;
    (*q)[plr::sim::kNose2] = 0.05;
    (*q)[plr::sim::kNose3] = 0.3;
  }
  CollisionChecker cc(robot(), w);
  ASSERT_TRUE(cc.is_valid(a)) << cc.describe_collision(a);
  ASSERT_TRUE(cc.is_valid(b)) << cc.describe_collision(b);
  cc.reset_stats();
  EXPECT_TRUE(cc.is_motion_valid(a, b, false));
  EXPECT_EQ(cc.stats().sweep_checks, 1u);
  EXPECT_EQ(cc.stats().state_checks, 0u);

  // A low box in the scoop's way, half way along the drive.
  w.boxes.push_back(box(1, 3.0, 0.0, 0.05, 0.1));
  CollisionChecker blocked(robot(), w);
  ASSERT_TRUE(blocked.is_valid(a));
  EXPECT_FALSE(blocked.is_motion_valid(a, b, false));
}

namespace {

std::unique_ptr<fcl::CollisionObjectd> fcl_object(std::shared_ptr<fcl::CollisionGeometryd> g,
                                                  const Eigen::Isometry3d& pose) {
  fcl::Transform3d tf = fcl::Transform3d::Identity();
  tf.linear() = pose.linear();
  tf.translation() = pose.translation();
  return std::make_unique<fcl::CollisionObjectd>(std::move(g), tf);
}

bool fcl_collide(const fcl::CollisionObjectd& a, const fcl::CollisionObjectd& b) {
  fcl::CollisionRequestd req;
  fcl::CollisionResultd res;
  return fcl::collide(&a, &b, req, res) > 0;
}

// Validity by FCL's own narrow phase and octree traversal alone: every link
// shape against the octree, every box and every other link not allowed to
// touch it, without the checker's occupancy grid, box tests or caches.
bool valid_by_fcl_alone(const JointVector& q, const World& w,
                        const std::shared_ptr<const octomap::OcTree>& tree) {
  const RobotModel& m = robot();
  std::vector<Eigen::Isometry3d> poses;
  m.forward_kinematics(q, poses);
  std::vector<std::pair<int, std::unique_ptr<fcl::CollisionObjectd>>> shapes;
  for (std::size_t l = 0; l < m.links().size(); ++l) {
    for (const auto& s : m.links()[l].shapes) {
      std::shared_ptr<fcl::CollisionGeometryd> g;
      if (s.type == plr::sim::CollisionShape::Type::kBox)
        g = std::make_shared<fcl::Boxd>(s.size);
      else if (s.type == plr::sim::CollisionShape::Type::kCylinder)
        g = std::make_shared<fcl::Cylinderd>(s.size.x(), s.size.y());
      else
        g = std::make_shared<fcl::Sphered>(s.size.x());
      shapes.emplace_back(static_cast<int>(l), fcl_object(g, poses[l] * s.origin));
    }
  }
  const fcl::CollisionObjectd octree(std::make_shared<fcl::OcTreed>(tree));
  for (const auto& [link, shape] : shapes) {
    if (fcl_collide(*shape, octree)) return false;
    for (const Box& b : w.boxes)
      if (fcl_collide(*shape, *fcl_object(std::make_shared<fcl::Boxd>(b.size), b.pose)))
        return false;
  }
  auto allowed = [&](int a, int b) {
    if (a == b || m.links()[a].parent_link == b || m.links()[b].parent_link == a) return true;
    for (const auto& [x, y] : m.allowed_collisions())
      if ((x == a && y == b) || (x == b && y == a)) return true;
    return false;
  };
  for (std::size_t i = 0; i < shapes.size(); ++i)
    for (std::size_t j = i + 1; j < shapes.size(); ++j)
      if (!allowed(shapes[i].first, shapes[j].first) &&
          fcl_collide(*shapes[i].second, *shapes[j].second))
        return false;
  return true;
}

}  // namespace

// The checker's shortcuts (occupied-cell grid, FCL's box-box SAT in place of
// its narrow phase, cached free placements) must not change any answer.
TEST(Collision, AgreesWithFclAloneOnRandomStates) {
  World w;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (std::uint32_t id = 1; id <= 25; ++id) {
    Box b =
        box(id, 4.0 + 2.5 * u(rng), -1.0 + 2.0 * u(rng), 0.2 + 2.2 * u(rng), 0.3 + 0.2 * u(rng));
    b.pose.linear() = Eigen::AngleAxisd(u(rng), Eigen::Vector3d::UnitZ()).toRotationMatrix();
    w.boxes.push_back(b);
  }
  const std::shared_ptr<const octomap::OcTree> tree = plr::sim::build_trailer_octree(w.trailer);
  CollisionChecker cc(robot(), w, tree);
  int valid = 0, invalid = 0;
  for (int n = 0; n < 1500; ++n) {
    // Around the folded arm, an eighth of each joint's range either way.
    JointVector q = home(0.5 + 2.5 * u(rng));
    for (int j = plr::sim::kArm1; j < plr::sim::kNumJoints; ++j) {
      const auto& l = robot().limits(j);
      q[j] = std::clamp(q[j] + (l.upper - l.lower) * (u(rng) - 0.5) / 4.0, l.lower, l.upper);
    }
    const bool expected = valid_by_fcl_alone(q, w, tree);
    ASSERT_EQ(cc.is_valid(q), expected)
        << "q = " << q.transpose() << ": " << cc.describe_collision(q);
    (expected ? valid : invalid)++;
  }
  // Both answers are common, so the comparison means something.
  EXPECT_GT(valid, 150) << invalid;
  EXPECT_GT(invalid, 150);
}
