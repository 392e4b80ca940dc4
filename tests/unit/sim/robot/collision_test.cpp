#include "plr/sim/collision.hpp"
#include "plr/sim/generators.hpp"
#include "plr/sim/octree.hpp"

#include <gtest/gtest.h>

#include <fcl/fcl.h>
#include <octomap/octomap.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <optional>
#include <random>
#include <thread>

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
  EXPECT_TRUE(cc.is_valid(plr::sim::home_configuration(1.0)))
      << cc.describe_collision(plr::sim::home_configuration(1.0));
  EXPECT_EQ(cc.describe_collision(plr::sim::home_configuration(1.0)), "");
}

TEST(Collision, LimitsAreReported) {
  World w;
  CollisionChecker cc(robot(), w);
  JointVector q = plr::sim::home_configuration(1.0);
  q[plr::sim::kArm2] = 3.0;
  EXPECT_FALSE(cc.is_valid(q));
  EXPECT_EQ(cc.describe_collision(q), "arm_2 beyond limits");
}

TEST(Collision, BoxAtThePlateCollides) {
  World w;
  const Eigen::Vector3d plate = robot().plate_pose(plr::sim::home_configuration(1.0)).translation();
  w.boxes.push_back(box(12, plate.x() + 0.19, plate.y(), plate.z()));
  CollisionChecker cc(robot(), w);
  EXPECT_FALSE(cc.is_valid(plr::sim::home_configuration(1.0)));
  EXPECT_EQ(cc.describe_collision(plr::sim::home_configuration(1.0)), "plate - box 12");
  cc.ignore_box(12);
  EXPECT_TRUE(cc.is_valid(plr::sim::home_configuration(1.0)));
}

TEST(Collision, WallsAndFloorCollide) {
  World w;
  CollisionChecker cc(robot(), w);
  JointVector q = plr::sim::home_configuration(1.0);
  q[plr::sim::kArm1] = 1.57;  // arm sideways
  q[plr::sim::kArm2] = 0.0;
  q[plr::sim::kArm3] = 0.0;
  q[plr::sim::kArm4] = 0.0;
  EXPECT_FALSE(cc.is_valid(q));
  EXPECT_NE(cc.describe_collision(q).find("trailer"), std::string::npos)
      << cc.describe_collision(q);
  JointVector front = plr::sim::home_configuration(15.5);  // nose through the front wall
  EXPECT_FALSE(cc.is_valid(front));
}

TEST(Collision, SelfCollisionButNotAdjacentLinks) {
  World w;
  CollisionChecker cc(robot(), w);
  // Forearm folded back down into the base.
  JointVector q = plr::sim::home_configuration(3.0);
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
  const JointVector q = plr::sim::home_configuration(1.0);
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
  const JointVector q = plr::sim::home_configuration(1.0);
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
  JointVector a = plr::sim::home_configuration(2.0), b = plr::sim::home_configuration(2.0);
  a[plr::sim::kArm1] = -0.8;
  b[plr::sim::kArm1] = 0.8;
  Box board;
  board.id = 1;
  board.size = Eigen::Vector3d(3.0, 0.03, 0.3);
  board.pose.translation() = robot().plate_pose(plr::sim::home_configuration(2.0)).translation() +
                             Eigen::Vector3d(0.5, 0, 0);
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
  EXPECT_TRUE(
      cc.is_motion_valid(plr::sim::home_configuration(1.0), plr::sim::home_configuration(3.0)));
  // One sweep for the whole 2 m when nothing is near; a few more at most.
  EXPECT_LE(cc.stats().sweep_checks, 8u);
}

TEST(Collision, NoseDownDriveOverTheFloorIsOneSweepAndABoxAheadStillStopsIt) {
  // Nose lowered and pitched (scoop tip just above the floor): a tilted box
  // stretched along its own axes would dip into the floor on a 2 m drive.
  World w;
  JointVector a = plr::sim::home_configuration(1.0), b = plr::sim::home_configuration(3.0);
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
// A 40 ft container (2.35 m wide, 2.39 m high) is off the octree's 5 cm
// grid: its shell's leaves reach 2.5 cm into the sides and 4 cm below the
// ceiling. A box packed against the wall or just under the ceiling, once
// held, is still clear of the shell; pushed 1 cm into the wall it is not.
TEST(Collision, AHeldBoxAgainstAContainerWallOffTheOctreeGridIsClearOfIt) {
  World w;
  w.trailer = {2.35, 2.39, 12.0};
  const JointVector q = plr::sim::home_configuration(1.0);
  const double side = 0.5 * w.trailer.width;
  const auto held_at = [&](double y, double z) {
    CollisionChecker cc(robot(), w);
    cc.attach_box(box(7, 6.0, y, z, 0.5), q);
    return cc;
  };
  EXPECT_TRUE(held_at(side - 0.25, 1.0).is_valid(q))
      << held_at(side - 0.25, 1.0).describe_collision(q);
  EXPECT_TRUE(held_at(-side + 0.25, 1.0).is_valid(q));
  EXPECT_TRUE(held_at(0.0, w.trailer.height - 0.25).is_valid(q));
  EXPECT_EQ(held_at(side - 0.24, 1.0).describe_collision(q), "held box 7 - trailer");
  EXPECT_EQ(held_at(0.0, w.trailer.height - 0.24).describe_collision(q), "held box 7 - trailer");
  // Slid along the wall, as a lift or a pull-out does.
  JointVector back = q;
  back[plr::sim::kBaseX] -= 0.3;
  EXPECT_TRUE(held_at(side - 0.25, 1.0).is_motion_valid(q, back));
}

// The grip turns a box a few degrees (C seed 12: 6.6 degrees about z) while it
// stays against the wall; held so, it is still clear of the shell.
TEST(Collision, AHeldBoxTurnedAgainstAContainerWallIsClearOfIt) {
  World w;
  w.trailer = {2.35, 2.39, 12.0};
  const JointVector q = plr::sim::home_configuration(1.0);
  const double side = 0.5 * w.trailer.width;
  const double turn = 0.115;  // rad
  const auto held_at = [&](double gap) {
    Box b = box(7, 6.0, 0.0, 1.0, 0.5);
    b.pose.linear() = Eigen::AngleAxisd(turn, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    b.pose.translation().y() = side - 0.25 * (std::cos(turn) + std::sin(turn)) - gap;
    CollisionChecker cc(robot(), w);
    cc.attach_box(b, q);
    return cc;
  };
  EXPECT_TRUE(held_at(0.001).is_valid(q)) << held_at(0.001).describe_collision(q);
  EXPECT_EQ(held_at(-0.01).describe_collision(q), "held box 7 - trailer");
}

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
    JointVector q = plr::sim::home_configuration(0.5 + 2.5 * u(rng));
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

namespace {

// Random configurations around the folded arm, base x in [base, base +
// span], a sixth of each joint's range either way (often touching boxes in
// front of it), in threes that differ in the arm joints only: the base and
// nose shapes keep their placement, whose "free" result the checker caches.
std::vector<JointVector> random_states(int count, double base, double span, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  auto perturb = [&](JointVector& q, int from, int to) {
    for (int j = from; j < to; ++j) {
      const auto& l = robot().limits(j);
      q[j] = std::clamp(
          plr::sim::home_configuration(1.0)[j] + (l.upper - l.lower) * (u(rng) - 0.5) / 3.0,
          l.lower, l.upper);
    }
  };
  std::vector<JointVector> out;
  JointVector q = plr::sim::home_configuration(base);
  for (int i = 0; i < count; ++i) {
    if (i % 3 == 0) {
      q[plr::sim::kBaseX] = base + span * u(rng);
      perturb(q, plr::sim::kNose1, plr::sim::kNumJoints);
    }
    perturb(q, plr::sim::kArm1, plr::sim::kNose1);
    out.push_back(q);
  }
  return out;
}

// Leaves cached "free" results in `cc` for the first states: what an update
// that kept them would answer wrong on.
void warm(const CollisionChecker& cc, const std::vector<JointVector>& states) {
  cc.is_valid(states[0]);
  cc.is_motion_valid(states[0], states[1], false);
}

Box random_box(std::uint32_t id, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Box b = box(id, 2.5 + 2.5 * u(rng), -1.1 + 2.2 * u(rng), 0.2 + 2.2 * u(rng));
  b.size = Eigen::Vector3d(0.2 + 0.4 * u(rng), 0.2 + 0.4 * u(rng), 0.2 + 0.4 * u(rng));
  if (u(rng) < 0.3) {
    b.pose.linear() = Eigen::AngleAxisd(u(rng), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  } else if (u(rng) < 0.2) {  // fallen over: any orientation
    b.pose.linear() = Eigen::Quaterniond::UnitRandom().toRotationMatrix();
  }
  return b;
}

// The next world of a random sequence: boxes removed, moved a little or far,
// resized, added with new ids, and the list shuffled.
void step_world(World& w, std::uint32_t& next_id, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::vector<Box> boxes;
  for (Box b : w.boxes) {
    const double r = u(rng);
    if (r < 0.15) continue;  // taken out
    if (r < 0.45) {
      b.pose.translation() += Eigen::Vector3d(u(rng) - 0.5, u(rng) - 0.5, u(rng) - 0.5) * 0.02;
    } else if (r < 0.55) {
      b = random_box(b.id, rng);  // same id, anywhere, another size
    }
    boxes.push_back(b);
  }
  const int added = static_cast<int>(4 * u(rng));
  for (int i = 0; i < added; ++i) boxes.push_back(random_box(next_id++, rng));
  if (u(rng) < 0.2 && !boxes.empty()) boxes.push_back(boxes.front());  // an id twice
  std::shuffle(boxes.begin(), boxes.end(), rng);
  w.boxes = std::move(boxes);
}

// `updated` and `fresh` give the same answers, collision texts and check
// counts on `states` and on motions from each (both ends checked or not).
void expect_same_answers(CollisionChecker& updated, CollisionChecker& fresh,
                         const std::vector<JointVector>& states, int& valid, int& invalid) {
  updated.reset_stats();
  fresh.reset_stats();
  for (std::size_t i = 0; i < states.size(); ++i) {
    const JointVector& q = states[i];
    const bool ok = fresh.is_valid(q);
    ASSERT_EQ(updated.is_valid(q), ok) << "q = " << q.transpose();
    ASSERT_EQ(updated.describe_collision(q), fresh.describe_collision(q))
        << "q = " << q.transpose();
    (ok ? valid : invalid)++;
    const JointVector& next = states[(i + 1) % states.size()];
    ASSERT_EQ(updated.is_motion_valid(q, next, false), fresh.is_motion_valid(q, next, false));
    // A quarter of the way to another state: mostly short motions, some
    // near boxes (checked at motion_resolution), some crossing them.
    const JointVector b = q + 0.25 * (states[(i * 7 + 3) % states.size()] - q);
    ASSERT_EQ(updated.is_motion_valid(q, b), fresh.is_motion_valid(q, b));
    ASSERT_EQ(updated.is_motion_valid(q, b, false), fresh.is_motion_valid(q, b, false));
  }
  EXPECT_EQ(updated.stats().state_checks, fresh.stats().state_checks);
  EXPECT_EQ(updated.stats().sweep_checks, fresh.stats().sweep_checks);
}

}  // namespace

// set_boxes() must leave no trace of the previous boxes: not in the FCL
// objects reused by id, the x-sorted index, or the cached "free" placements.
// The same states are asked after every update, so a stale cache would show.
TEST(Collision, UpdatedCheckerAnswersAsAFreshOneOnRandomWorlds) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const std::shared_ptr<const octomap::OcTree> tree =
      plr::sim::build_trailer_octree(plr::sim::Trailer{});
  World w;
  std::uint32_t next_id = 1;
  for (; next_id <= 30; ++next_id) w.boxes.push_back(random_box(next_id, rng));
  const std::vector<JointVector> states = random_states(42, 1.0, 2.0, rng);

  CollisionChecker updated(robot(), w, tree);
  // A held box and ignored ids (some absent from the world), the same on
  // both checkers; kept over most updates, since changing them clears the
  // caches that a stale update would leave wrong.
  std::optional<std::pair<Box, JointVector>> held;
  std::vector<std::uint32_t> ignored;
  int valid = 0, invalid = 0;
  for (int step = 0; step < 30; ++step) {
    warm(updated, states);
    step_world(w, next_id, rng);
    const bool new_scope = step % 3 == 1 && !w.boxes.empty();
    if (new_scope) {
      const JointVector q = states[static_cast<std::size_t>(step) % states.size()];
      Box b = w.boxes[static_cast<std::size_t>(step) % w.boxes.size()];
      b.pose = robot().plate_pose(q) * Eigen::Translation3d(b.size.x() / 2, 0, 0);
      held.reset();
      if (step % 2 == 1) held.emplace(b, q);
      ignored.clear();
      for (int k = 0; k < 3; ++k)
        ignored.push_back(1 + static_cast<std::uint32_t>(u(rng) * next_id));
      updated.detach_all();
      updated.clear_ignored_boxes();
      if (held) updated.attach_box(held->first, held->second);
    }
    updated.set_boxes(w.boxes);
    if (new_scope)  // held box attached before the update, ids ignored after it
      for (std::uint32_t id : ignored) updated.ignore_box(id);

    CollisionChecker fresh(robot(), w, tree);
    if (held) fresh.attach_box(held->first, held->second);
    for (std::uint32_t id : ignored) fresh.ignore_box(id);

    std::vector<JointVector> asked = states;
    for (const JointVector& q : random_states(9, 1.0, 2.0, rng)) asked.push_back(q);
    ASSERT_NO_FATAL_FAILURE(expect_same_answers(updated, fresh, asked, valid, invalid))
        << "step " << step;
  }
  // Both answers are common, so the comparison means something.
  EXPECT_GT(valid, 200) << invalid;
  EXPECT_GT(invalid, 200) << valid;
}

// The nose keeps its placement over an arm-only motion, so its "free"
// results from the old world are cached: a box put on it must still count.
TEST(Collision, UpdateForgetsWhatWasFreeInTheOldWorld) {
  // Nose down and out, away from the arm, which turns the plate a little.
  JointVector a = plr::sim::home_configuration(2.0);
  a[plr::sim::kNose1] = 0.0;
  a[plr::sim::kNose3] = 0.3;
  JointVector b = a;
  b[plr::sim::kArm4] += 0.1;
  std::vector<Eigen::Isometry3d> poses;
  robot().forward_kinematics(a, poses);
  const int nose = robot().link_index("nose_conveyor");
  Box on_nose = box(7, 0, 0, 0, 0.1);
  on_nose.pose.translation() =
      (poses[nose] * robot().links()[nose].shapes.front().origin).translation();
  CollisionChecker cc(robot(), World{});
  ASSERT_TRUE(cc.is_valid(a)) << cc.describe_collision(a);
  ASSERT_TRUE(cc.is_motion_valid(a, b, false));
  cc.set_boxes({on_nose});
  EXPECT_FALSE(cc.is_valid(a));
  EXPECT_FALSE(cc.is_motion_valid(a, b, false));
  EXPECT_EQ(cc.describe_collision(a), "nose_conveyor - box 7");
  cc.set_boxes({});
  EXPECT_TRUE(cc.is_valid(a));
  EXPECT_TRUE(cc.is_motion_valid(a, b, false));
}

// The executor's use: generated walls and piles, front boxes taken out one
// by one and the rest settling by a few millimetres; the trailer changes
// between scenes (set_world, octree given or built from the sizes).
TEST(Collision, UpdatedCheckerAnswersAsAFreshOneOnGeneratedWorlds) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const plr::sim::Trailer narrow{2.35, 2.39, 12.0};
  std::unique_ptr<CollisionChecker> updated;
  int valid = 0, invalid = 0;
  for (int scene = 0; scene < 4; ++scene) {
    World w = plr::sim::generate_world(
        scene % 2 == 0 ? plr::sim::EnvFamily::kA1 : plr::sim::EnvFamily::kB1, 40 + scene,
        scene < 2 ? plr::sim::Trailer{} : narrow);
    const std::shared_ptr<const octomap::OcTree> tree =
        scene % 3 == 0 ? nullptr : plr::sim::build_trailer_octree(w.trailer);
    for (int pick = 0; pick < 6 && !w.boxes.empty(); ++pick) {
      double front = w.trailer.depth;
      for (const Box& b : w.boxes) front = std::min(front, b.pose.translation().x());
      const std::vector<JointVector> states = random_states(30, front - 1.6, 0.6, rng);
      if (updated) warm(*updated, states);
      const auto first =
          std::min_element(w.boxes.begin(), w.boxes.end(), [](const Box& a, const Box& b) {
            return a.pose.translation().x() < b.pose.translation().x();
          });
      w.boxes.erase(first);
      for (Box& b : w.boxes)
        if (u(rng) < 0.3) b.pose.translation().z() -= 0.004 * u(rng);
      if (updated)
        updated->set_world(w, tree);
      else
        updated = std::make_unique<CollisionChecker>(robot(), w, tree);
      CollisionChecker fresh(robot(), w, tree);
      ASSERT_NO_FATAL_FAILURE(expect_same_answers(*updated, fresh, states, valid, invalid))
          << "scene " << scene << " pick " << pick;
    }
  }
  EXPECT_GT(valid, 100) << invalid;
  EXPECT_GT(invalid, 100) << valid;
}

// The trailer tables (FCL octree object, occupied-voxel table) are computed
// once per octree while a checker holds them or they were the last computed.
TEST(Collision, CheckersOnTheSameOctreeShareTheTrailerTables) {
  const std::shared_ptr<const octomap::OcTree> a =
      plr::sim::build_trailer_octree(plr::sim::Trailer{});
  const std::shared_ptr<const octomap::OcTree> b =
      plr::sim::build_trailer_octree(plr::sim::Trailer{2.35, 2.39, 12.0});
  World w;
  w.boxes.push_back(box(1, 3.0, 0.0, 0.3));
  const std::uint64_t n0 = CollisionChecker::trailer_builds();
  {
    CollisionChecker first(robot(), w, a);
    EXPECT_EQ(CollisionChecker::trailer_builds(), n0 + 1);
    CollisionChecker second(robot(), w, a);
    EXPECT_EQ(CollisionChecker::trailer_builds(), n0 + 1);
  }
  {
    CollisionChecker again(robot(), w, a);  // the last computed, kept
    EXPECT_EQ(CollisionChecker::trailer_builds(), n0 + 1);
    again.set_world(w, a);
    EXPECT_EQ(CollisionChecker::trailer_builds(), n0 + 1);
    again.set_world(w, b);
    EXPECT_EQ(CollisionChecker::trailer_builds(), n0 + 2);
    CollisionChecker on_b(robot(), w, b);
    EXPECT_EQ(CollisionChecker::trailer_builds(), n0 + 2);
  }
  // Neither held by a checker nor the last computed: gone.
  CollisionChecker on_a(robot(), w, a);
  EXPECT_EQ(CollisionChecker::trailer_builds(), n0 + 3);
  // The same tree under another owner is another key (identity is the
  // owner), so is a shell the checker builds itself; a shell is then found
  // by its sizes.
  const std::shared_ptr<const octomap::OcTree> alias(std::make_shared<int>(0), a.get());
  CollisionChecker on_alias(robot(), w, alias);
  EXPECT_EQ(CollisionChecker::trailer_builds(), n0 + 4);
  World shell = w;
  shell.trailer.depth = 13.0;
  CollisionChecker built(robot(), shell);
  EXPECT_EQ(CollisionChecker::trailer_builds(), n0 + 5);
  built.set_world(shell);
  CollisionChecker built_again(robot(), shell);
  EXPECT_EQ(CollisionChecker::trailer_builds(), n0 + 5);
  EXPECT_TRUE(on_a.is_valid(plr::sim::home_configuration(1.0)));
  EXPECT_FALSE(on_alias.is_valid(plr::sim::home_configuration(15.5)));
}

// Checkers on several threads share one trailer's tables and answer as one
// checker alone does.
TEST(Collision, CheckersOnSeveralThreadsShareATrailer) {
  std::mt19937 rng(3);
  const std::shared_ptr<const octomap::OcTree> tree =
      plr::sim::build_trailer_octree(plr::sim::Trailer{});
  World w;
  for (std::uint32_t id = 1; id <= 20; ++id) w.boxes.push_back(random_box(id, rng));
  const std::vector<JointVector> states = random_states(200, 1.0, 2.0, rng);
  std::vector<char> expected;
  {
    const CollisionChecker alone(robot(), w, tree);
    for (const JointVector& q : states) expected.push_back(alone.is_valid(q));
  }
  std::vector<std::vector<char>> got(4);
  std::vector<std::thread> threads;
  for (auto& answers : got) {
    threads.emplace_back([&, &answers = answers] {
      CollisionChecker cc(robot(), World{}, tree);
      cc.set_boxes(w.boxes);
      for (const JointVector& q : states) answers.push_back(cc.is_valid(q));
    });
  }
  for (auto& t : threads) t.join();
  for (const auto& answers : got) EXPECT_EQ(answers, expected);
}
