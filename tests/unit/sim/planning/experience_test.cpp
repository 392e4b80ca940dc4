// The lattice planner's experience (sim/planning/lattice/experience.hpp): a
// query like an earlier one follows the earlier path instead of searching
// again, and what it follows is checked against the world as it is now.
#include <gtest/gtest.h>

#include "plr/planning/lattice_planner.hpp"
#include "plr/sim/collision.hpp"
#include "plr/sim/shipped_files.hpp"

using namespace plr::sim;
using namespace plr::planning;

namespace {

const RobotModel& robot() {
  static const RobotModel m = load_robot().value();
  return m;
}

LatticeConfig config(bool experience) {
  auto c = LatticeConfig::from_file(shipped_file("robots/unloader_lattice.yaml").value()).value();
  c.experience.enabled = experience;
  return c;
}

JointVector home(double base) {
  JointVector q;
  q << base, 0.0, -1.0, 2.0, 0.0, 0.5, 0.0, 0.0;
  return q;
}

// A wall of 0.4 m boxes at x 5 m, and before it, in the middle of the
// trailer, a 1.2 m column the arm must get over or round to swing from one
// side of the wall to the other: a search of hundreds of expansions.
World column_before_wall() {
  World w;
  std::uint32_t id = 1;
  for (int r = 0; r < 5; ++r) {
    for (int c = 0; c < 5; ++c) {
      Box b;
      b.id = id++;
      b.size = Eigen::Vector3d(0.4, 0.4, 0.4);
      b.pose.translation() = Eigen::Vector3d(5.2, 0.405 * (c - 2), 0.2 + 0.405 * r);
      w.boxes.push_back(b);
    }
  }
  Box column;
  column.id = 99;
  column.size = Eigen::Vector3d(0.3, 0.4, 1.2);
  column.pose.translation() = Eigen::Vector3d(4.4, 0.0, 0.6);
  w.boxes.push_back(column);
  return w;
}

// The plate from one side of the wall to the other at height z (M2).
PlanQuery swing(const CollisionChecker& checker, double z) {
  PlanQuery q;
  q.mode = PlanMode::kArmBase;
  const auto start = robot().arm_ik({Eigen::Vector3d(4.7, -0.7, z), 0.0}, home(3.0));
  EXPECT_FALSE(start.empty());
  if (!start.empty()) q.start = start.front();
  EXPECT_TRUE(checker.is_valid(q.start));
  PoseGoal g;
  g.target = {Eigen::Vector3d(4.7, 0.7, z), 0.0};
  q.goal = g;
  // As the executor asks: the first solution at ε = 5, within a budget.
  q.eps_initial = q.eps_final = 5.0;
  q.max_expansions = 5000;
  q.time_limit_s = 600.0;
  return q;
}

bool path_valid(const std::vector<JointVector>& path, const CollisionChecker& checker) {
  for (std::size_t i = 1; i < path.size(); ++i) {
    if (!checker.is_motion_valid(path[i - 1], path[i])) return false;
  }
  return !path.empty();
}

}  // namespace

TEST(Experience, ARecurringQueryIsAnsweredFromExperience) {
  const World w = column_before_wall();
  CollisionChecker checker(robot(), w);
  LatticePlanner scratch(config(false));
  LatticePlanner off(config(true));
  off.set_experience(false);
  LatticePlanner with(config(true));

  const PlanResult first = with.plan(swing(checker, 1.0), checker);
  ASSERT_EQ(first.status, PlanStatus::kSolved) << first.message;
  EXPECT_EQ(with.experience_paths(PlanMode::kArmBase), 1u);
  EXPECT_EQ(first.stats.experience_edges, 0u);  // nothing stored yet

  // The same motion 5 cm higher: the next box of the column.
  const PlanQuery again = swing(checker, 1.05);
  const PlanResult fresh = scratch.plan(again, checker);
  const PlanResult reused = with.plan(again, checker);
  ASSERT_EQ(fresh.status, PlanStatus::kSolved) << fresh.message;
  ASSERT_EQ(reused.status, PlanStatus::kSolved) << reused.message;
  EXPECT_GT(reused.stats.experience_edges, 0u);
  EXPECT_LT(reused.stats.expansions * 4, fresh.stats.expansions)
      << reused.stats.expansions << " with experience, " << fresh.stats.expansions << " without";
  EXPECT_TRUE(path_valid(reused.path, checker));
  EXPECT_LE(reused.trajectory.duration(), 1.5 * fresh.trajectory.duration());

  // Off, the planner is the one without experience, bit for bit.
  const PlanResult plain = off.plan(again, checker);
  EXPECT_EQ(plain.path, fresh.path);
  EXPECT_EQ(plain.stats.expansions, fresh.stats.expansions);
  EXPECT_EQ(off.experience_paths(PlanMode::kArmBase), 0u);
}

TEST(Experience, AStoredPathABoxNowBlocksIsNotFollowed) {
  const World w = column_before_wall();
  CollisionChecker checker(robot(), w);
  LatticePlanner with(config(true));
  const PlanQuery q = swing(checker, 1.0);
  const PlanResult learnt = with.plan(q, checker);
  ASSERT_EQ(learnt.status, PlanStatus::kSolved) << learnt.message;
  ASSERT_GE(learnt.path.size(), 3u);

  // A box where the plate passed in the middle of the stored path.
  World changed = w;
  Box box;
  box.id = 100;
  box.size = Eigen::Vector3d(0.2, 0.2, 0.2);
  const std::size_t k = learnt.path.size() / 2;
  box.pose.translation() =
      robot().plate_pose(0.5 * (learnt.path[k - 1] + learnt.path[k])).translation();
  changed.boxes.push_back(box);
  CollisionChecker now(robot(), changed);
  ASSERT_TRUE(now.is_valid(q.start));
  ASSERT_FALSE(path_valid(learnt.path, now));  // the old path runs through it

  const PlanResult r = with.plan(q, now);
  EXPECT_NE(r.path, learnt.path);
  if (r.status == PlanStatus::kSolved) {
    EXPECT_TRUE(path_valid(r.path, now));
  }
}
