#include "report.hpp"

#include <plr/svg_chart.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>

namespace plr::executor {

nlohmann::json to_json(const RunStats& s) {
  nlohmann::json left = nlohmann::json::array();
  std::map<std::string, std::uint32_t> left_by_reason;
  for (const auto& b : s.boxes_left) {
    left.push_back({{"id", b.id}, {"reason", b.reason}, {"detail", b.detail}});
    ++left_by_reason[b.reason];
  }
  nlohmann::json curve = nlohmann::json::array();
  for (const auto& p : s.curve) curve.push_back({p.robot_time_s, p.boxes});
  const auto to_90 = actions::robot_time_to_share(curve, s.boxes_total, 0.9);
  nlohmann::json steps = nlohmann::json::array();
  for (const auto& r : s.steps)
    steps.push_back({{"source", r.source},
                     {"action", r.action},
                     {"observation", r.observation},
                     {"wall_height", r.wall_height},
                     {"pile_height", r.pile_height},
                     {"pile_depth", r.pile_depth},
                     {"applicable", r.applicable},
                     {"boxes", r.boxes},
                     {"robot_time_s", r.robot_time_s}});
  nlohmann::json trailers = nlohmann::json::array();
  for (const auto& t : s.trailers)
    trailers.push_back({{"name", t.name},
                        {"boxes_total", t.boxes_total},
                        {"boxes_unloaded", t.boxes_unloaded},
                        {"sim_boxes_unloaded", t.sim_boxes_unloaded},
                        {"sim_boxes_left", t.sim_boxes_left},
                        {"recoveries", t.recoveries},
                        {"plan_calls_unanswered", t.plan_calls_unanswered},
                        {"wall_time_s", t.wall_time_s},
                        {"stop_reason", t.stop_reason},
                        {"start_checkpoint_bytes", t.start_checkpoint_bytes}});
  nlohmann::json out = {
      {"boxes_total", s.boxes_total},
      {"boxes_unloaded", s.boxes_unloaded},
      {"unloaded_fraction",
       s.boxes_total ? static_cast<double>(s.boxes_unloaded) / s.boxes_total : 0.0},
      {"sim_time_s", s.sim_time_s},
      {"robot_time_s", s.robot_time_s},
      {"plan_wall_s", s.plan_wall_s},
      {"wasted_s", s.wasted_s},
      {"wasted_share", s.robot_time_s > 0 ? s.wasted_s / s.robot_time_s : 0.0},
      {"wall_time_s", s.wall_time_s},
      {"boxes_per_robot_s", s.robot_time_s > 0 ? s.boxes_unloaded / s.robot_time_s : 0.0},
      // Boxes a pick moved out: per applicable pick, and per pick that moved any.
      {"boxes_per_pick", actions::boxes_per_execution(s.pick)},
      {"boxes_per_successful_pick", actions::boxes_per_success(s.pick)},
      {"robot_trailer_collisions", s.robot_trailer_collisions},
      {"failed_grasps", s.failed_grasps},
      {"not_applicable", s.not_applicable},
      {"recoveries", s.recoveries},
      {"strategies_asked", s.strategies_asked},
      {"strategy_steps", s.strategy_steps},
      {"stop_reason", s.stop_reason},
      {"boxes_left", left},
      {"boxes_left_by_reason", left_by_reason},
      {"planner_modes", actions::modes_json(s.planner)},
      {"planners", s.planner.planners},
      {"plan_calls_unanswered", s.planner.unanswered},
      {"actions",
       {{"pick", actions::action_json(s.pick)}, {"sweep", actions::action_json(s.sweep)}}},
      {"curve", curve},
      {"robot_s_to_90_percent", to_90 ? nlohmann::json(*to_90) : nlohmann::json()},
      {"steps", steps}};
  if (!s.trailers.empty()) out["trailers"] = trailers;
  return out;
}

std::string curve_svg(const std::vector<CurvePoint>& curve, std::uint32_t total,
                      const std::string& title) {
  Chart chart;
  chart.title = title;
  chart.x.label = "robot time [s]";
  chart.x.min = 0;
  chart.y.label = "boxes unloaded";
  chart.y.min = 0;
  // Headroom over the dashed line of all boxes, so that it stands clear of the frame.
  chart.y.max = 1.05 * std::max<double>(1.0, total);
  chart.y.integer = true;
  // A step curve: the count rises as each box leaves the trailer.
  ChartSeries unloaded;
  unloaded.color = "#c0392b";
  unloaded.steps = true;
  unloaded.points.push_back({0, 0});
  for (const auto& p : curve)
    unloaded.points.push_back({p.robot_time_s, static_cast<double>(p.boxes)});
  ChartSeries all;
  all.color = "#bbb";
  all.dashed = true;
  all.width = 1;
  all.points = {{0, static_cast<double>(total)},
                {std::max(1.0, unloaded.points.back().x), static_cast<double>(total)}};
  chart.series = {all, unloaded};
  return render_svg(chart);
}

std::string progress_line(std::uint32_t done, std::uint32_t total, double robot_time_s,
                          const std::string& what, int width) {
  const double f = total ? std::min(1.0, static_cast<double>(done) / total) : 0.0;
  const int filled = static_cast<int>(std::lround(f * width));
  return fmt::format("[{}{}] {}/{} boxes {:3.0f}%  {:.2f} boxes/s  {}", std::string(filled, '#'),
                     std::string(width - filled, '-'), done, total, 100 * f,
                     robot_time_s > 0 ? done / robot_time_s : 0.0, what);
}

}  // namespace plr::executor
