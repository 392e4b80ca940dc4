#include <plr/svg_chart.hpp>
#include <plr/xml_escape.hpp>

#include <algorithm>
#include <cmath>
#include <cstdarg>
#include <cstdio>

namespace plr {

namespace {

// Kept free of fmt so that the installed sdk_support needs no more packages.
__attribute__((format(printf, 2, 3))) void add(std::string& out, const char* format, ...) {
  char buffer[512];
  va_list args;
  va_start(args, format);
  const int n = std::vsnprintf(buffer, sizeof buffer, format, args);
  va_end(args);
  if (n < 0) return;
  if (static_cast<std::size_t>(n) < sizeof buffer) {
    out.append(buffer, static_cast<std::size_t>(n));
    return;
  }
  std::string big(static_cast<std::size_t>(n) + 1, '\0');
  va_start(args, format);
  std::vsnprintf(big.data(), big.size(), format, args);
  va_end(args);
  big.pop_back();
  out += big;
}

double tick_step(double span, int target, bool integer) {
  const double raw = span / std::max(target, 1);
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  double step = 10 * p;
  for (double m : {1.0, 2.0, 5.0}) {
    if (m * p >= raw * (1 - 1e-9)) {
      step = m * p;
      break;
    }
  }
  return integer ? std::max(1.0, std::round(step)) : step;
}

struct Range {
  double lo, hi;
};

// The axis's range: given ends kept, the data's ends widened to a round tick.
Range axis_range(const ChartAxis& axis, double data_lo, double data_hi) {
  double lo = axis.min.value_or(data_lo), hi = axis.max.value_or(data_hi);
  if (!(hi - lo > 1e-12)) {
    if (axis.max && !axis.min) {
      lo = hi - 1;
    } else {
      hi = lo + 1;
    }
  }
  const double step = tick_step(hi - lo, 5, axis.integer);
  if (!axis.min) lo = std::floor(lo / step + 1e-9) * step;
  if (!axis.max) hi = std::ceil(hi / step - 1e-9) * step;
  return {lo, hi};
}

std::string tick_label(double v, double step) {
  char buffer[32];
  if (step >= 1 && std::fabs(v) < 1e7) {
    std::snprintf(buffer, sizeof buffer, "%.0f", v);
  } else {
    std::snprintf(buffer, sizeof buffer, "%g", v);
  }
  return buffer;
}

constexpr double kLeft = 64, kTop = 40, kBottom = 50, kRight = 20, kCharWidth = 7;

}  // namespace

std::vector<double> chart_ticks(double min, double max, int target, bool integer) {
  std::vector<double> ticks;
  if (!(max > min) || !std::isfinite(min) || !std::isfinite(max)) return ticks;
  const double step = tick_step(max - min, target, integer);
  for (double k = std::ceil(min / step - 1e-9); k * step <= max + 1e-9 * step; k += 1) {
    const double v = k * step;
    ticks.push_back(std::fabs(v) < 1e-9 * step ? 0.0 : v);
  }
  return ticks;
}

std::string render_svg(const Chart& c) {
  double x_lo = INFINITY, x_hi = -INFINITY, y_lo = INFINITY, y_hi = -INFINITY;
  for (const ChartSeries& s : c.series) {
    for (std::size_t i = 0; i < s.points.size(); ++i) {
      x_lo = std::min(x_lo, s.points[i].x);
      x_hi = std::max(x_hi, s.points[i].x);
      y_lo = std::min(y_lo, s.points[i].y);
      y_hi = std::max(y_hi, s.points[i].y);
      if (i < s.band_low.size() && i < s.band_high.size()) {
        y_lo = std::min(y_lo, s.band_low[i]);
        y_hi = std::max(y_hi, s.band_high[i]);
      }
    }
  }
  // No data: the unit square.
  if (x_lo > x_hi) {
    x_lo = 0;
    x_hi = 1;
  }
  if (y_lo > y_hi) {
    y_lo = 0;
    y_hi = 1;
  }
  const Range xr = axis_range(c.x, x_lo, x_hi), yr = axis_range(c.y, y_lo, y_hi);

  std::size_t legend_chars = 0;
  for (const ChartSeries& s : c.series) legend_chars = std::max(legend_chars, s.label.size());
  const double right =
      legend_chars == 0
          ? kRight
          : std::clamp(50 + kCharWidth * static_cast<double>(legend_chars), 100.0, c.width / 2);
  const double x0 = kLeft, x1 = c.width - right, y0 = c.height - kBottom, y1 = kTop;
  const auto px = [&](double x) { return x0 + (x1 - x0) * (x - xr.lo) / (xr.hi - xr.lo); };
  const auto py = [&](double y) { return y0 - (y0 - y1) * (y - yr.lo) / (yr.hi - yr.lo); };

  std::string out;
  add(out,
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" "
      "viewBox=\"0 0 %.0f %.0f\" font-family=\"sans-serif\" font-size=\"12\">\n"
      "<rect width=\"100%%\" height=\"100%%\" fill=\"white\"/>\n"
      "<text x=\"%.0f\" y=\"24\" font-size=\"14\">%s</text>\n",
      c.width, c.height, c.width, c.height, x0, xml_escape(c.title).c_str());

  const std::vector<double> xt = chart_ticks(xr.lo, xr.hi, 5, c.x.integer);
  const std::vector<double> yt = chart_ticks(yr.lo, yr.hi, 5, c.y.integer);
  const double x_step = xt.size() > 1 ? xt[1] - xt[0] : 1,
               y_step = yt.size() > 1 ? yt[1] - yt[0] : 1;
  for (double t : xt) {
    add(out,
        "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#e3e3e3\"/>"
        "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">%s</text>\n",
        px(t), y0, px(t), y1, px(t), y0 + 16, tick_label(t, x_step).c_str());
  }
  for (double t : yt) {
    add(out,
        "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"#e3e3e3\"/>"
        "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"end\">%s</text>\n",
        x0, py(t), x1, py(t), x0 - 6, py(t) + 4, tick_label(t, y_step).c_str());
  }
  add(out,
      "<rect x=\"%.1f\" y=\"%.1f\" width=\"%.1f\" height=\"%.1f\" fill=\"none\" "
      "stroke=\"black\"/>\n",
      x0, y1, x1 - x0, y0 - y1);
  add(out, "<text x=\"%.1f\" y=\"%.1f\" text-anchor=\"middle\">%s</text>\n", (x0 + x1) / 2,
      c.height - 12, xml_escape(c.x.label).c_str());
  add(out,
      "<text x=\"16\" y=\"%.1f\" transform=\"rotate(-90 16 %.1f)\" "
      "text-anchor=\"middle\">%s</text>\n",
      (y0 + y1) / 2, (y0 + y1) / 2, xml_escape(c.y.label).c_str());

  // Bands under every line, lines under every marker.
  for (const ChartSeries& s : c.series) {
    if (s.band_low.size() != s.points.size() || s.band_high.size() != s.points.size() ||
        s.points.empty())
      continue;
    std::string points;
    for (std::size_t i = 0; i < s.points.size(); ++i)
      add(points, "%.1f,%.1f ", px(s.points[i].x), py(s.band_high[i]));
    for (std::size_t i = s.points.size(); i-- > 0;)
      add(points, "%.1f,%.1f ", px(s.points[i].x), py(s.band_low[i]));
    points.pop_back();
    add(out, "<polygon points=\"%s\" fill=\"%s\" fill-opacity=\"0.2\" stroke=\"none\"/>\n",
        points.c_str(), xml_escape(s.color).c_str());
  }
  for (const ChartSeries& s : c.series) {
    if (s.points.empty()) continue;
    std::string points;
    for (std::size_t i = 0; i < s.points.size(); ++i) {
      if (s.steps && i > 0) add(points, "%.1f,%.1f ", px(s.points[i].x), py(s.points[i - 1].y));
      add(points, "%.1f,%.1f ", px(s.points[i].x), py(s.points[i].y));
    }
    points.pop_back();
    add(out, "<polyline points=\"%s\" fill=\"none\" stroke=\"%s\" stroke-width=\"%g\"%s/>\n",
        points.c_str(), xml_escape(s.color).c_str(), s.width,
        s.dashed ? " stroke-dasharray=\"5 4\"" : "");
  }
  for (const ChartSeries& s : c.series) {
    if (s.marker_radius <= 0) continue;
    for (const ChartPoint& p : s.points)
      add(out, "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"%g\" fill=\"%s\"/>\n", px(p.x), py(p.y),
          s.marker_radius, xml_escape(s.color).c_str());
  }

  double row_y = y1 + 10;
  for (const ChartSeries& s : c.series) {
    if (s.label.empty()) continue;
    add(out,
        "<line x1=\"%.1f\" y1=\"%.1f\" x2=\"%.1f\" y2=\"%.1f\" stroke=\"%s\" "
        "stroke-width=\"3\"%s/><text x=\"%.1f\" y=\"%.1f\">%s</text>\n",
        x1 + 10, row_y, x1 + 30, row_y, xml_escape(s.color).c_str(),
        s.dashed ? " stroke-dasharray=\"5 4\"" : "", x1 + 36, row_y + 4,
        xml_escape(s.label).c_str());
    row_y += 18;
  }
  out += "</svg>\n";
  return out;
}

}  // namespace plr
