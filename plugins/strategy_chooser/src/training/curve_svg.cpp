#include "training/curve_svg.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <iterator>

namespace plr::chooser {

std::string curve_svg(const std::vector<IterationRecord>& iterations) {
  constexpr double kW = 640, kH = 360, kLeft = 60, kRight = 150, kTop = 30, kBottom = 50;
  const double n = std::max<double>(1.0, static_cast<double>(iterations.size()));
  const auto x = [&](double i) { return kLeft + (kW - kLeft - kRight) * (i / n); };
  const auto y = [&](double a) { return kH - kBottom - (kH - kTop - kBottom) * a; };
  std::string s = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{0}\" height=\"{1}\" "
      "font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"{0}\" height=\"{1}\" "
      "fill=\"white\"/>\n<text x=\"{2}\" y=\"18\">chooser training: accuracy after each "
      "iteration</text>\n",
      kW, kH, kLeft);
  for (int k = 0; k <= 4; ++k) {
    const double a = k / 4.0;
    s += fmt::format(
        "<line x1=\"{0}\" x2=\"{1}\" y1=\"{2:.1f}\" y2=\"{2:.1f}\" stroke=\"#ddd\"/>"
        "<text x=\"{3}\" y=\"{4:.1f}\" text-anchor=\"end\">{5:.2f}</text>\n",
        kLeft, kW - kRight, y(a), kLeft - 6, y(a) + 4, a);
  }
  for (std::size_t i = 0; i < iterations.size(); ++i)
    s += fmt::format("<text x=\"{:.1f}\" y=\"{}\" text-anchor=\"middle\">{}</text>\n",
                     x(static_cast<double>(i + 1)), kH - kBottom + 16, iterations[i].iteration);
  s += fmt::format("<text x=\"{:.1f}\" y=\"{}\" text-anchor=\"middle\">iteration</text>\n",
                   (kLeft + kW - kRight) / 2, kH - 12);
  const struct {
    double IterationRecord::*field;
    const char* colour;
    const char* label;
  } lines[] = {{&IterationRecord::validation_accuracy, "#1f77b4", "held-out validation"},
               {&IterationRecord::cv_accuracy, "#2ca02c", "cross-validation"},
               {&IterationRecord::majority_accuracy, "#999", "majority class"}};
  for (std::size_t l = 0; l < std::size(lines); ++l) {
    std::string points;
    for (std::size_t i = 0; i < iterations.size(); ++i) {
      const double px = x(static_cast<double>(i + 1)), py = y(iterations[i].*lines[l].field);
      points += fmt::format("{:.1f},{:.1f} ", px, py);
      s += fmt::format("<circle cx=\"{:.1f}\" cy=\"{:.1f}\" r=\"3\" fill=\"{}\"/>\n", px, py,
                       lines[l].colour);
    }
    s += fmt::format("<polyline points=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"2\"/>\n",
                     points, lines[l].colour);
    const double ly = kTop + 20 + 18 * static_cast<double>(l);
    s += fmt::format(
        "<line x1=\"{0}\" x2=\"{1}\" y1=\"{2}\" y2=\"{2}\" stroke=\"{3}\" stroke-width=\"2\"/>"
        "<text x=\"{4}\" y=\"{5}\">{6}</text>\n",
        kW - kRight + 10, kW - kRight + 30, ly, lines[l].colour, kW - kRight + 35, ly + 4,
        lines[l].label);
  }
  return s + "</svg>\n";
}

}  // namespace plr::chooser
