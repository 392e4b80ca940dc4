#include "footprint.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace plr::actions {

namespace {

double cross(const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return (a - o).x() * (b - o).y() - (a - o).y() * (b - o).x();
}

Polygon hull(std::vector<Eigen::Vector2d> pts) {
  std::sort(pts.begin(), pts.end(), [](const auto& a, const auto& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  if (pts.size() < 3) return pts;
  Polygon h(2 * pts.size());
  std::size_t k = 0;
  for (const auto& p : pts) {  // lower chain
    while (k >= 2 && cross(h[k - 2], h[k - 1], p) <= 0) --k;
    h[k++] = p;
  }
  for (std::size_t i = pts.size() - 1, t = k + 1; i-- > 0;) {  // upper chain
    while (k >= t && cross(h[k - 2], h[k - 1], pts[i]) <= 0) --k;
    h[k++] = pts[i];
  }
  h.resize(k - 1);
  return h;
}

// Largest gap between the two outlines' projections on the normals of
// `edges`' sides.
double gap_along_normals(const Polygon& edges, const Polygon& a, const Polygon& b) {
  double best = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < edges.size(); ++i) {
    const Eigen::Vector2d e = edges[(i + 1) % edges.size()] - edges[i];
    if (e.squaredNorm() < 1e-18) continue;
    const Eigen::Vector2d axis = Eigen::Vector2d(e.y(), -e.x()).normalized();
    double a0 = std::numeric_limits<double>::infinity(), a1 = -a0, b0 = a0, b1 = -a0;
    for (const auto& p : a) {
      a0 = std::min(a0, axis.dot(p));
      a1 = std::max(a1, axis.dot(p));
    }
    for (const auto& p : b) {
      b0 = std::min(b0, axis.dot(p));
      b1 = std::max(b1, axis.dot(p));
    }
    best = std::max(best, std::max(b0 - a1, a0 - b1));
  }
  return best;
}

}  // namespace

Polygon footprint(const sim::Box& box) {
  std::vector<Eigen::Vector2d> corners;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d local((c & 1 ? 0.5 : -0.5) * box.size.x(),
                                (c & 2 ? 0.5 : -0.5) * box.size.y(),
                                (c & 4 ? 0.5 : -0.5) * box.size.z());
    corners.push_back((box.pose * local).head<2>());
  }
  return hull(std::move(corners));
}

Polygon swept(const Polygon& p, const Eigen::Vector2d& d) {
  std::vector<Eigen::Vector2d> pts = p;
  for (const auto& q : p) pts.push_back(q + d);
  return hull(std::move(pts));
}

double separation(const Polygon& a, const Polygon& b) {
  return std::max(gap_along_normals(a, a, b), gap_along_normals(b, a, b));
}

std::optional<Span> span_in_band(const Polygon& p, const Eigen::Vector2d& origin,
                                 const Eigen::Vector2d& n, double half_width) {
  const Eigen::Vector2d lateral(-n.y(), n.x());
  // Each side of the outline, clipped to the band, contributes its ends.
  std::optional<Span> out;
  auto add = [&](const Eigen::Vector2d& q) {
    const double along = n.dot(q - origin);
    if (!out) out = Span{along, along};
    out->min = std::min(out->min, along);
    out->max = std::max(out->max, along);
  };
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Eigen::Vector2d a = p[i], b = p[(i + 1) % p.size()];
    const double la = lateral.dot(a - origin), lb = lateral.dot(b - origin);
    double t0 = 0, t1 = 1;
    for (const double bound : {-half_width, half_width}) {
      const bool lower = bound < 0;
      const double fa = lower ? la - bound : bound - la, fb = lower ? lb - bound : bound - lb;
      if (fa < 0 && fb < 0) {
        t0 = 1;
        t1 = 0;
      } else if (fa < 0) {
        t0 = std::max(t0, fa / (fa - fb));
      } else if (fb < 0) {
        t1 = std::min(t1, fa / (fa - fb));
      }
    }
    // The strip is unbounded along n and the outline bounded: where they
    // meet, some side of the outline lies in the strip.
    if (t0 > t1) continue;
    add(a + t0 * (b - a));
    add(a + t1 * (b - a));
  }
  return out;
}

}  // namespace plr::actions
