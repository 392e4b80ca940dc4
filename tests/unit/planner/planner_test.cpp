// Both planners on small hand-built worlds: statuses, limits, collision-free
// trajectories (re-checked densely with FCL directly, independently of the
// checker's sweeps), M6 escape, bad requests.
#include <gtest/gtest.h>

#include <fcl/fcl.h>

#include <atomic>
#include <cmath>
#include <thread>

#include "arastar_planner.hpp"
#include "ompl_planner.hpp"
#include "plr/sim/collision.hpp"
#include "plr/sim/plan_types.hpp"

using namespace plr::sim;

namespace {

const RobotModel& robot() {
  static const RobotModel m = RobotModel::from_urdf_file(PLR_UNLOADER_URDF);
  return m;
}

JointVector home(double base) {
  JointVector q;
  q << base, 0.0, -1.0, 2.0, 0.0, 0.5, 0.0, 0.0;
  return q;
}

// A wall of 0.4 m boxes across the trailer, front face at x = face; 5
// columns, the middle one centred on the trailer axis.
World wall(double face, int rows = 5) {
  World w;
  std::uint32_t id = 1;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < 5; ++c) {
      Box b;
      b.id = id++;
      b.size = Eigen::Vector3d(0.4, 0.4, 0.4);
      b.pose.translation() = Eigen::Vector3d(face + 0.2, 0.405 * (c - 2), 0.2 + 0.405 * r);
      w.boxes.push_back(b);
    }
  }
  return w;
}

// Box in row r (from the floor), column c (0..4, 2 centred).
const Box& at(const World& w, int r, int c) {
  return w.boxes[static_cast<std::size_t>(5 * r + c)];
}

plr::arastar::Planner& arastar() {
  static plr::arastar::Planner p(plr::arastar::LatticeConfig::from_file(PLR_ARASTAR_PRIMITIVES));
  return p;
}

PlanQuery pose_query(PlanMode mode, const JointVector& start, const Eigen::Vector3d& p,
                     double yaw) {
  PlanQuery q;
  q.mode = mode;
  q.start = start;
  PoseGoal g;
  g.target = {p, yaw};
  q.goal = g;
  return q;
}

PlanQuery joint_query(PlanMode mode, const JointVector& start, const JointVector& goal) {
  PlanQuery q;
  q.mode = mode;
  q.start = start;
  JointGoal g;
  g.q = goal;
  q.goal = g;
  return q;
}

// Independent re-check: samples the trajectory every 2 ms and collides every
// link box/cylinder with every world box and the trailer's inner walls as
// half-spaces with FCL directly (no octree, no sweeps, no caches).
std::string dense_collision(const Trajectory& traj, const World& world,
                            const std::vector<std::uint32_t>& ignored) {
  const RobotModel& m = robot();
  std::vector<std::pair<std::shared_ptr<fcl::CollisionGeometryd>, std::uint32_t>> boxes;
  for (const Box& b : world.boxes) {
    if (std::find(ignored.begin(), ignored.end(), b.id) == ignored.end()) {
      boxes.emplace_back(std::make_shared<fcl::Boxd>(b.size), b.id);
    }
  }
  const double hw = world.trailer.width / 2;
  std::vector<std::shared_ptr<fcl::CollisionGeometryd>> planes = {
      std::make_shared<fcl::Halfspaced>(Eigen::Vector3d(0, 0, 1), -1e-3),  // floor z < 0
      std::make_shared<fcl::Halfspaced>(Eigen::Vector3d(0, 0, -1), -world.trailer.height - 1e-3),
      std::make_shared<fcl::Halfspaced>(Eigen::Vector3d(0, 1, 0), -hw - 1e-3),
      std::make_shared<fcl::Halfspaced>(Eigen::Vector3d(0, -1, 0), -hw - 1e-3),
      std::make_shared<fcl::Halfspaced>(Eigen::Vector3d(-1, 0, 0), -world.trailer.depth - 1e-3)};
  std::vector<Eigen::Isometry3d> poses;
  for (double t = 0.0;; t += 0.002) {
    const JointVector q = traj.sample(std::min(t, traj.duration())).position;
    m.forward_kinematics(q, poses);
    for (std::size_t l = 0; l < m.links().size(); ++l) {
      for (const CollisionShape& s : m.links()[l].shapes) {
        std::shared_ptr<fcl::CollisionGeometryd> g;
        if (s.type == CollisionShape::Type::kBox) {
          g = std::make_shared<fcl::Boxd>(s.size);
        } else {
          g = std::make_shared<fcl::Cylinderd>(s.size.x(), s.size.y());
        }
        fcl::Transform3d tf = fcl::Transform3d::Identity();
        const Eigen::Isometry3d p = poses[l] * s.origin;
        tf.linear() = p.linear();
        tf.translation() = p.translation();
        fcl::CollisionObjectd link(g, tf);
        for (std::size_t i = 0; i < boxes.size(); ++i) {
          fcl::Transform3d bt = fcl::Transform3d::Identity();
          bt.linear() = world.boxes[i].pose.linear();
          bt.translation() = world.boxes[i].pose.translation();
          const Box* box = nullptr;
          for (const Box& b : world.boxes) {
            if (b.id == boxes[i].second) box = &b;
          }
          bt.linear() = box->pose.linear();
          bt.translation() = box->pose.translation();
          fcl::CollisionObjectd other(boxes[i].first, bt);
          fcl::CollisionRequestd req;
          fcl::CollisionResultd res;
          if (fcl::collide(&link, &other, req, res)) {
            return m.links()[l].name + " - box " + std::to_string(boxes[i].second) +
                   " at t=" + std::to_string(t);
          }
        }
        // Walls only inside the trailer (x >= 0): the rear is open.
        for (std::size_t i = 0; i < planes.size(); ++i) {
          if (i >= 2 && p.translation().x() < 0.0) continue;
          fcl::CollisionObjectd plane(planes[i]);
          fcl::CollisionRequestd req;
          fcl::CollisionResultd res;
          if (fcl::collide(&link, &plane, req, res)) {
            return m.links()[l].name + " - trailer plane " + std::to_string(i) +
                   " at t=" + std::to_string(t);
          }
        }
      }
    }
    if (t >= traj.duration()) break;
  }
  return {};
}

void expect_within_limits(const Trajectory& traj) {
  const Limits& lim = robot().all_limits();
  for (const auto& [t, s] : traj.sampled(0.005)) {
    for (int j = 0; j < kNumJoints; ++j) {
      EXPECT_GE(s.position[j], lim[j].lower - 1e-9) << kJointNames[j] << " t=" << t;
      EXPECT_LE(s.position[j], lim[j].upper + 1e-9) << kJointNames[j] << " t=" << t;
      EXPECT_LE(std::abs(s.velocity[j]), lim[j].velocity + 1e-9) << kJointNames[j] << " t=" << t;
      EXPECT_LE(std::abs(s.acceleration[j]), lim[j].acceleration + 1e-9)
          << kJointNames[j] << " t=" << t;
    }
  }
}

class Planners : public ::testing::TestWithParam<int> {
 protected:
  PlanResult plan(const PlanQuery& q, CollisionChecker& cc) {
    static plr::ompl_planner::Planner rrt;
    return GetParam() == 0 ? arastar().plan(q, cc) : rrt.plan(q, cc);
  }
};

}  // namespace

TEST_P(Planners, ArmToPreGraspIsCollisionFreeAndWithinLimits) {
  const World w = wall(4.0);
  CollisionChecker cc(robot(), w);
  const JointVector start = home(4.0 - 1.35);
  // Plate 15 cm in front of a box's face (row 2, column 1), square to it.
  const Eigen::Vector3d target(3.85, at(w, 2, 1).pose.translation().y(),
                               at(w, 2, 1).pose.translation().z());
  const PlanResult r = plan(pose_query(PlanMode::kArm, start, target, 0.0), cc);
  ASSERT_EQ(r.status, PlanStatus::kSolved) << r.message;
  EXPECT_EQ(r.path.front(), start);
  const PlateTarget reached = robot().plate_target(r.path.back());
  EXPECT_LT((reached.position - target).norm(), 0.005 + 1e-6);
  EXPECT_EQ(dense_collision(r.trajectory, w, {}), "");
  expect_within_limits(r.trajectory);
  // Only arm joints moved.
  for (int j : {kBaseX, kNose1, kNose2, kNose3}) EXPECT_EQ(r.path.back()[j], start[j]);
}

TEST_P(Planners, ArmAndBaseReachFromFarBack) {
  const World w = wall(5.0);
  CollisionChecker cc(robot(), w);
  const JointVector start = home(2.0);
  const Eigen::Vector3d target(4.85, 0.4, 1.8);
  const PlanResult r = plan(pose_query(PlanMode::kArmBase, start, target, 0.0), cc);
  ASSERT_EQ(r.status, PlanStatus::kSolved) << r.message;
  EXPECT_GT(r.path.back()[kBaseX], start[kBaseX] + 0.3);  // had to drive
  EXPECT_EQ(dense_collision(r.trajectory, w, {}), "");
  expect_within_limits(r.trajectory);
}

TEST_P(Planners, NoseDownAndBaseLine) {
  const World w = wall(6.0);
  CollisionChecker cc(robot(), w);
  JointVector down = home(4.0);
  down[kNose1] = 0.0;
  down[kNose2] = 0.05;
  down[kNose3] = 0.3;
  const PlanResult nose = plan(joint_query(PlanMode::kNose, home(4.0), down), cc);
  ASSERT_EQ(nose.status, PlanStatus::kSolved) << nose.message;
  EXPECT_LT((nose.path.back() - down).cwiseAbs().maxCoeff(), 1e-3);
  EXPECT_EQ(dense_collision(nose.trajectory, w, {}), "");
  expect_within_limits(nose.trajectory);

  JointVector back = down;
  back[kBaseX] = 2.5;
  const PlanResult base = plan(joint_query(PlanMode::kBaseLine, down, back), cc);
  ASSERT_EQ(base.status, PlanStatus::kSolved) << base.message;
  EXPECT_EQ(dense_collision(base.trajectory, w, {}), "");
  expect_within_limits(base.trajectory);
  // Straight along the trailer axis: one segment.
  EXPECT_EQ(base.path.size(), 2u);
}

TEST_P(Planners, CartesianApproachStaysOnTheLine) {
  const World w = wall(4.0);
  CollisionChecker cc(robot(), w);
  const Box& box = at(w, 2, 2);
  const Eigen::Vector3d face(4.0, box.pose.translation().y(), box.pose.translation().z());
  const auto pre = robot().arm_ik({face - Eigen::Vector3d(0.15, 0, 0), 0.0}, home(4.0 - 1.35));
  ASSERT_FALSE(pre.empty());
  PlanQuery q =
      pose_query(PlanMode::kArmCartesian, pre.front(), face - Eigen::Vector3d(0.005, 0, 0), 0.0);
  q.ignored_boxes = {box.id};
  const PlanResult r = plan(q, cc);
  ASSERT_EQ(r.status, PlanStatus::kSolved) << r.message;
  for (const auto& [t, s] : r.trajectory.sampled(0.01)) {
    const Eigen::Vector3d p = robot().plate_pose(s.position).translation();
    EXPECT_LT(std::hypot(p.y() - face.y(), p.z() - face.z()), 0.006) << "t=" << t;
  }
  EXPECT_EQ(dense_collision(r.trajectory, w, {box.id}), "");
}

TEST_P(Planners, GoalInCollisionIsReportedAsSuch) {
  const World w = wall(4.0);
  CollisionChecker cc(robot(), w);
  JointVector goal = home(4.0 - 1.35);
  goal[kBaseX] = 4.5;  // inside the wall
  const PlanResult r = plan(joint_query(PlanMode::kBaseLine, home(2.0), goal), cc);
  EXPECT_EQ(r.status, PlanStatus::kGoalInvalid);
  EXPECT_NE(r.message.find("box"), std::string::npos) << r.message;
}

TEST_P(Planners, InvalidRequestsGetClearErrors) {
  World w;
  CollisionChecker cc(robot(), w);
  PlanQuery q;
  q.mode = PlanMode::kNose;
  q.start = home(1.0);
  PoseGoal pg;
  q.goal = pg;
  PlanResult r = plan(q, cc);
  EXPECT_EQ(r.status, PlanStatus::kInvalidRequest);
  EXPECT_EQ(r.message, "M3 nose needs a joint goal");

  q = joint_query(PlanMode::kNose, home(1.0), home(1.0));
  std::get<JointGoal>(q.goal).q[kNose1] = 2.0;
  r = plan(q, cc);
  EXPECT_EQ(r.status, PlanStatus::kInvalidRequest);
  EXPECT_EQ(r.message.rfind("joint goal nose_1 = 2.000000 is beyond limits", 0), 0u) << r.message;

  q = joint_query(PlanMode::kArm, home(1.0), home(1.0));
  q.time_limit_s = 0.0;
  r = plan(q, cc);
  EXPECT_EQ(r.status, PlanStatus::kInvalidRequest);
  EXPECT_EQ(r.message, "time_limit_s must be positive and finite");

  q.time_limit_s = 1.0;
  q.start[kArm1] = std::nan("");
  EXPECT_EQ(plan(q, cc).message, "start configuration has a non-finite value");
}

INSTANTIATE_TEST_SUITE_P(ArastarAndRrtConnect, Planners, ::testing::Values(0, 1),
                         [](const auto& info) {
                           return info.param == 0 ? "Arastar" : "RrtConnect";
                         });

TEST(Arastar, EscapesLightContactThenReachesTheGoal) {
  const World w = wall(4.0);
  CollisionChecker cc(robot(), w);
  const Box& box = at(w, 2, 2);
  const Eigen::Vector3d face(4.0, box.pose.translation().y(), box.pose.translation().z());
  const auto pre = robot().arm_ik({face - Eigen::Vector3d(0.08, 0, 0), 0.0}, home(4.0 - 1.35));
  ASSERT_FALSE(pre.empty());
  JointVector pressed = pre.front();
  pressed[kBaseX] += 0.088;  // plate 8 mm into the box
  ASSERT_FALSE(cc.is_valid(pressed));

  PlanQuery esc;
  esc.mode = PlanMode::kEscape;
  esc.start = pressed;
  const PlanResult e = arastar().plan(esc, cc);
  ASSERT_EQ(e.status, PlanStatus::kSolved) << e.message;
  EXPECT_TRUE(cc.is_valid(e.path.back()));
  EXPECT_TRUE(e.stats.escaped);
  // The nearest free state: about 1 cm away, not a long retreat.
  EXPECT_LT(
      (robot().plate_pose(e.path.back()).translation() - robot().plate_pose(pressed).translation())
          .norm(),
      0.03);

  const PlanResult r =
      arastar().plan(joint_query(PlanMode::kArm, pressed, home(pressed[kBaseX])), cc);
  ASSERT_EQ(r.status, PlanStatus::kSolved) << r.message;
  EXPECT_TRUE(r.stats.escaped);
  EXPECT_EQ(r.path.front(), pressed);
  EXPECT_LT((r.path.back() - home(pressed[kBaseX])).cwiseAbs().maxCoeff(), 1e-3);
  // After the escape part, the trajectory is collision-free.
  Trajectory rest =
      Trajectory::from_waypoints({r.path.begin() + 1, r.path.end()}, robot().all_limits());
  EXPECT_EQ(dense_collision(rest, w, {}), "");

  PlanQuery no_escape = joint_query(PlanMode::kArm, pressed, home(pressed[kBaseX]));
  no_escape.escape_if_start_invalid = false;
  const PlanResult n = arastar().plan(no_escape, cc);
  EXPECT_EQ(n.status, PlanStatus::kStartInvalid);
  EXPECT_EQ(n.message, "start in collision: plate - box " + std::to_string(box.id));
}

TEST(Arastar, UnreachableGoalGivesNoPathWithinTheTimeLimit) {
  // A floor-to-ceiling wall across the trailer; valid goals behind it.
  World w;
  Box wall;
  wall.id = 1;
  wall.size = Eigen::Vector3d(0.4, 2.48, 2.68);
  wall.pose.translation() = Eigen::Vector3d(3.2, 0.0, 1.345);
  w.boxes.push_back(wall);
  CollisionChecker cc(robot(), w);
  ASSERT_TRUE(cc.is_valid(home(1.0)));
  ASSERT_TRUE(cc.is_valid(home(5.0)));

  // M5: the base line is exhausted on this side of the wall.
  PlanQuery base = joint_query(PlanMode::kBaseLine, home(1.0), home(5.0));
  base.time_limit_s = 2.0;
  const PlanResult nb = arastar().plan(base, cc);
  EXPECT_EQ(nb.status, PlanStatus::kNoPath) << nb.message;
  EXPECT_LT(nb.stats.planning_time_s, 2.0);

  // M2: the lattice is too large to exhaust; the time limit ends it.
  PlanQuery arm = pose_query(PlanMode::kArmBase, home(1.0), Eigen::Vector3d(5.2, 0.0, 1.2), 0.0);
  arm.time_limit_s = 0.5;
  const PlanResult na = arastar().plan(arm, cc);
  EXPECT_EQ(na.status, PlanStatus::kTimeout) << na.message;
  EXPECT_EQ(na.message, "no solution within the time limit");
  EXPECT_LT(na.stats.planning_time_s, 0.5 + 0.2);
  EXPECT_TRUE(na.path.empty());
}

TEST(Trajectory, TrapezoidRespectsLimitsAndReachesWaypoints) {
  const Limits& lim = robot().all_limits();
  const std::vector<JointVector> wps = {home(1.0), home(3.0), home(2.6)};
  const Trajectory t = Trajectory::from_waypoints(wps, lim);
  EXPECT_NEAR(t.sample(t.waypoint_time(1)).position[kBaseX], 3.0, 1e-9);
  EXPECT_LT((t.sample(t.duration()).position - wps.back()).norm(), 1e-12);
  // 2 m at 0.6 m/s, 0.8 m/s^2: 2/0.6 + 0.6/0.8 s.
  EXPECT_NEAR(t.waypoint_time(1), 2.0 / 0.6 + 0.6 / 0.8, 1e-9);
  // 0.4 m: triangular (0.6^2 / 0.8 > 0.4), 2 sqrt(0.4 / 0.8) s.
  EXPECT_NEAR(t.duration() - t.waypoint_time(1), 2.0 * std::sqrt(0.4 / 0.8), 1e-9);
  expect_within_limits(t);
  EXPECT_NEAR(segment_duration(wps[0], wps[1], lim), t.waypoint_time(1), 1e-12);
}

// Deterministic planning: with an expansion budget the same request gives the
// same trajectory, bit for bit, whether or not other threads load the
// machine. ARA* needs ~0.5 s for this budget, past the default improve_time_s
// (0.1 s): were ε still lowered on a timer, how far it got would differ
// between the two runs.
TEST_P(Planners, ExpansionBudgetMakesPlansIndependentOfLoad) {
  const World w = wall(5.0);
  PlanQuery q = pose_query(PlanMode::kArmBase, home(2.0), Eigen::Vector3d(4.85, 0.4, 1.8), 0.0);
  // Past the first solution (ARA*: ~100 expansions), short of ε = 1.
  q.max_expansions = 400;
  // The budget decides, not the clock: sanitizer builds run ~10x slower.
  q.time_limit_s = 120.0;
  auto once = [&] {
    CollisionChecker cc(robot(), w);
    return plan(q, cc);
  };
  const PlanResult quiet = once();
  ASSERT_EQ(quiet.status, PlanStatus::kSolved) << quiet.message;
  EXPECT_LE(quiet.stats.expansions, q.max_expansions);
  EXPECT_FALSE(quiet.stats.time_limit_hit);
  if (GetParam() == 0) {
    EXPECT_TRUE(quiet.stats.budget_exhausted);  // not improve_time_s
  }

  std::atomic<bool> stop{false};
  std::vector<std::thread> burners;
  for (int i = 0; i < 2; ++i) {
    burners.emplace_back([&stop] {
      volatile double x = 1.0;
      while (!stop.load(std::memory_order_relaxed)) x = std::sqrt(x + 1.0);
    });
  }
  const PlanResult loaded = once();
  stop = true;
  for (auto& t : burners) t.join();

  ASSERT_EQ(loaded.status, PlanStatus::kSolved) << loaded.message;
  EXPECT_EQ(loaded.stats.expansions, quiet.stats.expansions);
  EXPECT_EQ(loaded.stats.final_eps, quiet.stats.final_eps);
  EXPECT_EQ(loaded.stats.cost, quiet.stats.cost);
  ASSERT_EQ(loaded.path.size(), quiet.path.size());
  for (std::size_t i = 0; i < quiet.path.size(); ++i) EXPECT_EQ(loaded.path[i], quiet.path[i]);
  const auto a = quiet.trajectory.sampled(0.02), b = loaded.trajectory.sampled(0.02);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].first, b[i].first);
    EXPECT_EQ(a[i].second.position, b[i].second.position);
    EXPECT_EQ(a[i].second.velocity, b[i].second.velocity);
  }
}

TEST_P(Planners, ExhaustedBudgetWithoutSolutionSaysSo) {
  const World w = wall(5.0);
  CollisionChecker cc(robot(), w);
  PlanQuery q = pose_query(PlanMode::kArmBase, home(2.0), Eigen::Vector3d(4.85, 0.4, 1.8), 0.0);
  q.max_expansions = 3;
  const PlanResult r = plan(q, cc);
  EXPECT_EQ(r.status, PlanStatus::kTimeout);
  EXPECT_EQ(r.message, "no solution within the expansion budget of 3");
  EXPECT_TRUE(r.stats.budget_exhausted);
  EXPECT_FALSE(r.stats.time_limit_hit);
}

// ARA* with a budget that ends it while it improves: the last completed
// iteration's solution, the same every time.
TEST(Arastar, BudgetEndingTheImprovementReturnsTheLastSolution) {
  const World w = wall(5.0);
  PlanQuery q = pose_query(PlanMode::kArmBase, home(2.0), Eigen::Vector3d(4.85, 0.4, 1.8), 0.0);
  q.improve_time_s = 10.0;
  q.max_expansions = 400;
  CollisionChecker cc(robot(), w);
  const PlanResult cut = arastar().plan(q, cc);
  ASSERT_EQ(cut.status, PlanStatus::kSolved) << cut.message;
  EXPECT_TRUE(cut.stats.budget_exhausted);
  EXPECT_FALSE(cut.stats.time_limit_hit);
  EXPECT_EQ(cut.stats.expansions, q.max_expansions);
  EXPECT_GT(cut.stats.final_eps, q.eps_final);
  const PlanResult again = arastar().plan(q, cc);
  EXPECT_EQ(again.path, cut.path);
  EXPECT_EQ(again.stats.final_eps, cut.stats.final_eps);
}
