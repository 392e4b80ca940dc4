#include "plr/actions/instantiate.hpp"

#include "footprint.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <tuple>
#include <unordered_set>

#include <fmt/format.h>

namespace plr::actions {

namespace {

constexpr double kMargin = 0.03;     // m, footprint shrink and clearances
constexpr double kClearance = 0.02;  // m, the plate's distance to boxes it must not touch
// m, the plate's lowest edge above the floor: its bottom row of cups then
// seals on a box 9.5 cm high lying flat on the floor.
constexpr double kFloorGap = 0.015;
constexpr double kSlide = 0.05;   // m, steps of the plate off the face's centre
constexpr double kCovered = 0.1;  // m, the plate's centre stays this far inside the face
// m, the nearest pre-grasp: the plate comes down between the face and
// what stands in front of it.
constexpr double kMinPregrasp = 0.08;
constexpr double kProud = 0.015;  // m a neighbour may stand out of the face (the cups reach 2 cm)
// rad: a face tilted further than this from the vertical is not taken (the
// cups seal up to about 0.26 rad).
constexpr double kMaxFaceTilt = 0.2;
constexpr double kSquare = 0.03;  // rad: faces turned less than this are taken square to the axis
// rad: the furthest off the trailer's axis a face is approached (the wrist
// turns the plate that far).
constexpr double kMaxSideFace = 1.2;
// m past the cups' reach at which a face still counts as sealed on: a
// settled box leans a little, and a box outside the region the plate might
// take must keep the pose from being chosen.
constexpr double kSealMargin = 0.01;
// m: the highest lift off a tilted support (a box sunk deeper into what is
// under it is not pulled out), and what it clears the support's top by
// beyond kClearance.
constexpr double kMaxLift = 0.15;
// m between a box's top and the bottom of one resting on it (a settled stack).
constexpr double kStacked = 0.03;
constexpr double kLiftSlack = 0.005;
// Boxes of a wall that may rest, unsealed, on a group the plate takes: one
// rides on the load's top as it is lifted and pulled out (more would topple
// off it), which is what makes a wall's third row from the top a pick.
constexpr std::size_t kMaxRiders = 1;

sim::Height height_class(double top, double mid, double high) {
  if (top >= high) return sim::Height::kHigh;
  if (top >= mid) return sim::Height::kMid;
  return sim::Height::kLow;
}

sim::Side side_of(double y, const sim::World& w, const sim::ObservationParams& obs) {
  const double band = obs.side_band * w.trailer.width / 2;
  return y > band ? sim::Side::kLeft : (y < -band ? sim::Side::kRight : sim::Side::kCenter);
}

// The plate link's body behind its suction surface (its collision box along x).
double plate_body_depth(const sim::RobotModel& robot) {
  double depth = 0.0;
  for (const auto& shape : robot.links()[static_cast<std::size_t>(robot.plate_link())].shapes)
    if (shape.type == sim::CollisionShape::Type::kBox) depth = std::max(depth, shape.size.x());
  return depth;
}

bool reachable(const sim::RobotModel& robot, const sim::PlateTarget& t,
               const sim::JointVector& seed) {
  return !robot.arm_ik(t, seed).empty();
}

// The box axis nearest the vertical.
int up_axis(const Eigen::Matrix3d& R) {
  int up = 0;
  for (int k = 1; k < 3; ++k)
    if (std::abs(R(2, k)) > std::abs(R(2, up))) up = k;
  return up;
}

// A box axis made horizontal and unit, pointing into the trailer (+x).
Eigen::Vector3d inward(Eigen::Vector3d axis) {
  axis.z() = 0;
  return axis.normalized() * (axis.x() < 0 ? -1.0 : 1.0);
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

std::vector<std::uint32_t> boxes_on_robot(const sim::World& world, const sim::RobotModel& robot,
                                          const sim::JointVector& q,
                                          const std::vector<std::uint32_t>& held) {
  constexpr double kOffFloor = 0.02;  // m: a box touching the robot this high lies on it
  constexpr double kUnder = 0.03;     // m: a box whose top is this close under another carries it
  std::vector<std::uint32_t> out;
  const auto touching = boxes_touching(world, robot, q);
  for (const auto& box : world.boxes) {
    const sim::Bounds b = sim::bounds(box);
    if (b.z0 <= kOffFloor ||
        std::find(touching.begin(), touching.end(), box.id) == touching.end() ||
        std::find(held.begin(), held.end(), box.id) != held.end())
      continue;
    // A box standing on other boxes (a wall box beside the plate) is the
    // trailer's, not the robot's.
    const bool on_boxes = std::any_of(world.boxes.begin(), world.boxes.end(), [&](const auto& o) {
      const sim::Bounds u = sim::bounds(o);
      return o.id != box.id && u.z1 < b.z0 + kUnder && u.z1 > b.z0 - kUnder && u.x0 < b.x1 &&
             b.x0 < u.x1 && u.y0 < b.y1 && b.y0 < u.y1;
    });
    if (!on_boxes) out.push_back(box.id);
  }
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
  std::unordered_set<std::uint32_t> wall(scene.first_wall.begin(), scene.first_wall.end());
  std::unordered_set<std::uint32_t> front(scene.front_pile.begin(), scene.front_pile.end());
  const std::size_t count = world.boxes.size();
  std::vector<sim::Bounds> b(count);
  // The nearest box the lowered nose must stay short of: not one above the
  // nose (lying on the robot's arm, or leaning out over it), nor one lying
  // on the robot, which rides along with it (A1 s2: a box left on the arm
  // after a shake kept the base 2.5 m short of everything).
  const std::vector<std::uint32_t> on_robot = boxes_on_robot(world, robot, current);
  double nearest = std::numeric_limits<double>::infinity();
  // The action's region: boxes of the first wall or front pile of its
  // height class (a box's top against the wall or pile thresholds) and
  // third of the width.
  std::vector<bool> in_region(count, false);
  for (std::size_t i = 0; i < count; ++i) {
    const auto& box = world.boxes[i];
    b[i] = sim::bounds(box);
    if (b[i].z0 < g.nose_top + kMargin &&
        std::find(on_robot.begin(), on_robot.end(), box.id) == on_robot.end())
      nearest = std::min(nearest, b[i].x0);
    const bool is_wall = wall.count(box.id) > 0;
    if (!is_wall && !front.count(box.id)) continue;
    const auto cls = is_wall ? height_class(b[i].z1, obs.wall_mid, obs.wall_high)
                             : height_class(b[i].z1, obs.pile_mid, obs.pile_high);
    in_region[i] = cls == sim::height(action) &&
                   side_of(box.pose.translation().y(), world, obs) == sim::side(action);
  }

  // The front face: of the box's horizontal axes, the one nearest the
  // trailer's axis gives the face's normal and the plate's yaw (the wrist
  // turns the plate square to it). A box tilted on an edge has no face the
  // vertical plate can seal on.
  struct Face {
    Eigen::Vector3d n, lateral, centre;
    double half_d = 0, half_w = 0, half_up = 0;
  };
  // The face whose normal is box axis `axis` (n: that axis made horizontal,
  // pointing into the trailer).
  auto face_along = [](const sim::Box& box, int axis, int up, const Eigen::Vector3d& n) {
    Face f;
    f.n = n;
    f.lateral = Eigen::Vector3d(-n.y(), n.x(), 0.0);
    f.half_d = box.size[axis] / 2;
    f.half_w = box.size[3 - axis - up] / 2;
    f.half_up = box.size[up] / 2;
    f.centre = box.pose.translation() - f.half_d * n;
    return f;
  };
  auto face_of = [&](std::size_t i) -> std::optional<Face> {
    const auto& box = world.boxes[i];
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
  };
  std::vector<std::optional<Face>> faces(count);
  for (std::size_t i = 0; i < count; ++i)
    if (wall.count(world.boxes[i].id) || front.count(world.boxes[i].id)) faces[i] = face_of(i);
  // The face square to the robot, then the other side face of a box turned
  // well off the trailer's axis where it still looks towards the robot (at
  // most kMaxSideFace off the axis).
  auto faces_to_try = [&](std::size_t i) {
    std::vector<Face> out{*faces[i]};
    const auto& box = world.boxes[i];
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
  };

  auto near = [](double a0, double a1, double b0, double b1) {
    return a0 - kClearance < b1 && b0 < a1 + kClearance;
  };
  std::vector<Polygon> outline(count);
  for (std::size_t i = 0; i < count; ++i) outline[i] = footprint(world.boxes[i]);
  // Whether the space over `area` from z0 to z1 is free of every box but
  // those of `group`. Outlines that only touch (flush neighbours) do not
  // count: kMargin of overlap does.
  // Unless `leaning_too`, a box tilted on an edge (no face the plate seals
  // on) does not count: nothing can pick it, and it slides off what comes
  // out under it.
  // Returns the first box in the way.
  auto in_the_way = [&](const std::vector<std::size_t>& group, const Polygon& area, double z0,
                        double z1, bool leaning_too) -> std::optional<std::size_t> {
    for (std::size_t j = 0; j < count; ++j) {
      if (std::find(group.begin(), group.end(), j) == group.end() &&
          (leaning_too || has_sealable_face(world.boxes[j])) && near(z0, z1, b[j].z0, b[j].z1) &&
          separation(area, outline[j]) < -kMargin)
        return j;
    }
    return std::nullopt;
  };
  // The boxes resting on `group` that may ride on it, unsealed, as it comes
  // out: upright wall boxes, at most kMaxRiders, each resting on the group
  // alone and with its centre over it (else it stays behind, or tips off
  // while the load is lifted). None where any other box rests on the group:
  // it keeps the group in place.
  auto riders_on = [&](const std::vector<std::size_t>& group, double lift) {
    auto in_group = [&](std::size_t j) {
      return std::find(group.begin(), group.end(), j) != group.end();
    };
    auto rests_on = [&](std::size_t top, std::size_t under) {
      return std::abs(b[top].z0 - b[under].z1) < kStacked &&
             separation(outline[under], outline[top]) < -kMargin;
    };
    std::vector<std::size_t> out;
    for (std::size_t k = 0; k < count; ++k) {
      if (in_group(k) ||
          !std::any_of(group.begin(), group.end(), [&](std::size_t j) { return rests_on(k, j); }))
        continue;
      const Eigen::Vector3d c = world.boxes[k].pose.translation();
      bool carried =
          wall.count(world.boxes[k].id) > 0 && has_sealable_face(world.boxes[k]) &&
          b[k].z1 + lift + kClearance < world.trailer.height &&
          std::any_of(group.begin(), group.end(), [&](std::size_t j) {
            return b[j].x0 <= c.x() && c.x() <= b[j].x1 && b[j].y0 <= c.y() && c.y() <= b[j].y1;
          });
      for (std::size_t m = 0; m < count && carried; ++m)
        carried = m == k || in_group(m) || !rests_on(k, m);
      if (!carried || out.size() == kMaxRiders) return std::vector<std::size_t>{};
      out.push_back(k);
    }
    return out;
  };
  const double pw = g.plate_half_width(), ph = g.plate_half_height();
  const double plate_depth = plate_body_depth(robot);

  struct Ranked {
    PickCandidate c;
    double x_bin, top, centre_distance;
  };
  std::vector<Ranked> ranked;
  for (std::size_t i = 0; i < count; ++i) {
    if (!in_region[i]) continue;
    const auto& box = world.boxes[i];
    if (!faces[i]) {
      if (rejected) rejected->push_back({box.id, "no face the plate seals on"});
      continue;
    }
    // The boxes of the wall or pile stacked on this one, each resting on it
    // or on one of them (those the plate does not seal on keep it in place).
    std::vector<bool> stacked_on_i(count, false);
    std::vector<std::size_t> stack{i};
    for (std::size_t next = 0; next < stack.size(); ++next) {
      const std::size_t k = stack[next];
      for (std::size_t j = 0; j < count; ++j)
        if (j != i && !stacked_on_i[j] && std::abs(b[j].z0 - b[k].z1) < kStacked &&
            (wall.count(world.boxes[j].id) || front.count(world.boxes[j].id)) &&
            separation(outline[k], outline[j]) < -kMargin) {
          stacked_on_i[j] = true;
          stack.push_back(j);
        }
    }
    // The face square to the robot first; where nothing can be taken
    // through it, another side face that still looks towards the robot
    // (a box turned in a heap), the box alone.
    std::string first_refusal;
    bool taken = false;
    const auto alternatives = faces_to_try(i);
    for (std::size_t a = 0; a < alternatives.size(); ++a) {
      const Face& f = alternatives[a];
      const bool alternative = a > 0;
      auto member_face = [&](std::size_t j) -> const Face& { return j == i ? f : *faces[j]; };
      const Eigen::Vector3d& n = f.n;
      const Eigen::Vector3d& lateral = f.lateral;
      const Eigen::Vector3d& face_centre = f.centre;
      const double plate_yaw = std::atan2(n.y(), n.x());
      const double half_w = f.half_w, half_up = f.half_up;
      const double y = box.pose.translation().y();

      // Plate centred on the face, kept inside the trailer and off the floor;
      // turned, its body's back corner reaches further out.
      const double ylim =
          world.trailer.width / 2 - pw * std::abs(n.x()) - plate_depth * std::abs(n.y()) - kMargin;
      const double zc =
          std::clamp(face_centre.z(), ph + kFloorGap, world.trailer.height - ph - kMargin);
      const Eigen::Vector3d face(face_centre.x(), face_centre.y(), zc);
      // The plate is wider than many boxes: the corridor it moves through to
      // the face must be clear of every other box. Where a neighbour is in the
      // way, the plate slides off centre as long as it still covers most of
      // the face.
      auto slides = [&](double half_extent) {
        std::vector<double> out{0.0};
        for (double d = kSlide; d <= half_extent - kCovered + 1e-9; d += kSlide) {
          out.push_back(d);
          out.push_back(-d);
        }
        return out;
      };
      // The plate moves in to the face through a corridor (its outline along
      // the face's normal) that must be free. It stops grasp_gap short of the
      // face; a settled wall is not flush, so also grasp_gap short of any
      // neighbour in the corridor that stands out. The cups reach the face
      // across kProud of extra gap.
      const double half_h = (b[i].z1 - b[i].z0) / 2;
      auto plate_at = [&](double dy, double dz) {
        Eigen::Vector3d p = face + dy * lateral;
        p.y() = std::clamp(p.y(), -ylim, ylim);
        p.z() = std::clamp(face.z() + dz, ph + kFloorGap, world.trailer.height - ph - kMargin);
        return p;
      };
      auto cups_on = [&](std::size_t j, const Eigen::Vector3d& p) {
        const Face& fj = member_face(j);
        return covered_cups(g, fj.half_w, fj.half_up, (p - fj.centre).dot(lateral),
                            p.z() - fj.centre.z());
      };
      // Plate offsets (across, up) from the face's centre, in the order tried:
      // on the face, then centred on its edges, where it may take the
      // neighbours there too.
      std::vector<std::pair<double, double>> offsets;
      for (const double dz : slides(half_h))
        for (const double dy : slides(half_w)) offsets.emplace_back(dy, dz);
      for (const double dz : {0.0, half_up, -half_up})
        for (const double dy : {0.0, half_w, -half_w})
          if (dy != 0.0 || dz != 0.0) offsets.emplace_back(dy, dz);
      const bool fewer = most_cups.count(box.id) > 0;
      if (fewer) {
        // Half a cup pitch off centre puts two columns (or rows) of cups on a
        // face the centred grid covers with one.
        const double across = 0.5 * g.cups.extent.y() / g.cups.cups_y;
        const double up = 0.5 * g.cups.extent.x() / g.cups.cups_x;
        for (const double dz : {0.0, up, -up})
          for (const double dy : {0.0, across, -across}) offsets.emplace_back(dy, dz);
      }
      // Each plate pose the corridor allows: the boxes it seals on (all in the
      // region, else the pose is not taken), which must come out together.
      struct Grip {
        std::vector<std::size_t> group;  // the box first
        std::vector<std::size_t> riders;
        std::vector<int> cups;
        Eigen::Vector3d at_face;
        double back = 0;      // plate surface to the face at the grasp
        double pregrasp = 0;  // plate to the face before the approach
        double lift = 0, out_depth = 0;
      };
      std::optional<Grip> best;
      // Why the plate centred on the face was not taken: what the caller is
      // told if no other pose is taken either. Worded only if asked for.
      std::string refused;
      auto refuse = [&](const auto& why) {
        if (rejected && refused.empty()) refused = why();
      };
      for (const auto& [dy, dz] : offsets) {
        const Eigen::Vector3d p = plate_at(dy, dz);
        // In the plate's corridor, what reaches the face stops the plate short
        // of it (by more than the cups reach, the pose is not taken); what
        // stands further out leaves the plate less room before the face (a
        // nearer pre-grasp; too little room, and the pose is not taken).
        double back = g.grasp_gap, room = g.pregrasp_distance;
        std::size_t proud = count, before = count;
        for (std::size_t j = 0; j < count; ++j) {
          if (j == i || !near(p.z() - ph, p.z() + ph, b[j].z0, b[j].z1)) continue;
          const auto span = span_in_band(outline[j], p.head<2>(), n.head<2>(), pw);
          if (!span || span->min >= 0.0) continue;
          if (span->max > -kProud - kClearance) {
            if (g.grasp_gap - span->min > back) proud = j;
            back = std::max(back, g.grasp_gap - span->min);
          } else if (-span->max - kClearance - plate_depth < room) {
            // The plate's body stands behind its surface.
            before = j;
            room = -span->max - kClearance - plate_depth;
          }
        }
        if (back - g.grasp_gap > kProud) {
          refuse([&] {
            return fmt::format("box {} stands out before its face", world.boxes[proud].id);
          });
          continue;
        }
        if (room < kMinPregrasp) {
          refuse([&] {
            return fmt::format("box {} leaves the plate no room before it", world.boxes[before].id);
          });
          continue;
        }
        Grip grip;
        grip.at_face = p;
        grip.back = back;
        grip.pregrasp = room;
        const Eigen::Vector3d surface = p - back * n;
        const int own = cups_on(i, p);
        if (own == 0) {
          refuse([] { return std::string("no whole cup on its face"); });
          continue;
        }
        grip.group.push_back(i);
        grip.cups.push_back(own);
        // Every other box of the region whose face the cups reach (with a
        // margin: a settled box may lean) and that whole cups cover, and the
        // boxes of the wall or pile stacked on the box itself that they cover
        // too: the stack comes out together (the plate is as high as two
        // typical boxes). The cups over any other box stay closed
        // (cups_open): it stays.
        for (std::size_t j = 0; j < count; ++j) {
          if (j == i || alternative || !(in_region[j] || stacked_on_i[j]) || !faces[j] ||
              !near(p.y() - pw, p.y() + pw, b[j].y0, b[j].y1) ||
              !near(p.z() - ph, p.z() + ph, b[j].z0, b[j].z1))
            continue;
          const double gap = (faces[j]->centre - surface).dot(n);
          if (std::abs(gap) > g.cups.reach + kSealMargin) continue;
          const int k = cups_on(j, p);
          if (k == 0) continue;
          grip.group.push_back(j);
          grip.cups.push_back(k);
        }
        // The group is lifted off what it rests on (and over the lowered
        // nose) before it comes out: nothing but its own boxes may rest on it.
        double z0 = b[i].z0, depth = 0;
        for (auto j : grip.group) {
          z0 = std::min(z0, b[j].z0);
          depth = std::max(depth, b[j].x1 - b[j].x0);
        }
        grip.lift = std::max(g.retract_lift, g.nose_top + kMargin - z0);
        // A tilted box rests on a tilted top (a leaning column): their
        // outlines overlap in height by more than a flat stack's, and the
        // group comes out only once lifted clear of what it rests on.
        for (auto j : grip.group)
          for (std::size_t k = 0; k < count; ++k)
            if (std::find(grip.group.begin(), grip.group.end(), k) == grip.group.end() &&
                b[k].z0 < b[j].z0 && separation(outline[j], outline[k]) < -kMargin)
              grip.lift = std::max(grip.lift,
                                   std::min(kMaxLift, b[k].z1 - b[j].z0 + kClearance + kLiftSlack));
        grip.out_depth = std::max(2 * f.half_d, depth) + kMargin;
        grip.riders = riders_on(grip.group, grip.lift);
        std::vector<std::size_t> moving = grip.group;
        moving.insert(moving.end(), grip.riders.begin(), grip.riders.end());
        bool blocked = false;
        for (auto j : moving) {
          // Lifted, nothing may stand over it; pulled out, each box (it may be
          // wider than the plate) passes over what stands in front of it.
          // Neighbours beside it, flush with it, are not in the way.
          const auto over = in_the_way(moving, outline[j], b[j].z1, b[j].z1 + grip.lift, false);
          const auto out =
              over ? over
                   : in_the_way(moving, swept(outline[j], -grip.out_depth * n.head<2>()),
                                b[j].z0 + grip.lift, b[j].z1 + grip.lift, true);
          if (!out) continue;
          refuse([&] {
            const auto k = world.boxes[*out].id, id = world.boxes[j].id;
            return over ? fmt::format("box {} rests on box {}", k, id)
                        : fmt::format("box {} is in the way out of box {}", k, id);
          });
          blocked = true;
          break;
        }
        if (blocked) continue;
        // More boxes at once first, then more cups on the box that has the
        // fewest (the cups' force is shared by cups), then more in all; after
        // a failed grip, fewer boxes and more cups on the box itself.
        auto fewest = [](const Grip& x) { return *std::min_element(x.cups.begin(), x.cups.end()); };
        auto total = [](const Grip& x) {
          int n = 0;
          for (int k : x.cups) n += k;
          return n;
        };
        // A load with nothing riding on it first.
        auto rank = [&](const Grip& x) {
          const int n = static_cast<int>(x.group.size());
          const bool bare = x.riders.empty();
          return fewer ? std::make_tuple(bare, -n, x.cups.front(), total(x))
                       : std::make_tuple(bare, n, fewest(x), total(x));
        };
        if (!best || rank(grip) > rank(*best)) best = std::move(grip);
      }
      if (!best) {
        if (first_refusal.empty()) first_refusal = refused;
        continue;
      }
      PickCandidate c;
      c.box = box.id;
      for (auto j : best->group) c.boxes.push_back(world.boxes[j].id);
      for (auto j : best->riders) c.riders.push_back(world.boxes[j].id);
      c.box_cups = best->cups;
      c.cups = best->cups.front();
      const Eigen::Vector3d& at_face = best->at_face;
      c.grasp = {at_face - best->back * n, plate_yaw};
      // Backed off along a turned face's normal, the plate also moves sideways:
      // near a side wall, only as far as the wall lets it.
      Eigen::Vector3d pregrasp = at_face - best->pregrasp * n;
      pregrasp.y() = std::clamp(pregrasp.y(), -ylim, ylim);
      c.pregrasp = {pregrasp, plate_yaw};
      // The valves: the cup grid runs down the plate by rows, across by columns.
      const sim::SuctionPlate& grid = g.cups;
      c.cups_open.assign(static_cast<std::size_t>(grid.cups_x * grid.cups_y), false);
      for (int r = 0; r < grid.cups_x; ++r) {
        for (int k = 0; k < grid.cups_y; ++k) {
          const Eigen::Vector3d cup =
              at_face +
              (0.5 - (r + 0.5) / grid.cups_x) * grid.extent.x() * Eigen::Vector3d::UnitZ() +
              ((k + 0.5) / grid.cups_y - 0.5) * grid.extent.y() * lateral;
          c.cups_open[static_cast<std::size_t>(r * grid.cups_y + k)] =
              std::any_of(best->group.begin(), best->group.end(), [&](std::size_t j) {
                const Face& fj = member_face(j);
                return std::abs((cup - fj.centre).dot(lateral)) <= fj.half_w - grid.cup_radius &&
                       std::abs(cup.z() - fj.centre.z()) <= fj.half_up - grid.cup_radius;
              });
        }
      }
      // Base: the arm at its preferred reach, the lowered nose short of every
      // box. A plate low enough to meet the lowered nose stays
      // ahead of its tip at the pre-grasp (nose_clearance covers the plate's
      // body): turned off the trailer's axis, by its leading corner.
      const double by_reach = face.x() - g.pick_reach + g.arm_yaw_offset;
      const double by_nose = nearest - g.conveyor_length - g.nose_clearance;
      const double plate_back = c.pregrasp.position.x() - pw * std::abs(n.y());
      const double by_plate = c.pregrasp.position.z() - ph < g.nose_top
                                  ? plate_back - g.conveyor_length - g.nose_clearance
                                  : by_reach;
      c.base_x = std::min({by_reach, by_nose, by_plate});
      sim::JointVector at = current;
      at[sim::kBaseX] = c.base_x;
      // Lifted, then pulled out until clear of what it rested on: the
      // drop-off move after that swings freely.
      // A group against a side wall is lifted away from it too: dragged along
      // it, the held boxes would press into it. It moves no further than
      // halfway to the box standing beside it on the other side, which it
      // would press into instead (C s12: 3 cm into a flush neighbour).
      double x0 = b[i].x0, x1 = b[i].x1, y0 = b[i].y0, y1 = b[i].y1, z0 = b[i].z0, z1 = b[i].z1;
      for (auto j : best->group) {
        x0 = std::min(x0, b[j].x0);
        x1 = std::max(x1, b[j].x1);
        y0 = std::min(y0, b[j].y0);
        y1 = std::max(y1, b[j].y1);
        z0 = std::min(z0, b[j].z0);
        z1 = std::max(z1, b[j].z1);
      }
      const double half = world.trailer.width / 2;
      double off_wall = std::max(0.0, kMargin - (half + y0)) - std::max(0.0, kMargin - (half - y1));
      for (std::size_t j = 0; j < count && off_wall != 0.0; ++j) {
        if (std::find(best->group.begin(), best->group.end(), j) != best->group.end() ||
            !(b[j].x0 < x1 && x0 < b[j].x1 && b[j].z0 < z1 + best->lift && z0 < b[j].z1))
          continue;
        const double room = off_wall > 0 ? b[j].y0 - y1 : y0 - b[j].y1;
        const bool beside =
            off_wall > 0 ? b[j].y0 + b[j].y1 > y0 + y1 : b[j].y0 + b[j].y1 < y0 + y1;
        if (beside)
          off_wall = std::copysign(std::min(std::abs(off_wall), std::max(0.0, room / 2)), off_wall);
      }
      c.lift = {c.grasp.position + Eigen::Vector3d(0, off_wall, best->lift), plate_yaw};
      // Pulled out along a turned face's normal, the load also moves sideways:
      // no further than the side walls let it and the plate, and never pushed
      // further off a wall than the lift took it.
      Eigen::Vector3d retract = c.lift.position - best->out_depth * n;
      const double lo =
          std::min(off_wall, std::max(-half + kMargin - y0, -ylim - c.grasp.position.y()));
      const double hi =
          std::max(off_wall, std::min(half - kMargin - y1, ylim - c.grasp.position.y()));
      if (lo <= hi)
        retract.y() = c.grasp.position.y() + std::clamp(retract.y() - c.grasp.position.y(), lo, hi);
      c.retract = {retract, plate_yaw};
      if (!reachable(robot, c.grasp, at) || !reachable(robot, c.pregrasp, at)) {
        if (rejected && first_refusal.empty())
          first_refusal =
              fmt::format("no arm pose reaches its face from base x {:.2f} m", c.base_x);
        continue;
      }
      ranked.push_back({std::move(c), std::floor((b[i].x0 - nearest) / 0.2), b[i].z1, std::abs(y)});
      taken = true;
      break;
    }
    if (!taken && rejected) rejected->push_back({box.id, first_refusal});
  }
  // Nearest first: a box behind others is reached over them, which the arm
  // plans slowly and the held box may not clear; within reach of the front,
  // high up first.
  // A load with a box riding on it risks that box: after every other.
  std::stable_sort(ranked.begin(), ranked.end(), [](const Ranked& a, const Ranked& b) {
    if (a.c.riders.empty() != b.c.riders.empty()) return a.c.riders.empty();
    if (a.x_bin != b.x_bin) return a.x_bin < b.x_bin;
    if (std::abs(a.top - b.top) > 1e-3) return a.top > b.top;
    return a.centre_distance < b.centre_distance;
  });
  // A group found from each of its boxes is one candidate.
  std::vector<PickCandidate> out;
  std::vector<std::vector<std::uint32_t>> taken;
  for (std::size_t i = 0; i < ranked.size() && out.size() < max_count; ++i) {
    auto ids = ranked[i].c.boxes;
    std::sort(ids.begin(), ids.end());
    if (std::find(taken.begin(), taken.end(), ids) != taken.end()) continue;
    taken.push_back(std::move(ids));
    out.push_back(ranked[i].c);
  }
  return out;
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
