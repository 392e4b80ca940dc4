// A line chart as an SVG document: a title, two axes with round ticks, grid
// lines and labels, and series drawn as lines or steps, with markers and a
// shaded band if asked, named in a legend. What PLR's reports plot against
// time (boxes unloaded, bounds, accuracies) is drawn by this one helper.
// Link plr::sdk_support.
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace plr {

struct ChartAxis {
  std::string label;
  // The range shown; an end not given is the data's, widened to a round tick.
  std::optional<double> min, max;
  bool integer = false;  // ticks only at whole numbers (counts, iterations)
};

struct ChartPoint {
  double x = 0, y = 0;
};

struct ChartSeries {
  std::string label;  // in the legend; empty: not in the legend
  std::string color = "#1f77b4";
  std::vector<ChartPoint> points;
  // Steps: each y holds until the next point's x (a count that jumps).
  bool steps = false;
  bool dashed = false;
  double width = 2;
  double marker_radius = 0;  // a dot at each point when > 0
  // A shaded band from band_low[i] to band_high[i] at points[i].x (both
  // empty, or as many as points), e.g. mean ± standard error.
  std::vector<double> band_low, band_high;
};

struct Chart {
  std::string title;
  double width = 640, height = 400;
  ChartAxis x, y;
  std::vector<ChartSeries> series;
};

// The chart as a standalone SVG document (text escaped, fixed-point numbers).
std::string render_svg(const Chart& chart);

// The ticks of [min, max] at a round step (1, 2 or 5 times a power of ten)
// that gives about `target` intervals; at least 1 apart when `integer`.
std::vector<double> chart_ticks(double min, double max, int target = 5, bool integer = false);

}  // namespace plr
