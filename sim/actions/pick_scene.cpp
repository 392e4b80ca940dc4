// Pick pipeline, scene queries and generation: the faces of the boxes in
// front, the region of the action, and the plate poses tried on a face.
#include <algorithm>
#include <cmath>
#include <limits>

#include "pick_pipeline.hpp"

namespace plr::actions::pick {

namespace {

sim::Height height_class(double top, double mid, double high) {
  if (top >= high) return sim::Height::kHigh;
  if (top >= mid) return sim::Height::kMid;
  return sim::Height::kLow;
}

sim::Side side_of(double y, const sim::World& w, const sim::ObservationParams& obs) {
  const double band = obs.side_band * w.trailer.width / 2;
  return y > band ? sim::Side::kLeft : (y < -band ? sim::Side::kRight : sim::Side::kCenter);
}

double plate_body_depth(const sim::RobotModel& robot) {
  double depth = 0.0;
  for (const auto& shape : robot.links()[static_cast<std::size_t>(robot.plate_link())].shapes)
    if (shape.type == sim::CollisionShape::Type::kBox) depth = std::max(depth, shape.size.x());
  return depth;
}

// A box axis made horizontal and unit, pointing into the trailer (+x).
Eigen::Vector3d inward(Eigen::Vector3d axis) {
  axis.z() = 0;
  return axis.normalized() * (axis.x() < 0 ? -1.0 : 1.0);
}

// The face whose normal is box axis `axis` (n: that axis made horizontal,
// pointing into the trailer).
Face face_along(const sim::Box& box, int axis, int up, const Eigen::Vector3d& n) {
  Face f;
  f.n = n;
  f.lateral = Eigen::Vector3d(-n.y(), n.x(), 0.0);
  f.half_d = box.size[axis] / 2;
  f.half_w = box.size[3 - axis - up] / 2;
  f.half_up = box.size[up] / 2;
  f.centre = box.pose.translation() - f.half_d * n;
  return f;
}

// The face square to the robot; none for a box tilted on an edge, which has
// no face the vertical plate can seal on.
std::optional<Face> square_face(const sim::Box& box) {
  if (!has_sealable_face(box)) return std::nullopt;
  const Eigen::Matrix3d R = box.pose.linear();
  int normal_axis = -1;
  for (int k = 0; k < 3; ++k)
    if (std::abs(R(2, k)) < kMaxFaceTilt &&
        (normal_axis < 0 || std::abs(R(0, k)) > std::abs(R(0, normal_axis))))
      normal_axis = k;
  Eigen::Vector3d n = inward(R.col(normal_axis));
  // A settled wall's few milliradians are not worth turning the plate for:
  // turned, it would lead with a corner.
  if (std::abs(n.y()) < kSquare) n = Eigen::Vector3d::UnitX();
  return face_along(box, normal_axis, up_axis(R), n);
}

}  // namespace

int up_axis(const Eigen::Matrix3d& R) {
  int up = 0;
  for (int k = 1; k < 3; ++k)
    if (std::abs(R(2, k)) > std::abs(R(2, up))) up = k;
  return up;
}

bool PickScene::in_front(std::size_t j) const {
  const std::uint32_t id = world.boxes[j].id;
  return wall.count(id) > 0 || front.count(id) > 0;
}

PickScene query_scene(const sim::World& world, const sim::SceneAnalysis& scene, sim::Action action,
                      const sim::ObservationParams& obs, const sim::RobotModel& robot,
                      const Geometry& g, const sim::JointVector& current) {
  const std::size_t count = world.boxes.size();
  PickScene s{world,
              {scene.first_wall.begin(), scene.first_wall.end()},
              {scene.front_pile.begin(), scene.front_pile.end()},
              std::vector<sim::Bounds>(count),
              std::vector<Polygon>(count),
              std::vector<std::optional<Face>>(count),
              std::vector<bool>(count, false),
              std::numeric_limits<double>::infinity(),
              plate_body_depth(robot)};
  const std::vector<std::uint32_t> on_robot = boxes_on_robot(world, robot, current);
  for (std::size_t i = 0; i < count; ++i) {
    const auto& box = world.boxes[i];
    const sim::Bounds& b = s.bounds[i] = sim::bounds(box);
    s.outline[i] = footprint(box);
    if (b.z0 < g.nose_top + kMargin &&
        std::find(on_robot.begin(), on_robot.end(), box.id) == on_robot.end())
      s.nearest = std::min(s.nearest, b.x0);
    const bool is_wall = s.wall.count(box.id) > 0;
    if (!is_wall && !s.front.count(box.id)) continue;
    s.faces[i] = square_face(box);
    const auto cls = is_wall ? height_class(b.z1, obs.wall_mid, obs.wall_high)
                             : height_class(b.z1, obs.pile_mid, obs.pile_high);
    s.in_region[i] = cls == sim::height(action) &&
                     side_of(box.pose.translation().y(), world, obs) == sim::side(action);
  }
  return s;
}

std::vector<Face> faces_to_try(const PickScene& s, std::size_t i) {
  std::vector<Face> out{*s.faces[i]};
  const auto& box = s.world.boxes[i];
  const Eigen::Matrix3d R = box.pose.linear();
  const int up = up_axis(R);
  for (int k = 0; k < 3; ++k) {
    if (k == up || R.col(k).head<2>().norm() < 0.5) continue;
    const Eigen::Vector3d n = inward(R.col(k));
    if (n.dot(out.front().n) > std::cos(kMaxFaceTilt) ||
        std::atan2(std::abs(n.y()), n.x()) > kMaxSideFace)
      continue;
    out.push_back(face_along(box, k, up, n));
  }
  return out;
}

std::vector<bool> stacked_on(const PickScene& s, std::size_t i) {
  const auto& b = s.bounds;
  std::vector<bool> stacked(s.size(), false);
  std::vector<std::size_t> stack{i};
  for (std::size_t next = 0; next < stack.size(); ++next) {
    const std::size_t k = stack[next];
    for (std::size_t j = 0; j < s.size(); ++j)
      if (j != i && !stacked[j] && std::abs(b[j].z0 - b[k].z1) < kStacked && s.in_front(j) &&
          separation(s.outline[k], s.outline[j]) < -kMargin) {
        stacked[j] = true;
        stack.push_back(j);
      }
  }
  return stacked;
}

Approach approach(const PickScene& s, const Geometry& g, std::size_t i, const Face& f,
                  bool alternative) {
  Approach a;
  a.box = i;
  a.face = f;
  a.alternative = alternative;
  a.yaw = std::atan2(f.n.y(), f.n.x());
  // Turned, the plate body's back corner reaches further out.
  const sim::Trailer& trailer = s.world.trailer;
  a.ylim = trailer.width / 2 - g.plate_half_width() * std::abs(f.n.x()) -
           s.plate_depth * std::abs(f.n.y()) - kMargin;
  const double ph = g.plate_half_height();
  a.point =
      Eigen::Vector3d(f.centre.x(), f.centre.y(),
                      std::clamp(f.centre.z(), ph + kFloorGap, trailer.height - ph - kMargin));
  return a;
}

std::vector<std::pair<double, double>> plate_offsets(const Geometry& g, const Face& f,
                                                     double half_h, bool fewer) {
  // The plate is wider than many boxes: where a neighbour is in the way, it
  // slides off centre as long as it still covers most of the face.
  auto slides = [](double half_extent) {
    std::vector<double> out{0.0};
    for (double d = kSlide; d <= half_extent - kCovered + 1e-9; d += kSlide) {
      out.push_back(d);
      out.push_back(-d);
    }
    return out;
  };
  std::vector<std::pair<double, double>> offsets;
  for (const double dz : slides(half_h))
    for (const double dy : slides(f.half_w)) offsets.emplace_back(dy, dz);
  for (const double dz : {0.0, f.half_up, -f.half_up})
    for (const double dy : {0.0, f.half_w, -f.half_w})
      if (dy != 0.0 || dz != 0.0) offsets.emplace_back(dy, dz);
  if (fewer) {
    // Half a cup pitch off centre puts two columns (or rows) of cups on a
    // face the centred grid covers with one.
    const double across = 0.5 * g.cups.extent.y() / g.cups.cups_y;
    const double up = 0.5 * g.cups.extent.x() / g.cups.cups_x;
    for (const double dz : {0.0, up, -up})
      for (const double dy : {0.0, across, -across}) offsets.emplace_back(dy, dz);
  }
  return offsets;
}

Eigen::Vector3d plate_at(const sim::World& world, const Geometry& g, const Approach& a, double dy,
                         double dz) {
  const double ph = g.plate_half_height();
  Eigen::Vector3d p = a.point + dy * a.face.lateral;
  p.y() = std::clamp(p.y(), -a.ylim, a.ylim);
  p.z() = std::clamp(a.point.z() + dz, ph + kFloorGap, world.trailer.height - ph - kMargin);
  return p;
}

int cups_on(const PickScene& s, const Geometry& g, const Approach& a, std::size_t j,
            const Eigen::Vector3d& p) {
  // Measured across the approached face (the plate's rows run along it).
  const Face& fj = a.face_of(s, j);
  return covered_cups(g, fj.half_w, fj.half_up, (p - fj.centre).dot(a.face.lateral),
                      p.z() - fj.centre.z());
}

}  // namespace plr::actions::pick
