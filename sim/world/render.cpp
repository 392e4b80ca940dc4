// Hand-written SVG: each box is the convex hull of its 8 corners projected
// onto the view plane, drawn far to near.
#include "plr/sim/render.hpp"

#include <fmt/format.h>
#include <plr/atomic_file.hpp>
#include <plr/xml_escape.hpp>

#include <algorithm>
#include <array>
#include <cmath>

namespace plr::sim {
namespace {

struct Projection {
  int u, v, depth;  // axes: horizontal, vertical, towards the viewer
};

Projection axes(View view) {
  // Side view looks from -y (the robot's left); top view looks down.
  return view == View::kSide ? Projection{0, 2, 1} : Projection{0, 1, 2};
}

std::vector<Eigen::Vector2d> hull(std::vector<Eigen::Vector2d> p) {
  std::sort(p.begin(), p.end(), [](const auto& a, const auto& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  const auto cross = [](const Eigen::Vector2d& o, const Eigen::Vector2d& a,
                        const Eigen::Vector2d& b) {
    return (a - o).x() * (b - o).y() - (a - o).y() * (b - o).x();
  };
  std::vector<Eigen::Vector2d> h(2 * p.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    while (k >= 2 && cross(h[k - 2], h[k - 1], p[i]) <= 0) --k;
    h[k++] = p[i];
  }
  for (std::size_t i = p.size() - 1, t = k + 1; i > 0; --i) {
    while (k >= t && cross(h[k - 2], h[k - 1], p[i - 1]) <= 0) --k;
    h[k++] = p[i - 1];
  }
  h.resize(k > 0 ? k - 1 : 0);
  return h;
}

std::string mass_colour(double mass, double max_mass) {
  if (mass <= 0.0) return "#b0b0b0";
  const double s = std::clamp(mass / std::max(max_mass, 1e-9), 0.0, 1.0);
  // Pale yellow (light) to dark red (heavy).
  const int r = static_cast<int>(std::lround(255 - 95 * s));
  const int g = static_cast<int>(std::lround(235 - 215 * s));
  const int b = static_cast<int>(std::lround(160 - 140 * s));
  return fmt::format("#{:02x}{:02x}{:02x}", r, g, b);
}

}  // namespace

std::string render_svg(const World& world, View view, const RenderOptions& o) {
  const Projection a = axes(view);
  const Trailer& t = world.trailer;
  const double s = o.pixels_per_metre;
  const double margin = 20.0;
  const double v_min = view == View::kSide ? 0.0 : -0.5 * t.width;
  const double v_max = view == View::kSide ? t.height : 0.5 * t.width;
  const double width = (t.depth - o.x_min) * s + 2 * margin;
  const double height = (v_max - v_min) * s + 2 * margin + (o.title.empty() ? 0.0 : 20.0);
  const double top = o.title.empty() ? margin : margin + 20.0;
  const auto px = [&](const Eigen::Vector2d& p) {
    return Eigen::Vector2d(margin + (p.x() - o.x_min) * s, top + (v_max - p.y()) * s);
  };
  std::string svg = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{:.0f}\" height=\"{:.0f}\" "
      "viewBox=\"0 0 {:.0f} {:.0f}\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n",
      width, height, width, height);
  if (!o.title.empty()) {
    svg += fmt::format(
        "<text x=\"{:.0f}\" y=\"16\" font-family=\"sans-serif\" "
        "font-size=\"14\">{}</text>\n",
        margin, xml_escape(o.title));
  }
  const Eigen::Vector2d c0 = px({0.0, v_max}), c1 = px({t.depth, v_min});
  svg += fmt::format(
      "<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"#f4f6f8\" "
      "stroke=\"#333\" stroke-width=\"3\"/>\n",
      c0.x(), c0.y(), c1.x() - c0.x(), c1.y() - c0.y());

  struct Shape {
    double depth;
    std::vector<Eigen::Vector2d> outline;
    std::string fill;
    double opacity;
  };
  std::vector<Shape> shapes;
  const auto add = [&](const Eigen::Vector3d& size, const Eigen::Isometry3d& pose, std::string fill,
                       double opacity) {
    std::vector<Eigen::Vector2d> corners;
    for (int c = 0; c < 8; ++c) {
      const Eigen::Vector3d local(((c & 1) ? 0.5 : -0.5) * size.x(),
                                  ((c & 2) ? 0.5 : -0.5) * size.y(),
                                  ((c & 4) ? 0.5 : -0.5) * size.z());
      const Eigen::Vector3d p = pose * local;
      corners.push_back(px({p[a.u], p[a.v]}));
    }
    shapes.push_back(
        {pose.translation()[a.depth], hull(std::move(corners)), std::move(fill), opacity});
  };
  double max_mass = 0.0;
  for (const Box& b : world.boxes) max_mass = std::max(max_mass, b.mass);
  for (const Box& b : world.boxes) add(b.size, b.pose, mass_colour(b.mass, max_mass), 1.0);
  // Far to near: in the side view the viewer stands at -y, in the top view above.
  const bool near_is_low = view == View::kSide;
  std::stable_sort(shapes.begin(), shapes.end(), [&](const Shape& p, const Shape& q) {
    return near_is_low ? p.depth > q.depth : p.depth < q.depth;
  });
  const std::size_t boxes_end = shapes.size();
  for (const Overlay& r : o.robot) add(r.size, r.pose, "#3a6ea5", 0.6);
  for (std::size_t i = 0; i < shapes.size(); ++i) {
    const Shape& sh = shapes[i];
    std::string points;
    for (const auto& p : sh.outline) points += fmt::format("{:.1f},{:.1f} ", p.x(), p.y());
    svg += fmt::format(
        "<polygon points=\"{}\" fill=\"{}\" fill-opacity=\"{}\" stroke=\"{}\" "
        "stroke-width=\"1\"/>\n",
        points, sh.fill, sh.opacity, i < boxes_end ? "#5a4a3a" : "#1d3557");
  }
  svg += "</svg>\n";
  return svg;
}

Status write_svg(const std::filesystem::path& file, const World& world, View view,
                 const RenderOptions& options) {
  return write_file_atomically(file.string(), render_svg(world, view, options));
}

}  // namespace plr::sim
