#include "patch.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace plr::sim::detail {
namespace {

// An edge-edge axis must beat the best face axis by this factor to be used
// (as in ODE's dBoxBox): face contacts give patches, edge contacts one point.
constexpr double kEdgePreference = 1.05;
// Edge axes closer than this (cosine, ~18 degrees) to a face normal are left
// to the face axes.
constexpr double kFaceLike = 0.95;

// Convex polygon; a quad clipped by 5 half-spaces has at most 9 vertices.
struct Polygon {
  std::array<Eigen::Vector3d, 12> v;
  int n = 0;
};

// Keeps the part of `poly` where a . x <= offset (Sutherland-Hodgman).
void clip(Polygon& poly, const Eigen::Vector3d& a, double offset) {
  Polygon out;
  for (int i = 0; i < poly.n; ++i) {
    const Eigen::Vector3d& p = poly.v[static_cast<std::size_t>(i)];
    const Eigen::Vector3d& q = poly.v[static_cast<std::size_t>((i + 1) % poly.n)];
    const double fp = offset - a.dot(p), fq = offset - a.dot(q);
    if (fp >= 0.0) out.v[static_cast<std::size_t>(out.n++)] = p;
    if ((fp > 0.0 && fq < 0.0) || (fp < 0.0 && fq > 0.0)) {
      out.v[static_cast<std::size_t>(out.n++)] = p + (fp / (fp - fq)) * (q - p);
    }
  }
  poly = out;
}

// The face of a box (centre c, rotation r, half extents h) whose outward
// normal is most opposed to `n`, as a quad.
Polygon incident_face(const Eigen::Vector3d& c, const Eigen::Matrix3d& r, const Eigen::Vector3d& h,
                      const Eigen::Vector3d& n) {
  const Eigen::Vector3d along = r.transpose() * n;
  int k = 0;
  along.cwiseAbs().maxCoeff(&k);
  const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
  const Eigen::Vector3d centre = c - std::copysign(h[k], along[k]) * r.col(k);
  const Eigen::Vector3d u = h[k1] * r.col(k1), v = h[k2] * r.col(k2);
  Polygon quad;
  quad.v = {centre - u - v, centre + u - v, centre + u + v, centre - u + v};
  quad.n = 4;
  return quad;
}

// Samples the polygon below the plane nr . x = top (depth = top - nr . x) at
// its vertices, each weighted by half its two edges' share of the perimeter:
// a square gets its corners at 1/4 each (a box's rocking stiffness), and a
// vertex that appears or merges has a zero-length edge, so the samples change
// continuously with the poses.
void sample(const Polygon& poly, const Eigen::Vector3d& nr, double top, Patch& patch) {
  const auto at = [&](int i) -> const Eigen::Vector3d& {
    return poly.v[static_cast<std::size_t>(i % poly.n)];
  };
  std::array<double, 12> edge{};
  double perimeter = 0.0;
  for (int i = 0; i < poly.n; ++i) {
    edge[static_cast<std::size_t>(i)] = (at(i + 1) - at(i)).norm();
    perimeter += edge[static_cast<std::size_t>(i)];
  }
  for (int i = 0; i < poly.n; ++i) {
    const double weight = perimeter < 1e-9
                              ? 1.0 / poly.n
                              : 0.5 *
                                    (edge[static_cast<std::size_t>((i + poly.n - 1) % poly.n)] +
                                     edge[static_cast<std::size_t>(i)]) /
                                    perimeter;
    const double depth = std::max(0.0, top - nr.dot(at(i)));
    patch.points.push_back({at(i) + 0.5 * depth * nr, depth, weight});
  }
}

}  // namespace

void box_box_patch(const Eigen::Vector3d& size_a, const Eigen::Isometry3d& pose_a,
                   const Eigen::Vector3d& size_b, const Eigen::Isometry3d& pose_b, Patch& patch) {
  patch.points.clear();
  const Eigen::Matrix3d ra = pose_a.linear(), rb = pose_b.linear();
  const Eigen::Vector3d ha = 0.5 * size_a, hb = 0.5 * size_b;
  const Eigen::Vector3d d = pose_b.translation() - pose_a.translation();
  const Eigen::Matrix3d abs_c = (ra.transpose() * rb).cwiseAbs();
  const Eigen::Vector3d da = ra.transpose() * d, db = rb.transpose() * d;

  // Separating axes: the smallest penetration gives the contact normal.
  double face_depth = INFINITY;
  int face = -1;  // 0-2: a face of box a, 3-5: of box b
  for (int i = 0; i < 3; ++i) {
    const double depth = ha[i] + abs_c.row(i).dot(hb) - std::abs(da[i]);
    if (depth < 0.0) return;
    if (depth < face_depth) {
      face_depth = depth;
      face = i;
    }
  }
  for (int j = 0; j < 3; ++j) {
    const double depth = hb[j] + abs_c.col(j).dot(ha) - std::abs(db[j]);
    if (depth < 0.0) return;
    if (depth < face_depth) {
      face_depth = depth;
      face = 3 + j;
    }
  }
  double edge_depth = INFINITY;
  int edge_a = -1, edge_b = -1;
  Eigen::Vector3d edge_axis = Eigen::Vector3d::Zero();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      Eigen::Vector3d axis = ra.col(i).cross(rb.col(j));
      const double length = axis.norm();
      if (length < 1e-5) continue;  // parallel edges: the face axes cover them
      axis /= length;
      // Nearly along a face normal (e.g. the horizontal edges of two upright
      // boxes with different yaw): the face patch is the contact, and a
      // one-point edge contact winning by rounding makes the pair chatter.
      const Eigen::Vector3d along_a = (ra.transpose() * axis).cwiseAbs();
      const Eigen::Vector3d along_b = (rb.transpose() * axis).cwiseAbs();
      if (std::max(along_a.maxCoeff(), along_b.maxCoeff()) > kFaceLike) continue;
      const double depth = along_a.dot(ha) + along_b.dot(hb) - std::abs(axis.dot(d));
      if (depth < 0.0) return;
      if (depth < edge_depth) {
        edge_depth = depth;
        edge_a = i;
        edge_b = j;
        edge_axis = axis.dot(d) < 0.0 ? Eigen::Vector3d(-axis) : axis;
      }
    }
  }

  if (edge_depth * kEdgePreference < face_depth) {
    // Edge on edge: one point between the closest points of the two edges.
    patch.normal = -edge_axis;
    Eigen::Vector3d pa = pose_a.translation(), pb = pose_b.translation();
    for (int k = 0; k < 3; ++k) {
      if (k != edge_a) pa += std::copysign(ha[k], edge_axis.dot(ra.col(k))) * ra.col(k);
      if (k != edge_b) pb -= std::copysign(hb[k], edge_axis.dot(rb.col(k))) * rb.col(k);
    }
    const Eigen::Vector3d ua = ra.col(edge_a), ub = rb.col(edge_b), w = pb - pa;
    const double uu = ua.dot(ub), denom = std::max(1e-9, 1.0 - uu * uu);
    const double s = std::clamp((ua.dot(w) - uu * ub.dot(w)) / denom, -ha[edge_a], ha[edge_a]);
    const double t = std::clamp((uu * ua.dot(w) - ub.dot(w)) / denom, -hb[edge_b], hb[edge_b]);
    patch.points.push_back({0.5 * (pa + s * ua + pb + t * ub), edge_depth, 1.0});
    return;
  }

  // Face of the reference box against the most opposed face of the other,
  // clipped to the reference face and to where they interpenetrate.
  const bool ref_a = face < 3;
  const int i = face % 3;
  const Eigen::Vector3d& c_ref = ref_a ? pose_a.translation() : pose_b.translation();
  const Eigen::Matrix3d& r_ref = ref_a ? ra : rb;
  const Eigen::Vector3d& h_ref = ref_a ? ha : hb;
  const double toward = ref_a ? da[i] : -db[i];  // other centre along the face axis
  const Eigen::Vector3d nr = toward < 0.0 ? Eigen::Vector3d(-r_ref.col(i)) : r_ref.col(i);
  Polygon poly = ref_a ? incident_face(pose_b.translation(), rb, hb, nr)
                       : incident_face(pose_a.translation(), ra, ha, nr);
  for (const int k : {(i + 1) % 3, (i + 2) % 3}) {
    const Eigen::Vector3d& axis = r_ref.col(k);
    clip(poly, axis, axis.dot(c_ref) + h_ref[k]);
    clip(poly, -axis, -axis.dot(c_ref) + h_ref[k]);
  }
  const double top = nr.dot(c_ref) + h_ref[i];
  clip(poly, nr, top);
  patch.normal = ref_a ? Eigen::Vector3d(-nr) : nr;
  sample(poly, nr, top, patch);
}

void box_plane_patch(const Eigen::Vector3d& size, const Eigen::Isometry3d& pose,
                     const Eigen::Vector3d& normal, double offset, Patch& patch) {
  patch.points.clear();
  patch.normal = normal;
  Polygon poly = incident_face(pose.translation(), pose.linear(), 0.5 * size, normal);
  clip(poly, normal, offset);
  sample(poly, normal, offset, patch);
}

}  // namespace plr::sim::detail
