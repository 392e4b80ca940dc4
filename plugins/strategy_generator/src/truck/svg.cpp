#include "truck/svg.hpp"

#include <fmt/format.h>
#include <plr/svg_chart.hpp>
#include <plr/xml_escape.hpp>

#include <algorithm>
#include <tuple>
#include <utility>
#include <vector>

namespace plr::generator {

namespace {

constexpr double kNodeW = 120, kNodeH = 28, kGapX = 16, kRowH = 90, kMargin = 20;

// Leaves take one column each; a parent sits over the middle of its children.
double place(const sim::Strategy& s, std::uint32_t n, int depth, double& next_x,
             std::vector<double>& x, std::vector<int>& row) {
  row[n] = depth;
  const auto& kids = s.nodes[n].children;
  if (kids.empty()) {
    x[n] = next_x;
    next_x += kNodeW + kGapX;
    return x[n];
  }
  double first = 0, last = 0;
  for (std::size_t i = 0; i < kids.size(); ++i) {
    const double c = place(s, kids[i].second, depth + 1, next_x, x, row);
    if (i == 0) first = c;
    last = c;
  }
  x[n] = (first + last) / 2;
  return x[n];
}

}  // namespace

std::string strategy_svg(const sim::Strategy& s) {
  if (s.nodes.empty()) return "<svg xmlns=\"http://www.w3.org/2000/svg\"/>\n";
  std::vector<double> x(s.nodes.size(), 0);
  std::vector<int> row(s.nodes.size(), 0);
  double next_x = kMargin;
  place(s, s.root, 0, next_x, x, row);
  const int rows = *std::max_element(row.begin(), row.end()) + 1;
  const double w = std::max(next_x - kGapX + kMargin, 300.0);
  const double h = kMargin * 2 + 24 + rows * kRowH;
  std::string out = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{:.0f}\" height=\"{:.0f}\" "
      "font-family=\"sans-serif\" font-size=\"11\">\n"
      "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
      "<text x=\"{}\" y=\"{}\" font-size=\"14\">strategy {} ({} nodes, depth {})</text>\n",
      w, h, kMargin, kMargin + 4, xml_escape(s.name), s.nodes.size(), s.depth());
  auto top = [&](std::uint32_t n) { return kMargin + 30 + row[n] * kRowH; };
  for (std::uint32_t n = 0; n < s.nodes.size(); ++n) {
    for (const auto& [o, c] : s.nodes[n].children) {
      const double x0 = x[n] + kNodeW / 2, y0 = top(n) + kNodeH;
      const double x1 = x[c] + kNodeW / 2, y1 = top(c);
      out += fmt::format(
          "<line x1=\"{:.1f}\" y1=\"{:.1f}\" x2=\"{:.1f}\" y2=\"{:.1f}\" stroke=\"#555\"/>\n", x0,
          y0, x1, y1);
      out += fmt::format(
          "<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\" fill=\"#246\" "
          "font-size=\"10\">{}</text>\n",
          // Nearer the child than the parent: siblings' labels spread apart.
          0.3 * x0 + 0.7 * x1, 0.3 * y0 + 0.7 * y1 - 4, xml_escape(sim::to_string(o)));
    }
  }
  for (std::uint32_t n = 0; n < s.nodes.size(); ++n) {
    const bool sweep = sim::kind(s.nodes[n].action) == sim::ActionKind::kSweep;
    out += fmt::format(
        "<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{}\" height=\"{}\" rx=\"6\" fill=\"{}\" "
        "stroke=\"#333\"/>\n<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\">{}</text>\n",
        x[n], top(n), kNodeW, kNodeH, sweep ? "#fde2c8" : "#d6e8fa", x[n] + kNodeW / 2,
        top(n) + kNodeH / 2 + 4, xml_escape(sim::to_string(s.nodes[n].action)));
  }
  out += "</svg>\n";
  return out;
}

std::string anytime_svg(const sim::LibraryEntry& e) {
  Chart chart;
  chart.title = e.name + ": root value bounds (negated robot s) against wall time";
  chart.height = 360;
  chart.x.label = "wall time [s]";
  chart.x.min = 0;
  chart.y.label = "root value";
  // Steps: a bound holds until the trial that moves it; a dot per trial.
  for (const auto& [name, color, upper] :
       {std::tuple{"upper", "#c33", true}, std::tuple{"lower", "#36c", false}}) {
    ChartSeries s;
    s.label = name;
    s.color = color;
    s.steps = true;
    s.width = 1.5;
    s.marker_radius = 2.5;
    for (const sim::BoundPoint& p : e.curve)
      s.points.push_back({p.wall_s, upper ? p.upper : p.lower});
    chart.series.push_back(std::move(s));
  }
  return render_svg(chart);
}

}  // namespace plr::generator
