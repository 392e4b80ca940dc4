#include "plr/actions/instantiate.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <unordered_set>

#include "pick_pipeline.hpp"

namespace plr::actions {

namespace {

using pick::kMargin;
using pick::kMaxFaceTilt;
using pick::kStacked;
using pick::up_axis;

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

std::vector<std::uint32_t> boxes_touching(const sim::World& world, const sim::RobotModel& robot,
                                          const sim::JointVector& q,
                                          const std::vector<std::string>& links) {
  constexpr double kTouch = 0.02;
  std::vector<Eigen::Isometry3d> poses;
  robot.forward_kinematics(q, poses);
  std::vector<sim::Bounds> shapes;
  for (std::size_t l = 0; l < robot.links().size(); ++l) {
    const auto& link = robot.links()[l];
    if (!links.empty() && std::find(links.begin(), links.end(), link.name) == links.end()) continue;
    for (const auto& shape : link.shapes) {
      if (shape.type != sim::CollisionShape::Type::kBox) continue;
      const Eigen::Isometry3d pose = poses[l] * shape.origin;
      const Eigen::Vector3d e = pose.linear().cwiseAbs() * (shape.size / 2);
      const Eigen::Vector3d lo = pose.translation() - e, hi = pose.translation() + e;
      shapes.push_back({lo.x(), hi.x(), lo.y(), hi.y(), lo.z(), hi.z()});
    }
  }
  std::vector<std::uint32_t> out;
  for (const auto& box : world.boxes) {
    const auto b = sim::bounds(box);
    if (std::any_of(shapes.begin(), shapes.end(),
                    [&](const sim::Bounds& n) { return sim::within(b, n, kTouch); }))
      out.push_back(box.id);
  }
  return out;
}

bool behind_robot(const sim::Box& box, const sim::JointVector& q) {
  return sim::bounds(box).x1 < q[sim::kBaseX];
}

namespace {

// Whether the box lies (partly) on one of the robot's link shapes: a point
// of its lowest face, a little above or inside a shape (`shapes`: poses and
// half sizes). Points 10 % in from its edges: a shape beside the box (the
// plate against its face) is not under it.
bool rests_on_shapes(const sim::Box& box,
                     const std::vector<std::pair<Eigen::Isometry3d, Eigen::Vector3d>>& shapes) {
  constexpr double kBelow = 0.03;  // m under the face a supporting shape may stand
  constexpr double kSlack = 0.01;  // m the shapes are grown by
  const Eigen::Matrix3d& r = box.pose.linear();
  int down = 0;
  for (int k = 1; k < 3; ++k)
    if (std::abs(r(2, k)) > std::abs(r(2, down))) down = k;
  const int u = (down + 1) % 3, v = (down + 2) % 3;
  const Eigen::Vector3d half = box.size / 2;
  const Eigen::Vector3d face =
      box.pose.translation() - std::copysign(half[down], r(2, down)) * r.col(down);
  for (double a : {-0.8, -0.4, 0.0, 0.4, 0.8})
    for (double b : {-0.8, -0.4, 0.0, 0.4, 0.8})
      for (double d : {0.0, kBelow / 2, kBelow}) {
        const Eigen::Vector3d p =
            face + a * half[u] * r.col(u) + b * half[v] * r.col(v) - d * Eigen::Vector3d::UnitZ();
        for (const auto& [pose, h] : shapes) {
          const Eigen::Vector3d local = pose.inverse() * p;
          if ((local.cwiseAbs().array() <= h.array() + kSlack).all()) return true;
        }
      }
  return false;
}

}  // namespace

std::vector<std::uint32_t> boxes_on_robot(const sim::World& world, const sim::RobotModel& robot,
                                          const sim::JointVector& q,
                                          const std::vector<std::uint32_t>& held) {
  constexpr double kOffFloor = 0.02;  // m: a box touching the robot this high lies on it
  constexpr double kUnder = 0.03;     // m: a box whose top is this close under another carries it
  const auto touching = boxes_touching(world, robot, q);
  std::vector<Eigen::Isometry3d> poses;
  robot.forward_kinematics(q, poses);
  // The nose's links are left out: the scoop goes under what it sweeps, and
  // the boxes on it and on others are the pile's until the belt takes them.
  std::vector<std::pair<Eigen::Isometry3d, Eigen::Vector3d>> shapes;
  for (std::size_t l = 0; l < robot.links().size(); ++l)
    for (const auto& shape : robot.links()[l].shapes)
      if (robot.links()[l].name.rfind("nose_", 0) != 0)
        if (shape.type == sim::CollisionShape::Type::kBox)
          shapes.emplace_back(poses[l] * shape.origin, shape.size / 2);
  const std::size_t n = world.boxes.size();
  // What each box rests on: the boxes whose tops are just under its bottom.
  std::vector<std::vector<std::size_t>> under(n);
  std::vector<sim::Bounds> bounds(n);
  for (std::size_t i = 0; i < n; ++i) bounds[i] = sim::bounds(world.boxes[i]);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < n; ++j) {
      const sim::Bounds &b = bounds[i], &u = bounds[j];
      if (j != i && u.z1 < b.z0 + kUnder && u.z1 > b.z0 - kUnder && u.x0 < b.x1 && b.x0 < u.x1 &&
          u.y0 < b.y1 && b.y0 < u.y1)
        under[i].push_back(j);
    }
  std::vector<bool> free(n), on(n, false);
  for (std::size_t i = 0; i < n; ++i) {
    const auto id = world.boxes[i].id;
    free[i] = bounds[i].z0 > kOffFloor && std::find(held.begin(), held.end(), id) == held.end();
    if (!free[i] || std::find(touching.begin(), touching.end(), id) == touching.end()) continue;
    // A box touching the robot and standing on other boxes (a wall box
    // beside the plate) is the trailer's, unless a link is under it too: a
    // box dragged onto the arm, half on the wall it came from, rides on it.
    on[i] = under[i].empty() || rests_on_shapes(world.boxes[i], shapes);
  }
  // What rests only on boxes lying on the robot lies on it too (a box
  // dragged out on top of another onto the arm).
  for (bool grew = true; grew;) {
    grew = false;
    for (std::size_t i = 0; i < n; ++i) {
      if (on[i] || !free[i] || under[i].empty()) continue;
      if (std::all_of(under[i].begin(), under[i].end(), [&](std::size_t j) { return on[j]; })) {
        on[i] = true;
        grew = true;
      }
    }
  }
  std::vector<std::uint32_t> out;
  for (std::size_t i = 0; i < n; ++i)
    if (on[i]) out.push_back(world.boxes[i].id);
  return out;
}

sim::World without(const sim::World& world, const std::vector<std::uint32_t>& ids) {
  sim::World out = world;
  std::erase_if(out.boxes, [&](const sim::Box& b) {
    return std::find(ids.begin(), ids.end(), b.id) != ids.end();
  });
  return out;
}

std::vector<std::uint32_t> boxes_on_load(const sim::World& world,
                                         const std::vector<std::uint32_t>& held) {
  std::vector<sim::Bounds> load;
  for (const auto& box : world.boxes)
    if (std::find(held.begin(), held.end(), box.id) != held.end()) load.push_back(sim::bounds(box));
  std::vector<std::uint32_t> out;
  if (load.empty()) return out;
  for (const auto& box : world.boxes) {
    if (std::find(held.begin(), held.end(), box.id) != held.end()) continue;
    const sim::Bounds b = sim::bounds(box);
    if (std::any_of(load.begin(), load.end(), [&](const sim::Bounds& h) {
          return std::abs(b.z0 - h.z1) < kStacked && h.x0 < b.x1 && b.x0 < h.x1 && h.y0 < b.y1 &&
                 b.y0 < h.y1;
        }))
      out.push_back(box.id);
  }
  return out;
}

bool has_sealable_face(const sim::Box& box) {
  const Eigen::Matrix3d R = box.pose.linear();
  bool side = false;
  for (int k = 0; k < 3; ++k) side = side || std::abs(R(2, k)) < kMaxFaceTilt;
  return side && std::abs(R(2, up_axis(R))) >= std::cos(kMaxFaceTilt);
}

std::vector<std::uint32_t> leaning_on(const sim::World& world,
                                      const std::vector<std::uint32_t>& group) {
  constexpr double kTouch = 0.02;
  std::vector<sim::Bounds> held;
  for (const auto& box : world.boxes)
    if (std::find(group.begin(), group.end(), box.id) != group.end())
      held.push_back(sim::bounds(box));
  std::vector<std::uint32_t> out;
  for (const auto& box : world.boxes) {
    if (has_sealable_face(box) || std::find(group.begin(), group.end(), box.id) != group.end())
      continue;
    const sim::Bounds b = sim::bounds(box);
    if (std::any_of(held.begin(), held.end(),
                    [&](const sim::Bounds& h) { return sim::within(b, h, kTouch); }))
      out.push_back(box.id);
  }
  return out;
}

std::vector<PickCandidate> pick_candidates(const sim::World& world, const sim::SceneAnalysis& scene,
                                           sim::Action action, const sim::ObservationParams& obs,
                                           const sim::RobotModel& robot, const Geometry& g,
                                           const sim::JointVector& current, std::size_t max_count,
                                           const std::unordered_set<std::uint32_t>& most_cups,
                                           std::vector<PickRejection>* rejected) {
  using namespace pick;
  const PickScene s = query_scene(world, scene, action, obs, robot, g, current);
  std::vector<Ranked> candidates;
  for (std::size_t i = 0; i < s.size(); ++i) {
    if (!s.in_region[i]) continue;
    const std::uint32_t id = world.boxes[i].id;
    if (!s.faces[i]) {
      if (rejected) rejected->push_back({id, to_string(Refusal{Refusal::Kind::kNoFace})});
      continue;
    }
    const std::vector<bool> stacked = stacked_on(s, i);
    const bool fewer = most_cups.count(id) > 0;
    // The face square to the robot first; where nothing can be taken
    // through it, another side face that still looks towards the robot (a
    // box turned in a heap), the box alone. What the caller is told if no
    // face gives a candidate: why the first was refused.
    std::optional<Refusal> first_refusal;
    bool taken = false;
    const auto faces = faces_to_try(s, i);
    for (std::size_t f = 0; f < faces.size() && !taken; ++f) {
      const Approach a = approach(s, g, i, faces[f], f > 0);
      std::optional<Refusal> refused;
      const auto grip = best_grip(s, g, a, stacked, fewer, rejected ? &refused : nullptr);
      if (!grip) {
        if (!first_refusal) first_refusal = refused;
        continue;
      }
      PickCandidate c = make_candidate(s, g, a, *grip);
      if (const auto why = reach_refusal(robot, c, current)) {
        if (!first_refusal) first_refusal = why;
        continue;
      }
      candidates.push_back(ranked(s, i, std::move(c)));
      taken = true;
    }
    if (!taken && rejected)
      rejected->push_back({id, first_refusal ? to_string(*first_refusal) : std::string()});
  }
  return rank(std::move(candidates), max_count);
}

std::vector<sim::PlateTarget> dropoff_targets(const sim::World& world,
                                              const std::vector<std::uint32_t>& held,
                                              const sim::RobotModel& robot, const Geometry& g,
                                              const sim::JointVector& at, std::size_t max_count) {
  // The held load's extents (all the boxes the plate holds together):
  // along the plate's normal (depth: it sticks out of the plate by that
  // much), across it, and its height.
  double depth = 0.3, across = 0.3, height = 0.3;
  std::optional<sim::Bounds> load;
  for (const auto& box : world.boxes) {
    if (std::find(held.begin(), held.end(), box.id) == held.end()) continue;
    const auto bb = sim::bounds(box);
    if (!load) {
      load = bb;
      continue;
    }
    load->x0 = std::min(load->x0, bb.x0);
    load->x1 = std::max(load->x1, bb.x1);
    load->y0 = std::min(load->y0, bb.y0);
    load->y1 = std::max(load->y1, bb.y1);
    load->z0 = std::min(load->z0, bb.z0);
    load->z1 = std::max(load->z1, bb.z1);
  }
  if (load) {
    depth = std::max(depth, load->x1 - load->x0);
    across = std::max(across, load->y1 - load->y0);
    height = std::max(height, load->z1 - load->z0);
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
                                    sim::Action action, const Geometry& g, double scoop_extension) {
  constexpr double kOnFloor = 0.05;  // m, a box bottom this low lies on the floor
  constexpr double kStrayGap = 0.5;  // m of bare floor that ends a low sweep's stretch
  const double tip = g.conveyor_length + scoop_extension + g.scoop_lip;  // ahead of base_x
  const double deepest = world.trailer.depth - kMargin;
  std::unordered_set<std::uint32_t> front(scene.front_pile.begin(), scene.front_pile.end());
  std::unordered_set<std::uint32_t> wall(scene.first_wall.begin(), scene.first_wall.end());
  // The nearest face of what is in front between heights z0 and z1.
  auto nearest_between = [&](double z0, double z1) {
    double x = std::numeric_limits<double>::infinity();
    for (const auto& box : world.boxes) {
      if (!front.count(box.id) && !wall.count(box.id)) continue;
      const auto b = sim::bounds(box);
      if (b.z0 < z1 && b.z1 > z0) x = std::min(x, b.x0);
    }
    return x;
  };
  SweepPlan p;
  double near = std::numeric_limits<double>::infinity(), far = -near, top = 0.0;
  switch (sim::height(action)) {
    case sim::Height::kLow: {
      // The floor layer's nearest stretch: boxes strayed towards the door
      // are swept on their own, not driven through to the pile beyond them
      // (where the base would stall with them on the scoop).
      std::vector<std::pair<double, double>> floor;
      for (const auto& box : world.boxes) {
        const auto b = sim::bounds(box);
        if (front.count(box.id) && b.z0 <= kOnFloor) floor.emplace_back(b.x0, b.x1);
      }
      if (floor.empty()) return std::nullopt;
      std::sort(floor.begin(), floor.end());
      near = floor.front().first;
      far = floor.front().second;
      double next = std::numeric_limits<double>::infinity();
      for (const auto& [x0, x1] : floor) {
        if (x0 > far + kStrayGap) {
          next = x0;
          break;
        }
        far = std::max(far, x1);
      }
      // What the scoop pushes ahead gets all the room there is to climb
      // onto it: up to just short of the next stretch.
      far = std::isfinite(next) ? next - g.nose_clearance : far + g.sweep_overshoot;
      // What lies on the floor layer rides up with it.
      p.swept = scene.front_pile;
      if (!scene.first_wall.empty()) far = std::min(far, scene.wall_near_x - kMargin);
      break;
    }
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
      // The scoop's tip about halfway up what is in front, driven in past its
      // face at the scoop's height: a column leaning out towards the robot
      // stands further in there than its overhanging top (A2 s7, 16°: driven
      // in only past the top's face, the scoop met nothing).
      p.lift = std::clamp(top / 2 - g.nose_top, 0.0, g.nose_lift_max);
      p.lower_at_end = true;
      if (const double face = nearest_between(p.lift, p.lift + g.nose_top); std::isfinite(face))
        far = face + g.sweep_high_in;
      else
        far = near + g.sweep_high_in;
      break;
  }
  // The nose comes down (or up to its lift) before it drives in: short of
  // every box of the scene at its height too, not only of those it sweeps
  // (A2 seed 12: a floor layer behind the wall's foot, and the lowered scoop
  // met the wall).
  near = std::min(near, nearest_between(p.lift, p.lift + g.nose_top + kMargin));
  // The sweep starts just short of what it sweeps, wherever the base stands:
  // what rides out on the scoop is carried back that far, not across the
  // trailer.
  p.start_base_x = near - tip - g.nose_clearance;
  p.end_base_x = std::max(p.start_base_x, std::min(far, deepest) - tip);
  return p;
}

}  // namespace plr::actions
