#include "support.hpp"

#include <algorithm>
#include <cmath>

#include "patch.hpp"

namespace plr::sim::detail {
namespace {

// How far below a box its supports may lie: boxes at rest sink a fraction
// of a millimetre into each other, and one set down loosely hovers no more
// than this above what holds it.
constexpr double kSupportGap = 0.002;  // m
// A contact holds a box up when its normal is within 45 degrees of vertical.
constexpr double kUpright = 0.7;
// The centre of mass must lie this far inside the support polygon: on its
// edge a box is in unstable balance.
constexpr double kInside = 0.002;  // m

Eigen::Isometry3d lowered(const Eigen::Isometry3d& pose) {
  Eigen::Isometry3d p = pose;
  p.translation().z() -= kSupportGap;
  return p;
}

double cross(const Eigen::Vector2d& o, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return (a - o).x() * (b - o).y() - (a - o).y() * (b - o).x();
}

// Whether `c` lies at least kInside within the convex hull of `points`
// (Andrew's monotone chain, counter-clockwise).
bool inside_hull(std::vector<Eigen::Vector2d> points, const Eigen::Vector2d& c) {
  if (points.size() < 3) return false;  // a line or a point holds nothing up
  std::sort(points.begin(), points.end(), [](const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
    return a.x() < b.x() || (a.x() == b.x() && a.y() < b.y());
  });
  std::vector<Eigen::Vector2d> hull(2 * points.size());
  std::size_t k = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    while (k >= 2 && cross(hull[k - 2], hull[k - 1], points[i]) <= 0.0) --k;
    hull[k++] = points[i];
  }
  for (std::size_t i = points.size() - 1, t = k + 1; i > 0; --i) {
    while (k >= t && cross(hull[k - 2], hull[k - 1], points[i - 1]) <= 0.0) --k;
    hull[k++] = points[i - 1];
  }
  if (k < 4) return false;  // all on a line
  hull.resize(k - 1);
  for (std::size_t i = 0; i < hull.size(); ++i) {
    const Eigen::Vector2d& a = hull[i];
    const Eigen::Vector2d& b = hull[(i + 1) % hull.size()];
    const double length = (b - a).norm();
    if (length > 0.0 && cross(a, b, c) / length < kInside) return false;
  }
  return true;
}

}  // namespace

void resting_on(const std::vector<Body>& bodies, const BroadPhase& broad, int below,
                const Eigen::Isometry3d& pose, std::vector<int>& out) {
  out.clear();
  const Body& s = bodies[static_cast<std::size_t>(below)];
  const Eigen::Vector3d e = pose.linear().cwiseAbs() * (0.5 * s.box.size);
  const Eigen::Vector3d lo = pose.translation() - e;
  const Eigen::Vector3d hi = pose.translation() + e + Eigen::Vector3d(0, 0, kSupportGap);
  std::vector<int> near;
  broad.query(lo, hi, BroadPhase::kSleeping, near);
  Patch patch;
  for (const int j : near) {
    if (j == below) continue;
    const Body& b = bodies[static_cast<std::size_t>(j)];
    box_box_patch(b.box.size, lowered(b.box.pose), s.box.size, pose, patch);
    if (!patch.points.empty() && patch.normal.z() > kUpright) out.push_back(j);
  }
}

bool supported(const std::vector<Body>& bodies, const BroadPhase& broad, int i) {
  const Body& b = bodies[static_cast<std::size_t>(i)];
  const Eigen::Isometry3d low = lowered(b.box.pose);
  std::vector<Eigen::Vector2d> points;
  Patch patch;
  box_plane_patch(b.box.size, low, Eigen::Vector3d::UnitZ(), 0.0, patch);
  for (const PatchPoint& p : patch.points) points.push_back(p.p.head<2>());
  const Eigen::Vector3d e = b.box.pose.linear().cwiseAbs() * (0.5 * b.box.size);
  std::vector<int> near;
  broad.query(b.box.pose.translation() - e - Eigen::Vector3d(0, 0, kSupportGap),
              b.box.pose.translation() + e, BroadPhase::kSleeping, near);
  for (const int j : near) {
    if (j == i) continue;
    const Body& o = bodies[static_cast<std::size_t>(j)];
    box_box_patch(b.box.size, low, o.box.size, o.box.pose, patch);
    if (patch.points.empty() || patch.normal.z() <= kUpright) continue;
    for (const PatchPoint& p : patch.points) points.push_back(p.p.head<2>());
  }
  return inside_hull(std::move(points), b.box.pose.translation().head<2>());
}

}  // namespace plr::sim::detail
