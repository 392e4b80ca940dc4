// The unloading curve: a step where each box left, a point at each action's end.
#include "plr/episode/curve.hpp"

#include <gtest/gtest.h>

namespace plr::episode {
namespace {

actions::Outcome outcome(std::uint32_t boxes, double robot_time_s, std::vector<double> at) {
  actions::Outcome o;
  o.boxes = boxes;
  o.robot_time_s = robot_time_s;
  o.unloaded_at_s = std::move(at);
  return o;
}

std::vector<std::pair<double, std::uint32_t>> points(const Curve& c) {
  std::vector<std::pair<double, std::uint32_t>> out;
  for (const auto& p : c.points()) out.emplace_back(p.robot_time_s, p.boxes);
  return out;
}

TEST(Curve, StepsWhereEachBoxLeftInTimeOrderAndEndsAtTheActionsEnd) {
  Curve c;
  c.add(0.0, 0, outcome(2, 10.0, {7.0, 4.0}));
  c.add(10.0, 2, outcome(0, 5.0, {}));
  const std::vector<std::pair<double, std::uint32_t>> want = {
      {4.0, 1}, {7.0, 2}, {10.0, 2}, {15.0, 2}};
  EXPECT_EQ(points(c), want);
}

// The world's count rules: a box seen leaving after the action's end counts
// at its end; one more time than boxes counted is no extra step.
TEST(Curve, ABoxSeenLeavingLateCountsAtTheEndAndExtraTimesAreNoSteps) {
  Curve c;
  c.add(2.0, 3, outcome(1, 4.0, {9.0, 1.0}));
  const std::vector<std::pair<double, std::uint32_t>> want = {{3.0, 4}, {6.0, 4}};
  EXPECT_EQ(points(c), want);
  Curve late;
  late.add(2.0, 3, outcome(1, 4.0, {9.0}));
  const std::vector<std::pair<double, std::uint32_t>> at_end = {{6.0, 4}, {6.0, 4}};
  EXPECT_EQ(points(late), at_end);
}

}  // namespace
}  // namespace plr::episode
