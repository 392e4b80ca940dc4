#include "report.hpp"

#include <plr/sim/render.hpp>

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
    steps.push_back({{"action", r.action},
                     {"observation", r.observation},
                     {"wall_height", r.wall_height},
                     {"pile_height", r.pile_height},
                     {"pile_depth", r.pile_depth},
                     {"applicable", r.applicable},
                     {"boxes", r.boxes},
                     {"robot_time_s", r.robot_time_s}});
  return {{"boxes_total", s.boxes_total},
          {"boxes_unloaded", s.boxes_unloaded},
          {"unloaded_fraction",
           s.boxes_total ? static_cast<double>(s.boxes_unloaded) / s.boxes_total : 0.0},
          {"sim_time_s", s.sim_time_s},
          {"robot_time_s", s.robot_time_s},
          {"plan_wall_s", s.plan_wall_s},
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
}

std::string curve_svg(const std::vector<CurvePoint>& curve, std::uint32_t total,
                      const std::string& title) {
  constexpr double kW = 640, kH = 400, kL = 60, kR = 20, kT = 40, kB = 50;
  const double t_max = std::max(1.0, curve.empty() ? 1.0 : curve.back().robot_time_s);
  const double n_max = std::max<double>(1.0, total);
  auto px = [&](double t) { return kL + (kW - kL - kR) * t / t_max; };
  auto py = [&](double n) { return kH - kB - (kH - kT - kB) * n / n_max; };
  std::string svg = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{}\" "
      "font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%\" height=\"100%\" "
      "fill=\"white\"/>\n<text x=\"{}\" y=\"24\" font-size=\"14\">{}</text>\n",
      kW, kH, kL, sim::xml_escape(title));
  // Axes with five ticks each.
  svg += fmt::format(
      "<line x1=\"{0}\" y1=\"{1}\" x2=\"{2}\" y2=\"{1}\" stroke=\"black\"/>\n"
      "<line x1=\"{0}\" y1=\"{1}\" x2=\"{0}\" y2=\"{3}\" stroke=\"black\"/>\n",
      kL, kH - kB, kW - kR, kT);
  for (int i = 0; i <= 5; ++i) {
    const double t = t_max * i / 5, n = n_max * i / 5;
    svg += fmt::format(
        "<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\">{:.0f}</text>\n"
        "<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"end\">{:.0f}</text>\n",
        px(t), kH - kB + 16, t, kL - 6, py(n) + 4, n);
  }
  svg += fmt::format(
      "<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\">robot time [s]</text>\n"
      "<text x=\"16\" y=\"{:.1f}\" transform=\"rotate(-90 16 {:.1f})\" "
      "text-anchor=\"middle\">boxes unloaded</text>\n",
      (kL + kW - kR) / 2, kH - 12, (kT + kH - kB) / 2, (kT + kH - kB) / 2);
  svg += fmt::format(
      "<line x1=\"{}\" y1=\"{:.1f}\" x2=\"{}\" y2=\"{:.1f}\" stroke=\"#bbb\" "
      "stroke-dasharray=\"4 4\"/>\n",
      kL, py(total), kW - kR, py(total));
  // A step curve: the count rises as each box leaves the trailer.
  std::string points = fmt::format("{:.1f},{:.1f}", px(0), py(0));
  std::uint32_t last = 0;
  for (const auto& p : curve) {
    points += fmt::format(" {:.1f},{:.1f} {:.1f},{:.1f}", px(p.robot_time_s), py(last),
                          px(p.robot_time_s), py(p.boxes));
    last = p.boxes;
  }
  svg += "<polyline fill=\"none\" stroke=\"#c0392b\" stroke-width=\"2\" points=\"" + points +
         "\"/>\n</svg>\n";
  return svg;
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
