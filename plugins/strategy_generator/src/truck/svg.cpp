#include "truck/svg.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "plr/sim/render.hpp"

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
      w, h, kMargin, kMargin + 4, sim::xml_escape(s.name), s.nodes.size(), s.depth());
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
          0.3 * x0 + 0.7 * x1, 0.3 * y0 + 0.7 * y1 - 4, sim::xml_escape(sim::to_string(o)));
    }
  }
  for (std::uint32_t n = 0; n < s.nodes.size(); ++n) {
    const bool sweep = sim::kind(s.nodes[n].action) == sim::ActionKind::kSweep;
    out += fmt::format(
        "<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{}\" height=\"{}\" rx=\"6\" fill=\"{}\" "
        "stroke=\"#333\"/>\n<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\">{}</text>\n",
        x[n], top(n), kNodeW, kNodeH, sweep ? "#fde2c8" : "#d6e8fa", x[n] + kNodeW / 2,
        top(n) + kNodeH / 2 + 4, sim::xml_escape(sim::to_string(s.nodes[n].action)));
  }
  out += "</svg>\n";
  return out;
}

std::string anytime_svg(const sim::LibraryEntry& e) {
  constexpr double W = 640, H = 360, L = 70, R = 20, T = 40, B = 50;
  double t_max = 1e-9, v_min = 0, v_max = 0;
  bool first = true;
  for (const sim::BoundPoint& p : e.curve) {
    t_max = std::max(t_max, p.wall_s);
    if (first) v_min = p.lower, v_max = p.upper, first = false;
    v_min = std::min(v_min, p.lower);
    v_max = std::max(v_max, p.upper);
  }
  if (v_max - v_min < 1e-9) v_max = v_min + 1;
  // A margin, so that a bound at the range's end does not hide in an axis.
  const double pad = 0.05 * (v_max - v_min);
  v_min -= pad;
  v_max += pad;
  auto px = [&](double t) { return L + (W - L - R) * t / t_max; };
  auto py = [&](double v) { return T + (H - T - B) * (v_max - v) / (v_max - v_min); };
  std::string out = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{}\" "
      "font-family=\"sans-serif\" font-size=\"11\">\n"
      "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
      "<text x=\"{}\" y=\"22\" font-size=\"14\">{}: root value bounds (negated robot s) against "
      "wall time</text>\n"
      "<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"black\"/>\n"
      "<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"black\"/>\n",
      W, H, L, sim::xml_escape(e.name), L, H - B, W - R, H - B, L, T, L, H - B);
  for (int i = 0; i <= 4; ++i) {
    const double v = v_min + (v_max - v_min) * i / 4, t = t_max * i / 4;
    out += fmt::format(
        "<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"end\">{:.1f}</text>\n"
        "<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\">{:.0f}</text>\n",
        L - 6, py(v) + 4, v, px(t), H - B + 16, t);
  }
  out +=
      fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" text-anchor=\"middle\">wall time [s]</text>\n",
                  (L + W - R) / 2, H - 12);
  for (const auto& [name, color, upper] :
       {std::tuple{"upper", "#c33", true}, std::tuple{"lower", "#36c", false}}) {
    // Steps: a bound holds until the trial that moves it; a dot per trial.
    std::string pts, dots;
    double last = 0.0;
    for (std::size_t i = 0; i < e.curve.size(); ++i) {
      const sim::BoundPoint& p = e.curve[i];
      const double v = upper ? p.upper : p.lower;
      if (i > 0) pts += fmt::format("{:.1f},{:.1f} ", px(p.wall_s), py(last));
      pts += fmt::format("{:.1f},{:.1f} ", px(p.wall_s), py(v));
      dots += fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"2.5\" fill=\"{}\"/>\n",
                          px(p.wall_s), py(v), color);
      last = v;
    }
    out += fmt::format(
        "<polyline fill=\"none\" stroke=\"{}\" stroke-width=\"1.5\" points=\"{}\"/>\n", color, pts);
    out += dots;
    out += fmt::format("<text x=\"{:.1f}\" y=\"{:.1f}\" fill=\"{}\">{}</text>\n", W - R - 40,
                       upper ? T + 12 : T + 26, color, name);
  }
  out += "</svg>\n";
  return out;
}

}  // namespace plr::generator
