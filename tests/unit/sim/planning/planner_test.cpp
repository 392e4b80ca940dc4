// The planner contract's public half (sim/planning/planner.cpp), with a
// planner whose hook only tries the straight move: what plan() does before
// and after any planner's search.
#include <gtest/gtest.h>

#include "plr/planning/planner.hpp"

namespace plr::planning {
namespace {

using namespace plr::sim;

const RobotModel& robot() {
  static const RobotModel m = load_robot().value();
  return m;
}

class StraightPlanner final : public Planner {
 public:
  std::string name() const override { return "straight"; }
  std::vector<PlanMode> modes() const override { return {PlanMode::kArm, PlanMode::kBaseLine}; }

  int calls = 0;
  PlanQuery last;

 protected:
  PlanResult do_plan(const PlanQuery& q, CollisionChecker& checker) override {
    ++calls;
    last = q;
    PlanResult r;
    JointVector goal = q.start;
    for (int j : planned_joints(q.mode)) goal[j] = std::get<JointGoal>(q.goal).q[j];
    if (!checker.is_motion_valid(q.start, goal)) {
      r.status = PlanStatus::kNoPath;
      r.message = "not straight";
      return r;
    }
    r.status = PlanStatus::kSolved;
    r.path = {q.start, goal};
    r.stats.expansions = 1;
    return r;
  }
};

PlanQuery joint_query(PlanMode mode, const JointVector& start, const JointVector& goal) {
  PlanQuery q;
  q.mode = mode;
  q.start = start;
  q.goal = JointGoal{goal, 1e-3};
  return q;
}

// A 0.4 m box whose near face is at x.
World box_at(double x, double y = 0.0, double z = 1.2) {
  World w;
  Box b;
  b.id = 3;
  b.pose.translation() = Eigen::Vector3d(x + 0.2, y, z);
  w.boxes.push_back(b);
  return w;
}

TEST(Planner, SolvedPathsAreTimedAndCounted) {
  StraightPlanner p;
  const World empty;
  CollisionChecker checker(robot(), empty);
  const PlanResult r = p.plan(joint_query(PlanMode::kBaseLine, plr::sim::home_configuration(1.0),
                                          plr::sim::home_configuration(2.5)),
                              checker);
  ASSERT_EQ(r.status, PlanStatus::kSolved) << r.message;
  EXPECT_EQ(r.path, (std::vector<JointVector>{plr::sim::home_configuration(1.0),
                                              plr::sim::home_configuration(2.5)}));
  // 1.5 m at 0.6 m/s and 0.8 m/s^2.
  EXPECT_NEAR(r.trajectory.duration(), 1.5 / 0.6 + 0.6 / 0.8, 1e-9);
  EXPECT_EQ(r.stats.expansions, 1u);
  EXPECT_GT(r.stats.collision_checks, 0u);
  EXPECT_FALSE(r.stats.escaped);
}

TEST(Planner, BadQueriesAndOtherModesNeverReachTheHook) {
  StraightPlanner p;
  const World empty;
  CollisionChecker checker(robot(), empty);
  PlanQuery bad = joint_query(PlanMode::kBaseLine, plr::sim::home_configuration(1.0),
                              plr::sim::home_configuration(2.5));
  bad.time_limit_s = -1.0;
  PlanResult r = p.plan(bad, checker);
  EXPECT_EQ(r.status, PlanStatus::kInvalidRequest);
  EXPECT_EQ(r.message, "time_limit_s must be positive and finite");
  r = p.plan(joint_query(PlanMode::kNose, plr::sim::home_configuration(1.0),
                         plr::sim::home_configuration(1.0)),
             checker);
  EXPECT_EQ(r.status, PlanStatus::kInvalidRequest);
  EXPECT_EQ(r.message, "M3 nose is not a mode of planner straight");
  EXPECT_EQ(p.calls, 0);
}

TEST(Planner, GoalsInCollisionAreJudgedBeforeTheSearch) {
  StraightPlanner p;
  const World w = box_at(3.0, 0.0, 0.2);
  CollisionChecker checker(robot(), w);
  const PlanResult r = p.plan(joint_query(PlanMode::kBaseLine, plr::sim::home_configuration(1.0),
                                          plr::sim::home_configuration(3.2)),
                              checker);
  EXPECT_EQ(r.status, PlanStatus::kGoalInvalid);
  EXPECT_NE(r.message.find("box 3"), std::string::npos) << r.message;
  EXPECT_EQ(p.calls, 0);
}

TEST(Planner, StartInCollisionIsEscapedThenPlannedFrom) {
  StraightPlanner p;
  // The plate 8 mm into a box.
  const JointVector start = plr::sim::home_configuration(2.0);
  const Eigen::Vector3d plate = robot().plate_pose(start).translation();
  const World w = box_at(plate.x() - 0.008, plate.y(), plate.z());
  CollisionChecker checker(robot(), w);
  ASSERT_FALSE(checker.is_valid(start));
  const JointVector goal = plr::sim::home_configuration(1.5);
  const PlanResult r = p.plan(joint_query(PlanMode::kBaseLine, start, goal), checker);
  ASSERT_EQ(r.status, PlanStatus::kSolved) << r.message;
  EXPECT_TRUE(r.stats.escaped);
  EXPECT_EQ(r.path.front(), start);
  EXPECT_TRUE(checker.is_valid(p.last.start)) << "the hook starts where the escape ended";
  EXPECT_LT((p.last.start - start).cwiseAbs().maxCoeff(), 0.05) << "a short escape";
  EXPECT_EQ(r.path.back()[kBaseX], goal[kBaseX]);
  EXPECT_GT(r.stats.expansions, 1u) << "the escape's expansions count";

  PlanQuery stay = joint_query(PlanMode::kBaseLine, start, goal);
  stay.escape_if_start_invalid = false;
  const PlanResult n = p.plan(stay, checker);
  EXPECT_EQ(n.status, PlanStatus::kStartInvalid);
  EXPECT_EQ(n.message, "start in collision: plate - box 3");
}

TEST(Planner, AnEscapeThatSpendsTheBudgetLeavesNothingForTheHook) {
  StraightPlanner p;
  const JointVector start = plr::sim::home_configuration(2.0);
  const Eigen::Vector3d plate = robot().plate_pose(start).translation();
  const World w = box_at(plate.x() - 0.008, plate.y(), plate.z());
  CollisionChecker checker(robot(), w);
  PlanQuery q = joint_query(PlanMode::kBaseLine, start, plr::sim::home_configuration(1.5));
  q.max_expansions = 1;
  const PlanResult r = p.plan(q, checker);
  EXPECT_EQ(r.status, PlanStatus::kStartInvalid);
  EXPECT_NE(r.message.find("expansion budget of 1 exhausted"), std::string::npos) << r.message;
  EXPECT_EQ(p.calls, 0);
}

TEST(Planner, HeldBoxesMoveWithThePlateForOneQueryOnly) {
  StraightPlanner p;
  const World empty;
  CollisionChecker checker(robot(), empty);
  const JointVector start = plr::sim::home_configuration(2.0);
  // A tall box held in front of the plate reaches the ceiling when raised.
  Box held;
  held.id = 9;
  held.size = {0.4, 0.4, 0.4};
  held.pose = robot().plate_pose(start) * Eigen::Translation3d(0.2, 0.0, 0.0);
  PlanQuery q = joint_query(PlanMode::kBaseLine, start, plr::sim::home_configuration(2.5));
  q.held_boxes = {held};
  EXPECT_EQ(p.plan(q, checker).status, PlanStatus::kSolved);
  // Afterwards the checker holds nothing: the box is not where the plate was.
  EXPECT_TRUE(checker.is_valid(start));
  EXPECT_EQ(checker.describe_collision(start), "");
}

}  // namespace
}  // namespace plr::planning
