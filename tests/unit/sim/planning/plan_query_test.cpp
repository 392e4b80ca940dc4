// Query checks (sim/planning/plan_query.cpp): each rule and its one-line reason.
#include <gtest/gtest.h>

#include <cmath>

#include "plr/planning/plan_query.hpp"

namespace plr::planning {
namespace {

using namespace plr::sim;

const RobotModel& robot() {
  static const RobotModel m = load_robot().value();
  return m;
}

std::string why(const PlanQuery& q) {
  const auto ok = check_query(q, robot());
  return ok ? "" : ok.error().message;
}

PlanQuery joint(PlanMode mode) {
  PlanQuery q;
  q.mode = mode;
  q.start = plr::sim::home_configuration(1.0);
  q.goal = JointGoal{plr::sim::home_configuration(1.0), 1e-3};
  return q;
}

TEST(PlanQuery, WellFormedQueriesPass) {
  for (PlanMode m : {PlanMode::kArm, PlanMode::kArmBase, PlanMode::kNose, PlanMode::kBaseLine})
    EXPECT_EQ(why(joint(m)), "") << to_string(m);
  PlanQuery pose = joint(PlanMode::kArmCartesian);
  pose.goal = PoseGoal{};
  EXPECT_EQ(why(pose), "");
  PlanQuery escape = joint(PlanMode::kEscape);
  escape.goal = std::monostate{};
  EXPECT_EQ(why(escape), "");
}

TEST(PlanQuery, GoalKindPerMode) {
  PlanQuery q = joint(PlanMode::kNose);
  q.goal = PoseGoal{};
  EXPECT_EQ(why(q), "M3 nose needs a joint goal");
  q = joint(PlanMode::kArmCartesian);
  EXPECT_EQ(why(q), "M4 arm line needs a pose goal");
  q = joint(PlanMode::kArm);
  q.goal = std::monostate{};
  EXPECT_EQ(why(q), "M1 arm needs a joint or pose goal");
  q = joint(PlanMode::kEscape);
  EXPECT_EQ(why(q), "M6 escape takes no goal");
  q.mode = static_cast<PlanMode>(9);
  EXPECT_EQ(why(q), "unknown plan mode 9");
}

TEST(PlanQuery, NumbersAndLimits) {
  PlanQuery q = joint(PlanMode::kNose);
  std::get<JointGoal>(q.goal).q[kNose1] = 2.0;
  EXPECT_EQ(why(q).rfind("joint goal nose_1 = 2.000000 is beyond limits [", 0), 0u) << why(q);
  // Joints the mode does not plan are not judged.
  q = joint(PlanMode::kNose);
  std::get<JointGoal>(q.goal).q[kArm2] = 20.0;
  EXPECT_EQ(why(q), "");
  q = joint(PlanMode::kArm);
  q.start[kArm1] = std::nan("");
  EXPECT_EQ(why(q), "start configuration has a non-finite value");
  q = joint(PlanMode::kArm);
  q.time_limit_s = std::numeric_limits<double>::infinity();
  EXPECT_EQ(why(q), "time_limit_s must be positive and finite");
  q = joint(PlanMode::kArm);
  q.eps_final = 3.0;
  q.eps_initial = 2.0;
  EXPECT_EQ(why(q), "epsilon schedule needs eps_initial >= eps_final >= 1 and eps_decrement > 0");
  q = joint(PlanMode::kArm);
  std::get<JointGoal>(q.goal).tolerance = 0.0;
  EXPECT_EQ(why(q), "joint goal tolerance must be positive");
  q = joint(PlanMode::kArm);
  q.held_boxes.push_back(Box{.id = 4, .size = {0.4, 0.0, 0.4}});
  EXPECT_EQ(why(q), "held box 4 has a bad size");
}

TEST(PlanQuery, ModeNamesAndJoints) {
  EXPECT_STREQ(to_string(PlanMode::kArmBase), "M2 arm+base");
  EXPECT_STREQ(to_string(static_cast<PlanMode>(0)), "unknown");
  EXPECT_STREQ(to_string(PlanStatus::kGoalInvalid), "goal invalid");
  EXPECT_EQ(planned_joints(PlanMode::kArmBase),
            (std::vector<int>{kBaseX, kArm1, kArm2, kArm3, kArm4}));
  EXPECT_EQ(planned_joints(PlanMode::kBaseLine), std::vector<int>{kBaseX});
}

}  // namespace
}  // namespace plr::planning
