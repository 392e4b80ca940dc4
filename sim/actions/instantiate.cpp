#include "plr/actions/instantiate.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <unordered_set>

namespace plr::actions {

namespace {

constexpr double kMargin = 0.03;     // m, footprint shrink and clearances
constexpr double kClearance = 0.02;  // m, the plate's distance to boxes it must not touch
constexpr double kSlide = 0.05;      // m, steps of the plate off the face's centre
constexpr double kCovered = 0.1;     // m, the plate's centre stays this far inside the face
constexpr double kProud = 0.015;  // m a neighbour may stand out of the face (the cups reach 2 cm)
// rad: a face tilted further than this from the vertical is not taken (the
// cups seal up to about 0.26 rad).
constexpr double kMaxFaceTilt = 0.2;
constexpr double kSquare = 0.03;  // rad: faces turned less than this are taken square to the axis

sim::Height height_class(double top, double mid, double high) {
  if (top >= high) return sim::Height::kHigh;
  if (top >= mid) return sim::Height::kMid;
  return sim::Height::kLow;
}

sim::Side side_of(double y, const sim::World& w, const sim::ObservationParams& obs) {
  const double band = obs.side_band * w.trailer.width / 2;
  return y > band ? sim::Side::kLeft : (y < -band ? sim::Side::kRight : sim::Side::kCenter);
}

bool reachable(const sim::RobotModel& robot, const sim::PlateTarget& t,
               const sim::JointVector& seed) {
  return !robot.arm_ik(t, seed).empty();
}

}  // namespace

int covered_cups(const Geometry& g, double half_across, double half_up, double across, double up) {
  auto on_face = [&](int count, double field, double offset, double face_half) {
    int n = 0;
    for (int k = 0; k < count; ++k) {
      const double at = offset + ((k + 0.5) / count - 0.5) * field;
      if (std::abs(at) <= face_half - g.cups.cup_radius) ++n;
    }
    return n;
  };
  return on_face(g.cups.cups_y, g.cups.extent.y(), across, half_across) *
         on_face(g.cups.cups_x, g.cups.extent.x(), up, half_up);
}

std::vector<PickCandidate> pick_candidates(const sim::World& world, const sim::SceneAnalysis& scene,
                                           sim::Action action, const sim::ObservationParams& obs,
                                           const sim::RobotModel& robot, const Geometry& g,
                                           const sim::JointVector& current, std::size_t max_count,
                                           const std::unordered_set<std::uint32_t>& most_cups) {
  std::unordered_set<std::uint32_t> wall(scene.first_wall.begin(), scene.first_wall.end());
  std::unordered_set<std::uint32_t> front(scene.front_pile.begin(), scene.front_pile.end());
  std::vector<std::size_t> members;
  std::vector<sim::Bounds> b(world.boxes.size());
  double nearest = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < world.boxes.size(); ++i) {
    b[i] = sim::bounds(world.boxes[i]);
    nearest = std::min(nearest, b[i].x0);
    if (wall.count(world.boxes[i].id) || front.count(world.boxes[i].id)) members.push_back(i);
  }

  struct Ranked {
    PickCandidate c;
    double x_bin, top, centre_distance;
  };
  std::vector<Ranked> ranked;
  for (auto i : members) {
    const auto& box = world.boxes[i];
    const bool is_wall = wall.count(box.id) > 0;
    const double y = box.pose.translation().y();
    const auto cls = is_wall ? height_class(b[i].z1, obs.wall_mid, obs.wall_high)
                             : height_class(b[i].z1, obs.pile_mid, obs.pile_high);
    // The action's region: its height class and third of the width.
    if (cls != sim::height(action) || side_of(y, world, obs) != sim::side(action)) continue;

    // The front face: of the box's horizontal axes, the one nearest the
    // trailer's axis gives the face's normal and the plate's yaw (the wrist
    // turns the plate square to it). A box tilted on an edge has no face
    // the vertical plate can seal on.
    const Eigen::Matrix3d R = box.pose.linear();
    int normal_axis = -1, up_axis = 0;
    for (int k = 0; k < 3; ++k) {
      if (std::abs(R(2, k)) > std::abs(R(2, up_axis))) up_axis = k;
      if (std::abs(R(2, k)) < kMaxFaceTilt &&
          (normal_axis < 0 || std::abs(R(0, k)) > std::abs(R(0, normal_axis))))
        normal_axis = k;
    }
    if (normal_axis < 0 || std::abs(R(2, up_axis)) < std::cos(kMaxFaceTilt)) continue;
    Eigen::Vector3d n = R.col(normal_axis);
    n.z() = 0;
    n = n.normalized() * (n.x() < 0 ? -1.0 : 1.0);
    // A settled wall's few milliradians are not worth turning the plate for:
    // turned, it would lead with a corner.
    if (std::abs(n.y()) < kSquare) n = Eigen::Vector3d::UnitX();
    const Eigen::Vector3d lateral(-n.y(), n.x(), 0.0);
    const double plate_yaw = std::atan2(n.y(), n.x());
    const double half_d = box.size[normal_axis] / 2;
    const double half_w = box.size[3 - normal_axis - up_axis] / 2;
    const Eigen::Vector3d face_centre = box.pose.translation() - half_d * n;

    // Plate centred on the face, kept inside the trailer and off the floor.
    const double ylim = world.trailer.width / 2 - g.plate_half_width - kMargin;
    const double zc = std::clamp(face_centre.z(), g.plate_half_height + kMargin,
                                 world.trailer.height - g.plate_half_height - kMargin);
    const Eigen::Vector3d face(face_centre.x(), face_centre.y(), zc);
    // Base: the arm at its preferred reach, the lowered nose short of every box.
    const double by_reach = face.x() - g.pick_reach + g.arm_yaw_offset;
    const double by_nose = nearest - g.conveyor_length - g.nose_clearance;
    // A plate low enough to meet the lowered nose stays ahead of its tip.
    const double by_plate =
        face.z() - g.plate_half_height < g.nose_top
            ? face.x() - g.pregrasp_distance - g.conveyor_length - g.nose_clearance
            : by_reach;
    const double base_x = std::min({by_reach, by_nose, by_plate});
    sim::JointVector at = current;
    at[sim::kBaseX] = base_x;
    // The plate is wider than many boxes: the corridor it moves through to
    // the face must be clear of every other box. Where a neighbour is in the
    // way, the plate slides off centre as long as it still covers most of
    // the face.
    const double pw = g.plate_half_width, ph = g.plate_half_height;
    auto near = [](double a0, double a1, double b0, double b1) {
      return a0 - kClearance < b1 && b0 < a1 + kClearance;
    };
    auto clear = [&](double x0, double x1, double y0, double y1, double z0, double z1) {
      for (std::size_t j = 0; j < world.boxes.size(); ++j) {
        if (j != i && near(x0, x1, b[j].x0, b[j].x1) && near(y0, y1, b[j].y0, b[j].y1) &&
            near(z0, z1, b[j].z0, b[j].z1))
          return false;
      }
      return true;
    };
    auto slides = [&](double half_extent) {
      std::vector<double> out{0.0};
      for (double d = kSlide; d <= half_extent - kCovered + 1e-9; d += kSlide) {
        out.push_back(d);
        out.push_back(-d);
      }
      return out;
    };
    // The plate moves in to the face through a corridor that must be free.
    // It stops grasp_gap short of the face; a settled wall is not flush, so
    // also grasp_gap short of any neighbour under its outline that stands
    // out (by its leading corner, if the plate is turned off the trailer's
    // axis). The cups reach the face across kProud of extra gap.
    const double half_h = (b[i].z1 - b[i].z0) / 2;
    const double half_up = box.size[up_axis] / 2;
    const double reach_y = pw * std::abs(n.x());
    const double lead = pw * std::abs(n.y());
    auto plate_at = [&](double dy, double dz) {
      Eigen::Vector3d p = face + dy * lateral;
      p.y() = std::clamp(p.y(), -ylim, ylim);
      p.z() = std::clamp(face.z() + dz, ph + kMargin, world.trailer.height - ph - kMargin);
      return p;
    };
    auto cups_at = [&](const Eigen::Vector3d& p) {
      return covered_cups(g, half_w, half_up, (p - face_centre).dot(lateral),
                          p.z() - face_centre.z());
    };
    // Plate offsets (across, up) from the face's centre, in the order tried.
    std::vector<std::pair<double, double>> offsets;
    for (const double dz : slides(half_h))
      for (const double dy : slides(half_w)) offsets.emplace_back(dy, dz);
    if (most_cups.count(box.id)) {
      // Half a cup pitch off centre puts two columns (or rows) of cups on a
      // face the centred grid covers with one.
      const double across = 0.5 * g.cups.extent.y() / g.cups.cups_y;
      const double up = 0.5 * g.cups.extent.x() / g.cups.cups_x;
      for (const double dz : {0.0, up, -up})
        for (const double dy : {0.0, across, -across}) offsets.emplace_back(dy, dz);
      std::vector<int> cups;
      for (const auto& [dy, dz] : offsets) cups.push_back(cups_at(plate_at(dy, dz)));
      std::vector<std::size_t> order(offsets.size());
      for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
      std::stable_sort(order.begin(), order.end(),
                       [&](std::size_t a, std::size_t b) { return cups[a] > cups[b]; });
      std::vector<std::pair<double, double>> sorted;
      for (auto k : order) sorted.push_back(offsets[k]);
      offsets = std::move(sorted);
    }
    std::optional<Eigen::Vector3d> at_face;
    double stop_x = 0.0;
    for (const auto& [dy, dz] : offsets) {
      const Eigen::Vector3d p = plate_at(dy, dz);
      const double at_target = p.x() - g.grasp_gap * n.x();
      double stop = at_target;
      for (std::size_t j = 0; j < world.boxes.size(); ++j) {
        if (j != i && near(b[i].x0 - g.pregrasp_distance, b[i].x0, b[j].x0, b[j].x1) &&
            near(p.y() - reach_y - lead, p.y() + reach_y + lead, b[j].y0, b[j].y1) &&
            near(p.z() - ph, p.z() + ph, b[j].z0, b[j].z1))
          stop = std::min(stop, b[j].x0 - g.grasp_gap - lead);
      }
      if (at_target - stop <= kProud) {
        at_face = p;
        stop_x = stop;
        break;
      }
    }
    // The box is lifted off what it rests on (and over the lowered nose)
    // before it comes out: nothing may rest on it.
    const double lift = std::max(g.retract_lift, g.nose_top + kMargin - b[i].z0);
    const bool liftable = clear(b[i].x0 + kMargin, b[i].x1 - kMargin, b[i].y0 + kMargin,
                                b[i].y1 - kMargin, b[i].z1, b[i].z1 + lift);
    // Pulled out, the whole box (it may be wider than the plate) passes over
    // what stands in front of it; neighbours beside it, flush with its face
    // (clear() adds kClearance), are not in the way.
    const double out_depth = 2 * half_d + kMargin;
    const bool extractable = clear(b[i].x0 - out_depth, b[i].x0 - 2 * kClearance, b[i].y0, b[i].y1,
                                   b[i].z0 + lift, b[i].z1 + lift);
    if (!at_face || !liftable || !extractable) continue;
    PickCandidate c;
    c.box = box.id;
    c.base_x = base_x;
    c.cups = cups_at(*at_face);
    c.grasp = {*at_face - (at_face->x() - stop_x) / n.x() * n, plate_yaw};
    c.pregrasp = {*at_face - g.pregrasp_distance * n, plate_yaw};
    // Lifted, then pulled out until clear of what it rested on: the
    // drop-off move after that swings freely.
    c.lift = {c.grasp.position + Eigen::Vector3d(0, 0, lift), plate_yaw};
    c.retract = {c.lift.position - out_depth * n, plate_yaw};
    if (!reachable(robot, c.grasp, at) || !reachable(robot, c.pregrasp, at)) continue;
    ranked.push_back({c, std::floor((b[i].x0 - nearest) / 0.2), b[i].z1, std::abs(y)});
  }
  // Nearest first: a box behind others is reached over them, which the arm
  // plans slowly and the held box may not clear; within reach of the front,
  // high up first.
  std::stable_sort(ranked.begin(), ranked.end(), [](const Ranked& a, const Ranked& b) {
    if (a.x_bin != b.x_bin) return a.x_bin < b.x_bin;
    if (std::abs(a.top - b.top) > 1e-3) return a.top > b.top;
    return a.centre_distance < b.centre_distance;
  });
  std::vector<PickCandidate> out;
  for (std::size_t i = 0; i < ranked.size() && out.size() < max_count; ++i)
    out.push_back(ranked[i].c);
  return out;
}

std::vector<sim::PlateTarget> dropoff_targets(const sim::World& world,
                                              const std::vector<std::uint32_t>& held,
                                              const sim::RobotModel& robot, const Geometry& g,
                                              const sim::JointVector& at, std::size_t max_count) {
  // The held load's extents: along the plate's normal (depth: it sticks out
  // of the plate by that much), across it, and its height.
  double depth = 0.3, across = 0.3, height = 0.3;
  for (const auto& box : world.boxes) {
    if (std::find(held.begin(), held.end(), box.id) == held.end()) continue;
    const auto bb = sim::bounds(box);
    depth = std::max(depth, bb.x1 - bb.x0);
    across = std::max(across, bb.y1 - bb.y0);
    height = std::max(height, bb.z1 - bb.z0);
  }
  // Facing forward, the wrist stands behind the box and close to the arm's
  // yaw axis, which folds the forearm over the plate; turned sideways the
  // wrist stands beside the box and the arm reaches further out. Sideways
  // first, the wrist on the side the plate comes from.
  const double side = robot.plate_target(at).position.y() < 0 ? 1.0 : -1.0;
  std::vector<sim::PlateTarget> out;
  const double base_x = at[sim::kBaseX];
  // The folded arm cannot bend enough to reach right over the nose hinge,
  // so look further along the conveyor and higher up for IK solutions.
  for (double extra_z : {0.0, 0.2, 0.4}) {
    // The box's centre `ahead` of base_x on the conveyor's middle line.
    for (double ahead = g.dropoff_ahead; ahead <= g.conveyor_length + 1e-9; ahead += 0.1) {
      for (const double yaw : {side * M_PI / 2, -side * M_PI / 2, 0.0}) {
        // The whole box over the conveyor: its length along it.
        const double along = yaw == 0.0 ? depth : across;
        if (ahead > g.conveyor_length - along / 2 + 1e-9) continue;
        const Eigen::Vector3d n(std::cos(yaw), std::sin(yaw), 0.0);
        const Eigen::Vector3d centre(base_x + ahead, 0.0, g.dropoff_bottom + extra_z + height / 2);
        const sim::PlateTarget t{centre - depth / 2 * n, yaw};
        if (reachable(robot, t, at)) out.push_back(t);
        if (out.size() >= max_count) return out;
      }
    }
  }
  return out;
}

bool follows_lines(const sim::RobotModel& robot, const sim::JointVector& from,
                   const std::vector<sim::PlateTarget>& through) {
  constexpr double kStep = 0.01, kMaxJump = 0.25;  // as the planner's M4 lattice
  sim::JointVector q = from;
  for (const auto& to : through) {
    const sim::PlateTarget start = robot.plate_target(q);
    const double yaw_change = std::remainder(to.yaw - start.yaw, 2.0 * M_PI);
    const int n =
        std::max(1, static_cast<int>(std::ceil((to.position - start.position).norm() / kStep)));
    for (int k = 1; k <= n; ++k) {
      const double s = static_cast<double>(k) / n;
      const auto sols = robot.arm_ik(
          {start.position + s * (to.position - start.position), start.yaw + s * yaw_change}, q);
      if (sols.empty() || (sols.front() - q).cwiseAbs().maxCoeff() > kMaxJump) return false;
      q = sols.front();
    }
  }
  return true;
}

std::optional<SweepPlan> sweep_plan(const sim::World& world, const sim::SceneAnalysis& scene,
                                    sim::Action action, const Geometry& g, double scoop_extension,
                                    const sim::JointVector& current) {
  constexpr double kOnFloor = 0.05;  // m, a box bottom this low lies on the floor
  const double tip = g.conveyor_length + scoop_extension + g.scoop_lip;  // ahead of base_x
  const double deepest = world.trailer.depth - kMargin;
  std::unordered_set<std::uint32_t> front(scene.front_pile.begin(), scene.front_pile.end());
  std::unordered_set<std::uint32_t> wall(scene.first_wall.begin(), scene.first_wall.end());
  SweepPlan p;
  double near = std::numeric_limits<double>::infinity(), far = -near, top = 0.0;
  switch (sim::height(action)) {
    case sim::Height::kLow:
      for (const auto& box : world.boxes) {
        const auto b = sim::bounds(box);
        if (!front.count(box.id) || b.z0 > kOnFloor) continue;
        near = std::min(near, b.x0);
        far = std::max(far, b.x1);
      }
      if (far < near) return std::nullopt;
      // What lies on the floor layer rides up with it.
      p.swept = scene.front_pile;
      far += g.sweep_overshoot;
      if (!scene.first_wall.empty()) far = std::min(far, scene.wall_near_x - kMargin);
      break;
    case sim::Height::kMid:
      if (scene.front_pile.empty() && scene.first_wall.empty()) return std::nullopt;
      p.swept = scene.front_pile;
      p.swept.insert(p.swept.end(), scene.first_wall.begin(), scene.first_wall.end());
      near = scene.front_pile.empty() ? scene.wall_near_x : scene.pile_near_x;
      far = (scene.first_wall.empty() ? scene.pile_far_x : scene.wall_near_x) + g.sweep_dig;
      break;
    case sim::Height::kHigh:
      for (const auto& box : world.boxes) {
        if (!front.count(box.id) && !wall.count(box.id)) continue;
        const auto b = sim::bounds(box);
        p.swept.push_back(box.id);
        near = std::min(near, b.x0);
        top = std::max(top, b.z1);
      }
      if (p.swept.empty() || top < g.sweep_high_min) return std::nullopt;
      // The scoop's tip about halfway up what is in front, driven in past its face.
      p.lift = std::clamp(top / 2 - g.nose_top, 0.0, g.nose_lift_max);
      p.lower_at_end = true;
      far = near + g.sweep_high_in;
      break;
  }
  p.start_base_x = std::min(current[sim::kBaseX], near - tip - g.nose_clearance);
  p.end_base_x = std::max(p.start_base_x, std::min(far, deepest) - tip);
  return p;
}

}  // namespace plr::actions
