// Pick pipeline, choice and ranking: the best grip of the poses that pass
// the filters, the candidate made of it, and the candidates' order.
#include "pick_pipeline.hpp"

#include <algorithm>
#include <cmath>

namespace plr::actions::pick {

std::tuple<bool, int, int, int> grip_rank(const Grip& grip, bool fewer) {
  const int n = static_cast<int>(grip.group.size());
  const bool bare = grip.riders.empty();
  int total = 0;
  for (int k : grip.cups) total += k;
  const int fewest = *std::min_element(grip.cups.begin(), grip.cups.end());
  return fewer ? std::make_tuple(bare, -n, grip.cups.front(), total)
               : std::make_tuple(bare, n, fewest, total);
}

std::optional<Grip> best_grip(const PickScene& s, const Geometry& g, const Approach& a,
                              const std::vector<bool>& stacked, bool fewer,
                              std::optional<Refusal>* refused) {
  const sim::Bounds& b = s.bounds[a.box];
  const Eigen::Vector3d& n = a.face.n;
  auto refuse = [&](const Refusal& why) {
    if (refused && !*refused) *refused = why;
  };
  std::optional<Grip> best;
  for (const auto& [dy, dz] : plate_offsets(g, a.face, (b.z1 - b.z0) / 2, fewer)) {
    const Eigen::Vector3d p = plate_at(s.world, g, a, dy, dz);
    const Corridor room = corridor(s, g, a, p);
    if (const auto why = corridor_refusal(s, g, room)) {
      refuse(*why);
      continue;
    }
    const int own = cups_on(s, g, a, a.box, p);
    if (own == 0) {
      refuse({Refusal::Kind::kNoCup});
      continue;
    }
    Sealed sealed = sealed_group(s, g, a, stacked, p, p - room.back * n, own);
    Grip grip;
    grip.at_face = p;
    grip.back = room.back;
    grip.pregrasp = room.room;
    grip.group = std::move(sealed.group);
    grip.cups = std::move(sealed.cups);
    grip.lift = std::min(lift_height(s, g, grip.group), ceiling_room(s, g, grip.group, p));
    double depth = 0;
    for (auto j : grip.group) depth = std::max(depth, s.bounds[j].x1 - s.bounds[j].x0);
    grip.out_depth = std::max(2 * a.face.half_d, depth) + kMargin;
    grip.riders = riders_on(s, grip.group, grip.lift);
    std::vector<std::size_t> moving = grip.group;
    moving.insert(moving.end(), grip.riders.begin(), grip.riders.end());
    if (const auto why = way_out_refusal(s, moving, grip.lift, grip.out_depth, n)) {
      refuse(*why);
      continue;
    }
    if (!best || grip_rank(grip, fewer) > grip_rank(*best, fewer)) best = std::move(grip);
  }
  return best;
}

PickCandidate make_candidate(const PickScene& s, const Geometry& g, const Approach& a,
                             const Grip& grip) {
  const auto& b = s.bounds;
  const Eigen::Vector3d& n = a.face.n;
  const Eigen::Vector3d& lateral = a.face.lateral;
  const double pw = g.plate_half_width(), ph = g.plate_half_height();
  PickCandidate c;
  c.box = s.world.boxes[a.box].id;
  for (auto j : grip.group) c.boxes.push_back(s.world.boxes[j].id);
  for (auto j : grip.riders) c.riders.push_back(s.world.boxes[j].id);
  c.box_cups = grip.cups;
  c.cups = grip.cups.front();
  c.grasp = {grip.at_face - grip.back * n, a.yaw};
  // Backed off along a turned face's normal, the plate also moves sideways:
  // near a side wall, only as far as the wall lets it.
  Eigen::Vector3d pregrasp = grip.at_face - grip.pregrasp * n;
  pregrasp.y() = std::clamp(pregrasp.y(), -a.ylim, a.ylim);
  c.pregrasp = {pregrasp, a.yaw};
  // The valves: the cup grid runs down the plate by rows, across by columns.
  const sim::SuctionPlate& cups = g.cups;
  c.cups_open.assign(static_cast<std::size_t>(cups.cups_x * cups.cups_y), false);
  for (int r = 0; r < cups.cups_x; ++r) {
    for (int k = 0; k < cups.cups_y; ++k) {
      const Eigen::Vector3d cup =
          grip.at_face +
          (0.5 - (r + 0.5) / cups.cups_x) * cups.extent.x() * Eigen::Vector3d::UnitZ() +
          ((k + 0.5) / cups.cups_y - 0.5) * cups.extent.y() * lateral;
      c.cups_open[static_cast<std::size_t>(r * cups.cups_y + k)] =
          std::any_of(grip.group.begin(), grip.group.end(), [&](std::size_t j) {
            const Face& fj = a.face_of(s, j);
            return std::abs((cup - fj.centre).dot(lateral)) <= fj.half_w - cups.cup_radius &&
                   std::abs(cup.z() - fj.centre.z()) <= fj.half_up - cups.cup_radius;
          });
    }
  }
  // Base: the arm at its preferred reach, the lowered nose short of every
  // box. A plate low enough to meet the lowered nose stays ahead of its tip
  // at the pre-grasp (nose_clearance covers the plate's body): turned off
  // the trailer's axis, by its leading corner.
  const double by_reach = a.point.x() - g.pick_reach + g.arm_yaw_offset;
  const double by_nose = s.nearest - g.conveyor_length - g.nose_clearance;
  const double plate_back = c.pregrasp.position.x() - pw * std::abs(n.y());
  const double by_plate = c.pregrasp.position.z() - ph < g.nose_top
                              ? plate_back - g.conveyor_length - g.nose_clearance
                              : by_reach;
  c.base_x = std::min({by_reach, by_nose, by_plate});
  // Lifted, then pulled out until clear of what it rested on: the drop-off
  // move after that swings freely. A group against a side wall is lifted
  // away from it too: dragged along it, the held boxes would press into it.
  // It moves no further than halfway to the box standing beside it on the
  // other side, which it would press into instead (C s12: 3 cm into a flush
  // neighbour).
  const sim::Bounds& first = b[a.box];
  double x0 = first.x0, x1 = first.x1, y0 = first.y0, y1 = first.y1, z0 = first.z0, z1 = first.z1;
  for (auto j : grip.group) {
    x0 = std::min(x0, b[j].x0);
    x1 = std::max(x1, b[j].x1);
    y0 = std::min(y0, b[j].y0);
    y1 = std::max(y1, b[j].y1);
    z0 = std::min(z0, b[j].z0);
    z1 = std::max(z1, b[j].z1);
  }
  const double half = s.world.trailer.width / 2;
  double off_wall = std::max(0.0, kMargin - (half + y0)) - std::max(0.0, kMargin - (half - y1));
  for (std::size_t j = 0; j < s.size() && off_wall != 0.0; ++j) {
    if (std::find(grip.group.begin(), grip.group.end(), j) != grip.group.end() ||
        !(b[j].x0 < x1 && x0 < b[j].x1 && b[j].z0 < z1 + grip.lift && z0 < b[j].z1))
      continue;
    const double room = off_wall > 0 ? b[j].y0 - y1 : y0 - b[j].y1;
    const bool beside = off_wall > 0 ? b[j].y0 + b[j].y1 > y0 + y1 : b[j].y0 + b[j].y1 < y0 + y1;
    if (beside)
      off_wall = std::copysign(std::min(std::abs(off_wall), std::max(0.0, room / 2)), off_wall);
  }
  c.lift = {c.grasp.position + Eigen::Vector3d(0, off_wall, grip.lift), a.yaw};
  // Pulled out along a turned face's normal, the load also moves sideways:
  // no further than the side walls let it and the plate, and never pushed
  // further off a wall than the lift took it.
  Eigen::Vector3d retract = c.lift.position - grip.out_depth * n;
  const double lo =
      std::min(off_wall, std::max(-half + kMargin - y0, -a.ylim - c.grasp.position.y()));
  const double hi =
      std::max(off_wall, std::min(half - kMargin - y1, a.ylim - c.grasp.position.y()));
  if (lo <= hi)
    retract.y() = c.grasp.position.y() + std::clamp(retract.y() - c.grasp.position.y(), lo, hi);
  c.retract = {retract, a.yaw};
  return c;
}

Ranked ranked(const PickScene& s, std::size_t i, PickCandidate c) {
  const sim::Bounds& b = s.bounds[i];
  return {std::move(c), std::floor((b.x0 - s.nearest) / 0.2), b.z1,
          std::abs(s.world.boxes[i].pose.translation().y())};
}

std::vector<PickCandidate> rank(std::vector<Ranked> ranked, std::size_t max_count) {
  // Nearest first: a box behind others is reached over them, which the arm
  // plans slowly and the held box may not clear; within reach of the front,
  // high up first. A load with a box riding on it risks that box: after
  // every other.
  std::stable_sort(ranked.begin(), ranked.end(), [](const Ranked& a, const Ranked& b) {
    if (a.c.riders.empty() != b.c.riders.empty()) return a.c.riders.empty();
    if (a.x_bin != b.x_bin) return a.x_bin < b.x_bin;
    if (std::abs(a.top - b.top) > 1e-3) return a.top > b.top;
    return a.centre_distance < b.centre_distance;
  });
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

}  // namespace plr::actions::pick
