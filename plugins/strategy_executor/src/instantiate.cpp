#include "instantiate.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <unordered_set>

namespace plr::executor {

namespace {

constexpr double kMargin = 0.03;     // m, footprint shrink and clearances
constexpr double kClearance = 0.02;  // m, the plate's distance to boxes it must not touch
constexpr double kSlide = 0.05;      // m, steps of the plate off the face's centre
constexpr double kCovered = 0.1;     // m, the plate's centre stays this far inside the face
constexpr double kFlush = 0.004;     // m a neighbour may stand out of the face unnoticed
// The cups' rims stay this far inside the plate's outline (plus kClearance),
// and grip faces up to this far below it.
constexpr double kCupInset = 0.04;
constexpr double kCupReach = 0.03;

sim::Height height_class(double top, double mid, double high) {
  if (top >= high) return sim::Height::kHigh;
  if (top >= mid) return sim::Height::kMid;
  return sim::Height::kLow;
}

sim::Side side_of(double y, const sim::World& w, const sim::ObservationParams& obs) {
  const double band = obs.side_band * w.trailer.width / 2;
  return y > band ? sim::Side::kLeft : (y < -band ? sim::Side::kRight : sim::Side::kCenter);
}

bool reachable(const sim::RobotModel& robot, const sim::PlateTarget& t, const sim::Config& seed) {
  return !robot.armIk(t, seed).empty();
}

}  // namespace

std::vector<PickCandidate> pick_candidates(const sim::World& world, const sim::SceneAnalysis& scene,
                                           sim::Action action, const sim::ObservationParams& obs,
                                           const sim::RobotModel& robot, const Geometry& g,
                                           const sim::Config& current, std::size_t max_count) {
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
    int mismatches;
    double x_bin, top, centre_distance;
  };
  std::vector<Ranked> ranked;
  for (auto i : members) {
    const auto& box = world.boxes[i];
    const bool is_wall = wall.count(box.id) > 0;
    const double y = box.pose.translation().y();
    const auto cls = is_wall ? height_class(b[i].z1, obs.wall_mid, obs.wall_high)
                             : height_class(b[i].z1, obs.pile_mid, obs.pile_high);
    const int mismatches =
        (cls != sim::height(action)) + (side_of(y, world, obs) != sim::side(action));

    // Plate centred on the face, kept inside the trailer and off the floor.
    const double ylim = world.trailer.width / 2 - g.plate_half_width - kMargin;
    const double zc = std::clamp((b[i].z0 + b[i].z1) / 2, g.plate_half_height + kMargin,
                                 world.trailer.height - g.plate_half_height - kMargin);
    const Eigen::Vector3d face(b[i].x0, std::clamp(y, -ylim, ylim), zc);
    // Base: the arm at its preferred reach, the lowered nose short of every box.
    const double by_reach = face.x() - g.pick_reach + g.arm_yaw_offset;
    const double by_nose = nearest - g.conveyor_length - g.nose_clearance;
    // A plate low enough to meet the lowered nose stays ahead of its tip.
    const double by_plate =
        face.z() - g.plate_half_height < g.nose_top
            ? face.x() - g.pregrasp_distance - g.conveyor_length - g.nose_clearance
            : by_reach;
    const double base_x = std::min({by_reach, by_nose, by_plate});
    const double yaw = std::atan2(face.y(), face.x() - (base_x - g.arm_yaw_offset));
    sim::Config at = current;
    at[sim::kBaseX] = base_x;
    // The plate is wider than many boxes: the corridor it moves through to
    // the face (or down onto the top) must be clear of every other box. Where
    // a neighbour is in the way, the plate slides off centre as long as it
    // still covers most of the face.
    const double pw = g.plate_half_width, ph = g.plate_half_height;
    const double top_x = (b[i].x0 + b[i].x1) / 2;
    // Facing down, the plate turns with the arm's yaw: its footprint's bounds.
    const double top_yaw = std::abs(std::atan2(y, top_x - (base_x - g.arm_yaw_offset)));
    const double hx = ph * std::cos(top_yaw) + pw * std::sin(top_yaw);
    const double hy = pw * std::cos(top_yaw) + ph * std::sin(top_yaw);
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
    const double half_w = (b[i].y1 - b[i].y0) / 2, half_d = (b[i].x1 - b[i].x0) / 2;
    auto slides = [&](double half_extent) {
      std::vector<double> out{0.0};
      for (double d = kSlide; d <= half_extent - kCovered + 1e-9; d += kSlide) {
        out.push_back(d);
        out.push_back(-d);
      }
      return out;
    };
    // The face corridor ends at the plate's surface in the grasp: neighbours
    // flush with the face do not block it, ones standing out do.
    const double half_h = (b[i].z1 - b[i].z0) / 2;
    const double corridor_end = face.x() - g.grasp_gap - kClearance + kFlush;
    std::optional<Eigen::Vector2d> face_offset;
    for (const double dz : slides(half_h)) {
      for (const double dy : slides(half_w)) {
        const double py = std::clamp(face.y() + dy, -ylim, ylim);
        const double pz =
            std::clamp(face.z() + dz, ph + kMargin, world.trailer.height - ph - kMargin);
        if (clear(face.x() - g.pregrasp_distance, corridor_end, py - pw, py + pw, pz - ph,
                  pz + ph)) {
          face_offset = Eigen::Vector2d(py - face.y(), pz - face.z());
          break;
        }
      }
      if (face_offset) break;
    }
    std::optional<Eigen::Vector2d> top_offset;
    for (const double dx : slides(half_d)) {
      for (const double dy : slides(half_w)) {
        const double px = top_x + dx, py = y + dy;
        const bool inside = std::abs(py) + hy <= world.trailer.width / 2 - kMargin &&
                            px + hx <= world.trailer.depth - kMargin;
        // Nothing above in the plate's way down, and no neighbour's top
        // under its cups (they would grip it too).
        if (inside &&
            clear(px - hx, px + hx, py - hy, py + hy, b[i].z1 + kMargin,
                  b[i].z1 + g.pregrasp_distance) &&
            clear(px - hx + kCupInset, px + hx - kCupInset, py - hy + kCupInset,
                  py + hy - kCupInset, b[i].z1 - kCupReach, b[i].z1 + kMargin)) {
          top_offset = Eigen::Vector2d(dx, dy);
          break;
        }
      }
      if (top_offset) break;
    }
    // Front grasps lift the box off what it rests on and over the lowered nose.
    const double lift = std::max(g.retract_lift, g.nose_top + kMargin - b[i].z0);
    auto add = [&](bool from_top) {
      PickCandidate c;
      c.box = box.id;
      c.matches = mismatches == 0;
      c.base_x = base_x;
      c.from_top = from_top;
      if (from_top) {
        const Eigen::Vector3d top(top_x + top_offset->x(), y + top_offset->y(), b[i].z1);
        c.grasp = {top + Eigen::Vector3d(0, 0, g.grasp_gap), M_PI / 2};
        c.pregrasp = {top + Eigen::Vector3d(0, 0, g.pregrasp_distance), M_PI / 2};
        c.retract = {c.pregrasp.position + Eigen::Vector3d(0, 0, g.retract_lift), M_PI / 2};
      } else {
        // Off the arm's axis the plate meets the face at an angle: keep its near edge off it.
        const double gap = g.grasp_gap + g.plate_half_width * std::sin(std::abs(yaw));
        const Eigen::Vector3d at_face =
            face + Eigen::Vector3d(0, face_offset->x(), face_offset->y());
        c.grasp = {at_face - Eigen::Vector3d(gap, 0, 0), 0.0};
        c.pregrasp = {at_face - Eigen::Vector3d(g.pregrasp_distance, 0, 0), 0.0};
        // Lifted off what it rests on (and over the lowered nose), then pulled
        // out until clear of it: the drop-off move after that swings freely.
        c.lift = {c.grasp.position + Eigen::Vector3d(0, 0, lift), 0.0};
        c.retract = {c.lift->position - Eigen::Vector3d(b[i].x1 - b[i].x0 + kMargin, 0, 0), 0.0};
      }
      if (!reachable(robot, c.grasp, at) || !reachable(robot, c.pregrasp, at)) return;
      ranked.push_back(
          {c, mismatches, std::floor((b[i].x0 - nearest) / 0.2), b[i].z1, std::abs(y)});
    };
    // A box taken by its face is lifted before it comes out: nothing may rest on it.
    const bool liftable = clear(b[i].x0 + kMargin, b[i].x1 - kMargin, b[i].y0 + kMargin,
                                b[i].y1 - kMargin, b[i].z1, b[i].z1 + lift);
    if (face_offset && liftable && std::abs(yaw) <= g.max_face_yaw) add(false);
    if (top_offset) add(true);
  }
  std::stable_sort(ranked.begin(), ranked.end(), [](const Ranked& a, const Ranked& b) {
    if (a.mismatches != b.mismatches) return a.mismatches < b.mismatches;
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
                                              const sim::Config& at, bool from_top,
                                              std::size_t max_count) {
  // The held load sticks out of the plate by its depth (front grasp) or
  // hangs below it by its height (top grasp).
  double depth = 0.3, height = 0.3;
  for (const auto& box : world.boxes) {
    if (std::find(held.begin(), held.end(), box.id) == held.end()) continue;
    const auto bb = sim::bounds(box);
    depth = std::max(depth, bb.x1 - bb.x0);
    height = std::max(height, bb.z1 - bb.z0);
  }
  // The folded arm cannot bend enough to reach right over the nose hinge, so
  // look further along the conveyor and higher up for IK solutions.
  std::vector<sim::PlateTarget> out;
  const double base_x = at[sim::kBaseX];
  for (double extra_z : {0.0, 0.2, 0.4}) {
    // The box's centre `ahead` of base_x, the whole box over the conveyor.
    for (double ahead = g.dropoff_ahead; ahead <= g.conveyor_length - depth / 2 + 1e-9;
         ahead += 0.1) {
      sim::PlateTarget t;
      if (from_top)
        t = {{base_x + ahead, 0.0, g.dropoff_bottom + extra_z + height + g.grasp_gap}, M_PI / 2};
      else
        t = {{base_x + ahead - depth / 2, 0.0, g.dropoff_bottom + extra_z + height / 2}, 0.0};
      if (reachable(robot, t, at)) out.push_back(t);
      if (out.size() >= max_count) return out;
    }
  }
  return out;
}

std::optional<SweepPlan> sweep_plan(const sim::SceneAnalysis& scene, sim::Action action,
                                    const Geometry& g, double scoop_extension,
                                    const sim::Config& current, double trailer_depth) {
  if (scene.front_pile.empty()) return std::nullopt;
  const double tip = g.conveyor_length + scoop_extension;  // ahead of base_x
  SweepPlan p;
  p.swept = scene.front_pile;
  p.start_base_x = std::min(current[sim::kBaseX], scene.pile_near_x - tip - g.nose_clearance);
  double far = scene.pile_far_x + g.sweep_overshoot;
  if (!scene.first_wall.empty()) far = std::min(far, scene.wall_near_x - kMargin);
  far = std::min(far, trailer_depth - kMargin);
  p.end_base_x = std::max(p.start_base_x, far - tip);
  // Higher sweeps skim higher: the scoop rides over what lies flat.
  switch (sim::height(action)) {
    case sim::Height::kLow:
      p.lift = 0.0;
      break;
    case sim::Height::kMid:
      p.lift = 0.05;
      break;
    case sim::Height::kHigh:
      p.lift = 0.1;
      break;
  }
  return p;
}

}  // namespace plr::executor
