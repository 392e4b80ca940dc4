#include "plr/sim/collision.hpp"

#include <gtest/gtest.h>

#include <fcl/fcl.h>
#include <octomap/octomap.h>

#include <algorithm>
#include <memory>
#include <random>

using plr::sim::Box;
using plr::sim::CollisionChecker;
using plr::sim::Config;
using plr::sim::RobotModel;
using plr::sim::World;

namespace {

const RobotModel& robot() {
  static const RobotModel m = RobotModel::fromUrdfFile(PLR_UNLOADER_URDF);
  return m;
}

// Arm folded above the raised nose, robot 1 m inside the trailer.
Config home(double base_x = 1.0) {
  Config q;
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

TEST(Collision, TrailerOctreeHasShellNotInterior) {
  const auto tree = plr::sim::makeTrailerOctree(plr::sim::Trailer{}, 0.05);
  auto occupied = [&](double x, double y, double z) {
    const auto* n = tree->search(x, y, z);
    return n != nullptr && tree->isNodeOccupied(n);
  };
  EXPECT_TRUE(occupied(3.0, 0.0, -0.02));
  EXPECT_TRUE(occupied(3.0, 1.27, 1.0));
  EXPECT_TRUE(occupied(3.0, 0.0, 2.72));
  EXPECT_TRUE(occupied(16.02, 0.0, 1.0));
  EXPECT_FALSE(occupied(3.0, 0.0, 1.0));
  EXPECT_FALSE(occupied(-1.0, 0.0, 1.0));  // open rear
}

TEST(Collision, HomeIsFreeInEmptyTrailer) {
  World w;
  CollisionChecker cc(robot(), w);
  EXPECT_TRUE(cc.isValid(home())) << cc.describeCollision(home());
  EXPECT_EQ(cc.describeCollision(home()), "");
}

TEST(Collision, LimitsAreReported) {
  World w;
  CollisionChecker cc(robot(), w);
  Config q = home();
  q[plr::sim::kArm2] = 3.0;
  EXPECT_FALSE(cc.isValid(q));
  EXPECT_EQ(cc.describeCollision(q), "arm_2 beyond limits");
}

TEST(Collision, BoxAtThePlateCollides) {
  World w;
  const Eigen::Vector3d plate = robot().platePose(home()).translation();
  w.boxes.push_back(box(12, plate.x() + 0.19, plate.y(), plate.z()));
  CollisionChecker cc(robot(), w);
  EXPECT_FALSE(cc.isValid(home()));
  EXPECT_EQ(cc.describeCollision(home()), "plate - box 12");
  cc.ignoreBox(12);
  EXPECT_TRUE(cc.isValid(home()));
}

TEST(Collision, WallsAndFloorCollide) {
  World w;
  CollisionChecker cc(robot(), w);
  Config q = home();
  q[plr::sim::kArm1] = 1.57;  // arm sideways
  q[plr::sim::kArm2] = 0.0;
  q[plr::sim::kArm3] = 0.0;
  q[plr::sim::kArm4] = 0.0;
  EXPECT_FALSE(cc.isValid(q));
  EXPECT_NE(cc.describeCollision(q).find("trailer"), std::string::npos) << cc.describeCollision(q);
  Config front = home(15.5);  // nose through the front wall
  EXPECT_FALSE(cc.isValid(front));
}

TEST(Collision, SelfCollisionButNotAdjacentLinks) {
  World w;
  CollisionChecker cc(robot(), w);
  // Forearm folded back down into the base.
  Config q = home(3.0);
  q[plr::sim::kArm2] = 0.3;
  q[plr::sim::kArm3] = 2.5;
  q[plr::sim::kArm4] = 0.0;
  const std::string what = cc.describeCollision(q);
  EXPECT_FALSE(cc.isValid(q));
  EXPECT_EQ(what.find("trailer"), std::string::npos) << what;
  EXPECT_EQ(what.find("box"), std::string::npos) << what;
}

TEST(Collision, HeldBoxCountsAsArm) {
  World w;
  const Config q = home();
  const Eigen::Isometry3d plate = robot().platePose(q);
  Box held = box(5, 0, 0, 0, 0.5);
  held.pose = plate * Eigen::Translation3d(0.25, 0.0, 0.0);
  w.boxes.push_back(held);
  CollisionChecker cc(robot(), w);
  EXPECT_FALSE(cc.isValid(q));
  cc.attachBox(held, q);
  EXPECT_TRUE(cc.isValid(q)) << cc.describeCollision(q);
  // A box just in front of the held one: moving forward hits it with the
  // held box, not with the plate.
  World w2 = w;
  w2.boxes.push_back(box(6, held.pose.translation().x() + 0.5, held.pose.translation().y(),
                         held.pose.translation().z()));
  CollisionChecker cc2(robot(), w2);
  cc2.attachBox(held, q);
  EXPECT_TRUE(cc2.isValid(q)) << cc2.describeCollision(q);
  Config ahead = q;
  ahead[plr::sim::kBaseX] += 0.3;
  EXPECT_EQ(cc2.describeCollision(ahead), "held box 5 - box 6");
  EXPECT_FALSE(cc2.isMotionValid(q, ahead));
  cc.detachAll();
  cc.clearIgnoredBoxes();
  EXPECT_FALSE(cc.isValid(q));
}

TEST(Collision, HeldBoxMayTouchWhatItWasTakenFrom) {
  const Config q = home();
  Box held = box(5, 0, 0, 0, 0.5);
  held.pose = robot().platePose(q) * Eigen::Translation3d(0.25, 0.0, 0.0);
  World w;
  w.boxes.push_back(held);
  // Its neighbour below, face to face: the lift starts from touching it.
  w.boxes.push_back(box(6, held.pose.translation().x(), held.pose.translation().y(),
                        held.pose.translation().z() - 0.5, 0.5));
  CollisionChecker cc(robot(), w);
  cc.attachBox(held, q);
  EXPECT_TRUE(cc.isValid(q)) << cc.describeCollision(q);
  w.boxes[1].pose.translation().z() += 0.05;  // 5 cm into the held box: a real collision
  CollisionChecker cc2(robot(), w);
  cc2.attachBox(held, q);
  EXPECT_FALSE(cc2.isValid(q));
}

TEST(Collision, MotionThroughThinObstacleIsCaughtBetweenEndpoints) {
  // A thin board between two free configurations: endpoints are free, the
  // straight motion is not.
  World w;
  Config a = home(2.0), b = home(2.0);
  a[plr::sim::kArm1] = -0.8;
  b[plr::sim::kArm1] = 0.8;
  Box board;
  board.id = 1;
  board.size = Eigen::Vector3d(3.0, 0.03, 0.3);
  board.pose.translation() =
      robot().platePose(home(2.0)).translation() + Eigen::Vector3d(0.5, 0, 0);
  w.boxes.push_back(board);
  CollisionChecker cc(robot(), w);
  ASSERT_TRUE(cc.isValid(a)) << cc.describeCollision(a);
  ASSERT_TRUE(cc.isValid(b)) << cc.describeCollision(b);
  EXPECT_FALSE(cc.isMotionValid(a, b));
  Config c = a;
  c[plr::sim::kArm1] = -0.4;
  EXPECT_TRUE(cc.isMotionValid(a, c));
}

TEST(Collision, FreeMotionFarFromObstaclesIsCheap) {
  World w;
  CollisionChecker cc(robot(), w);
  cc.resetStats();
  EXPECT_TRUE(cc.isMotionValid(home(1.0), home(3.0)));
  // One sweep for the whole 2 m when nothing is near; a few more at most.
  EXPECT_LE(cc.stats().sweep_checks, 8u);
}

TEST(Collision, NoseDownDriveOverTheFloorIsOneSweepAndABoxAheadStillStopsIt) {
  // Nose lowered and pitched (scoop tip just above the floor): a tilted box
  // stretched along its own axes would dip into the floor on a 2 m drive.
  World w;
  Config a = home(1.0), b = home(3.0);
  for (Config* q : {&a, &b}) {
    (*q)[plr::sim::kNose1] = 0.0;
    (*q)[plr::sim::kNose2] = 0.05;
    (*q)[plr::sim::kNose3] = 0.3;
  }
  CollisionChecker cc(robot(), w);
  ASSERT_TRUE(cc.isValid(a)) << cc.describeCollision(a);
  ASSERT_TRUE(cc.isValid(b)) << cc.describeCollision(b);
  cc.resetStats();
  EXPECT_TRUE(cc.isMotionValid(a, b, false));
  EXPECT_EQ(cc.stats().sweep_checks, 1u);
  EXPECT_EQ(cc.stats().state_checks, 0u);

  // A low box in the scoop's way, half way along the drive.
  w.boxes.push_back(box(1, 3.0, 0.0, 0.05, 0.1));
  CollisionChecker blocked(robot(), w);
  ASSERT_TRUE(blocked.isValid(a));
  EXPECT_FALSE(blocked.isMotionValid(a, b, false));
}

namespace {

std::unique_ptr<fcl::CollisionObjectd> fclObject(std::shared_ptr<fcl::CollisionGeometryd> g,
                                                 const Eigen::Isometry3d& pose) {
  fcl::Transform3d tf = fcl::Transform3d::Identity();
  tf.linear() = pose.linear();
  tf.translation() = pose.translation();
  return std::make_unique<fcl::CollisionObjectd>(std::move(g), tf);
}

bool fclCollide(const fcl::CollisionObjectd& a, const fcl::CollisionObjectd& b) {
  fcl::CollisionRequestd req;
  fcl::CollisionResultd res;
  return fcl::collide(&a, &b, req, res) > 0;
}

// Validity by FCL's own narrow phase and octree traversal alone: every link
// shape against the octree, every box and every other link not allowed to
// touch it, without the checker's occupancy grid, box tests or caches.
bool validByFclAlone(const Config& q, const World& w,
                     const std::shared_ptr<const octomap::OcTree>& tree) {
  const RobotModel& m = robot();
  std::vector<Eigen::Isometry3d> poses;
  m.forwardKinematics(q, poses);
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
      shapes.emplace_back(static_cast<int>(l), fclObject(g, poses[l] * s.origin));
    }
  }
  const fcl::CollisionObjectd octree(std::make_shared<fcl::OcTreed>(tree));
  for (const auto& [link, shape] : shapes) {
    if (fclCollide(*shape, octree)) return false;
    for (const Box& b : w.boxes)
      if (fclCollide(*shape, *fclObject(std::make_shared<fcl::Boxd>(b.size), b.pose))) return false;
  }
  auto allowed = [&](int a, int b) {
    if (a == b || m.links()[a].parent_link == b || m.links()[b].parent_link == a) return true;
    for (const auto& [x, y] : m.allowedCollisions())
      if ((x == a && y == b) || (x == b && y == a)) return true;
    return false;
  };
  for (std::size_t i = 0; i < shapes.size(); ++i)
    for (std::size_t j = i + 1; j < shapes.size(); ++j)
      if (!allowed(shapes[i].first, shapes[j].first) &&
          fclCollide(*shapes[i].second, *shapes[j].second))
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
  const auto tree = plr::sim::makeTrailerOctree(w.trailer, 0.05);
  CollisionChecker cc(robot(), w, tree);
  int valid = 0, invalid = 0;
  for (int n = 0; n < 1500; ++n) {
    // Around the folded arm, an eighth of each joint's range either way.
    Config q = home(0.5 + 2.5 * u(rng));
    for (int j = plr::sim::kArm1; j < plr::sim::kNumJoints; ++j) {
      const auto& l = robot().limits(j);
      q[j] = std::clamp(q[j] + (l.upper - l.lower) * (u(rng) - 0.5) / 4.0, l.lower, l.upper);
    }
    const bool expected = validByFclAlone(q, w, tree);
    ASSERT_EQ(cc.isValid(q), expected)
        << "q = " << q.transpose() << ": " << cc.describeCollision(q);
    (expected ? valid : invalid)++;
  }
  // Both answers are common, so the comparison means something.
  EXPECT_GT(valid, 150) << invalid;
  EXPECT_GT(invalid, 150);
}
