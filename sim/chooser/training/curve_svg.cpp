#include "curve_svg.hpp"

#include <plr/svg_chart.hpp>

#include <utility>

namespace plr::chooser {

std::string curve_svg(const std::vector<IterationRecord>& iterations) {
  Chart chart;
  // The learning curve: what more data bought (each point an iteration).
  chart.title = "chooser training: accuracy against labelled states";
  chart.height = 360;
  chart.x.label = "labelled training states";
  chart.x.min = 0;
  chart.x.integer = true;
  chart.y.label = "accuracy";
  chart.y.min = 0;
  chart.y.max = 1;
  const struct {
    double IterationRecord::*field;
    const char* color;
    const char* label;
  } lines[] = {{&IterationRecord::validation_accuracy, "#1f77b4", "held-out validation"},
               {&IterationRecord::cv_accuracy, "#2ca02c", "cross-validation"},
               {&IterationRecord::majority_accuracy, "#999", "majority class"}};
  for (const auto& line : lines) {
    ChartSeries s;
    s.label = line.label;
    s.color = line.color;
    s.marker_radius = 3;
    for (const IterationRecord& r : iterations)
      s.points.push_back({static_cast<double>(r.samples), r.*line.field});
    chart.series.push_back(std::move(s));
  }
  return render_svg(chart);
}

}  // namespace plr::chooser
