// What the executor reports (src/report.cpp): statistics, report.json, the
// unloading curve and the progress line.
#include <gtest/gtest.h>

#include <cmath>

#include "report.hpp"

namespace plr::executor {
namespace {

TEST(Report, AccumulatorIsWelford) {
  Accumulator a;
  for (double x : {2.0, 4.0, 4.0, 4.0, 5.0, 5.0, 7.0, 9.0}) a.add(x);
  EXPECT_EQ(a.n, 8u);
  EXPECT_DOUBLE_EQ(a.mean, 5.0);
  EXPECT_DOUBLE_EQ(a.sum, 40.0);
  EXPECT_NEAR(a.sd(), std::sqrt(32.0 / 7.0), 1e-12);  // sample standard deviation
  EXPECT_EQ(Accumulator{}.sd(), 0.0);
}

TEST(Report, JsonHasTheFiguresOfTheTables) {
  RunStats s;
  s.boxes_total = 10;
  s.boxes_unloaded = 4;
  s.robot_time_s = 20.0;
  s.wasted_s = 5.0;
  s.planner.modes[5].queries = 3;
  s.planner.modes[5].failures = 1;
  s.planner.modes[5].ms.add(2.0);
  s.pick.executions = 2;
  s.pick.boxes = 3;
  s.pick.plan_s.add(1.0);
  s.pick.exec_s.add(5.0);
  s.pick.exec_s.add(7.0);
  s.stop_reason = "trailer empty";
  s.boxes_left = {{12, "given up", "too heavy"},
                  {13, "blocked", "in front: 12"},
                  {14, "blocked", "in front: 12"}};
  s.curve = {{0.0, 0}, {20.0, 4}};
  s.steps = {{"library:A1-1", "Pick(mid, left)", "wall/mid/center", 2.0, 0.0, 0.0, true, 1, 12.0}};
  const auto j = to_json(s);
  EXPECT_EQ(j["boxes_unloaded"], 4);
  // Each step says which strategy it came from.
  ASSERT_EQ(j["steps"].size(), 1u);
  EXPECT_EQ(j["steps"][0]["source"], "library:A1-1");
  EXPECT_EQ(j["steps"][0]["action"], "Pick(mid, left)");
  EXPECT_DOUBLE_EQ(j["unloaded_fraction"].get<double>(), 0.4);
  EXPECT_DOUBLE_EQ(j["boxes_per_robot_s"].get<double>(), 0.2);
  EXPECT_DOUBLE_EQ(j["wasted_s"].get<double>(), 5.0);
  EXPECT_DOUBLE_EQ(j["wasted_share"].get<double>(), 0.25);
  EXPECT_EQ(j["planner_modes"]["M5"]["queries"], 3);
  EXPECT_NEAR(j["planner_modes"]["M5"]["failure_rate"].get<double>(), 1.0 / 3.0, 1e-12);
  EXPECT_EQ(j["planner_modes"]["M5"]["name"], "M5 base line");
  EXPECT_EQ(j["actions"]["pick"]["executions"], 2);
  EXPECT_DOUBLE_EQ(j["actions"]["pick"]["exec_s"].get<double>(), 6.0);
  // Boxes per second of the action's own time (planning + execution).
  EXPECT_DOUBLE_EQ(j["actions"]["pick"]["boxes_per_s"].get<double>(), 3.0 / (1.0 + 12.0));
  EXPECT_EQ(j["stop_reason"], "trailer empty");
  EXPECT_EQ(j["curve"].size(), 2u);
  EXPECT_TRUE(j["robot_s_to_90_percent"].is_null());  // 4 of 10 boxes
  s.curve = {{0.0, 0}, {20.0, 4}, {31.5, 9}, {40.0, 10}};
  EXPECT_DOUBLE_EQ(to_json(s)["robot_s_to_90_percent"].get<double>(), 31.5);
  ASSERT_EQ(j["boxes_left"].size(), 3u);
  EXPECT_EQ(j["boxes_left"][0]["reason"], "given up");
  EXPECT_EQ(j["boxes_left"][0]["detail"], "too heavy");
  EXPECT_EQ(j["boxes_left_by_reason"]["blocked"], 2);
  EXPECT_EQ(j["boxes_left_by_reason"]["given up"], 1);
}

TEST(Report, BoxesPerPick) {
  // Three picks: one moved nothing, one a box, one three boxes at once.
  RunStats s;
  s.pick.executions = 3;
  s.pick.boxes = 4;
  s.pick.boxes_histogram = {{0, 1}, {1, 1}, {3, 1}};
  const auto j = to_json(s);
  EXPECT_DOUBLE_EQ(j["boxes_per_pick"].get<double>(), 4.0 / 3.0);
  EXPECT_DOUBLE_EQ(j["boxes_per_successful_pick"].get<double>(), 2.0);
  EXPECT_DOUBLE_EQ(j["actions"]["pick"]["boxes_per_execution"].get<double>(), 4.0 / 3.0);
  EXPECT_EQ(j["actions"]["pick"]["boxes_histogram"]["3"], 1);
  EXPECT_EQ(j["actions"]["sweep"]["boxes_per_execution"], 0.0);  // none
}

TEST(Report, CurveIsAnSvgWithItsTitle) {
  const std::string svg = curve_svg({{0.0, 0}, {10.0, 3}, {25.0, 8}}, 10, "A1 <seed 1>");
  EXPECT_EQ(svg.rfind("<svg ", 0), 0u);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  EXPECT_NE(svg.find("<polyline"), std::string::npos);
  EXPECT_EQ(svg.find("<seed 1>"), std::string::npos) << "the title must be escaped";
}

TEST(Report, ProgressLine) {
  const std::string line = progress_line(12, 30, 60.0, "Pick(high, left): approach", 10);
  EXPECT_EQ(line.rfind("[####------] 12/30 boxes", 0), 0u) << line;
  EXPECT_NE(line.find("40%"), std::string::npos) << line;
  EXPECT_NE(line.find("0.20 boxes/s"), std::string::npos) << line;
  EXPECT_NE(line.find("Pick(high, left): approach"), std::string::npos) << line;
}

}  // namespace
}  // namespace plr::executor
