// Pick pipeline, filters: what a plate pose must pass to be a grip — a
// free corridor to the face, cups on it, a way up and out for what it takes
// — and the arm's reach for the candidate made of it.
#include <algorithm>
#include <cmath>

#include <fmt/format.h>

#include "pick_pipeline.hpp"

namespace plr::actions::pick {

namespace {

// Whether [a0, a1] and [b0, b1] come closer than kClearance.
bool near(double a0, double a1, double b0, double b1) {
  return a0 - kClearance < b1 && b0 < a1 + kClearance;
}

bool contains(const std::vector<std::size_t>& group, std::size_t j) {
  return std::find(group.begin(), group.end(), j) != group.end();
}

}  // namespace

std::string to_string(const Refusal& r) {
  switch (r.kind) {
    case Refusal::Kind::kNoFace:
      return "no face the plate seals on";
    case Refusal::Kind::kProud:
      return fmt::format("box {} stands out before its face", r.box);
    case Refusal::Kind::kNoRoom:
      return fmt::format("box {} leaves the plate no room before it", r.box);
    case Refusal::Kind::kNoCup:
      return "no whole cup on its face";
    case Refusal::Kind::kRestsOn:
      return fmt::format("box {} rests on box {}", r.box, r.of);
    case Refusal::Kind::kInTheWay:
      return fmt::format("box {} is in the way out of box {}", r.box, r.of);
    case Refusal::Kind::kUnreachable:
      return fmt::format("no arm pose reaches its face from base x {:.2f} m", r.base_x);
  }
  return {};
}

Corridor corridor(const PickScene& s, const Geometry& g, const Approach& a,
                  const Eigen::Vector3d& p) {
  // A settled wall is not flush: the plate stops grasp_gap short of the face
  // and of any neighbour in the corridor that stands out; the cups reach
  // the face across kProud of extra gap.
  const double pw = g.plate_half_width(), ph = g.plate_half_height();
  const Eigen::Vector3d& n = a.face.n;
  Corridor c{g.grasp_gap, g.pregrasp_distance, std::nullopt, std::nullopt};
  for (std::size_t j = 0; j < s.size(); ++j) {
    const sim::Bounds& b = s.bounds[j];
    if (j == a.box || !near(p.z() - ph, p.z() + ph, b.z0, b.z1)) continue;
    const auto span = span_in_band(s.outline[j], p.head<2>(), n.head<2>(), pw);
    if (!span || span->min >= 0.0) continue;
    if (span->max > -kProud - kClearance) {
      if (g.grasp_gap - span->min > c.back) c.proud = j;
      c.back = std::max(c.back, g.grasp_gap - span->min);
    } else if (-span->max - kClearance - s.plate_depth < c.room) {
      c.before = j;
      c.room = -span->max - kClearance - s.plate_depth;
    }
  }
  return c;
}

std::optional<Refusal> corridor_refusal(const PickScene& s, const Geometry& g, const Corridor& c) {
  if (c.back - g.grasp_gap > kProud)
    return Refusal{Refusal::Kind::kProud, s.world.boxes[*c.proud].id};
  if (c.room < kMinPregrasp) return Refusal{Refusal::Kind::kNoRoom, s.world.boxes[*c.before].id};
  return std::nullopt;
}

Sealed sealed_group(const PickScene& s, const Geometry& g, const Approach& a,
                    const std::vector<bool>& stacked, const Eigen::Vector3d& p,
                    const Eigen::Vector3d& surface, int own_cups) {
  // The plate is as high as two typical boxes. The cups over any other box
  // stay closed (cups_open): it stays.
  const double pw = g.plate_half_width(), ph = g.plate_half_height();
  Sealed out{{a.box}, {own_cups}};
  for (std::size_t j = 0; j < s.size(); ++j) {
    const sim::Bounds& b = s.bounds[j];
    if (j == a.box || a.alternative || !(s.in_region[j] || stacked[j]) || !s.faces[j] ||
        !near(p.y() - pw, p.y() + pw, b.y0, b.y1) || !near(p.z() - ph, p.z() + ph, b.z0, b.z1))
      continue;
    const double gap = (s.faces[j]->centre - surface).dot(a.face.n);
    if (std::abs(gap) > g.cups.reach + kSealMargin) continue;
    const int k = cups_on(s, g, a, j, p);
    if (k == 0) continue;
    out.group.push_back(j);
    out.cups.push_back(k);
  }
  return out;
}

double lift_height(const PickScene& s, const Geometry& g, const std::vector<std::size_t>& group) {
  const auto& b = s.bounds;
  double z0 = b[group.front()].z0;
  for (auto j : group) z0 = std::min(z0, b[j].z0);
  double lift = std::max(g.retract_lift, g.nose_top + kMargin - z0);
  // A tilted box rests on a tilted top (a leaning column): their outlines
  // overlap in height by more than a flat stack's, and the group comes out
  // only once lifted clear of what it rests on.
  for (auto j : group)
    for (std::size_t k = 0; k < s.size(); ++k)
      if (!contains(group, k) && b[k].z0 < b[j].z0 &&
          separation(s.outline[j], s.outline[k]) < -kMargin)
        lift = std::max(lift, std::min(kMaxLift, b[k].z1 - b[j].z0 + kClearance + kLiftSlack));
  return lift;
}

double ceiling_room(const PickScene& s, const Geometry& g, const std::vector<std::size_t>& group,
                    const Eigen::Vector3d& p) {
  double top = p.z() + g.plate_half_height();
  for (auto j : group) top = std::max(top, s.bounds[j].z1);
  return std::max(0.0, s.world.trailer.height - kClearance - top);
}

std::vector<std::size_t> riders_on(const PickScene& s, const std::vector<std::size_t>& group,
                                   double lift) {
  const auto& b = s.bounds;
  auto rests_on = [&](std::size_t top, std::size_t under) {
    return std::abs(b[top].z0 - b[under].z1) < kStacked &&
           separation(s.outline[under], s.outline[top]) < -kMargin;
  };
  std::vector<std::size_t> out;
  for (std::size_t k = 0; k < s.size(); ++k) {
    if (contains(group, k) ||
        !std::any_of(group.begin(), group.end(), [&](std::size_t j) { return rests_on(k, j); }))
      continue;
    const sim::Box& box = s.world.boxes[k];
    const Eigen::Vector3d c = box.pose.translation();
    bool carried =
        s.wall.count(box.id) > 0 && has_sealable_face(box) &&
        b[k].z1 + lift + kClearance < s.world.trailer.height &&
        std::any_of(group.begin(), group.end(), [&](std::size_t j) {
          return b[j].x0 <= c.x() && c.x() <= b[j].x1 && b[j].y0 <= c.y() && c.y() <= b[j].y1;
        });
    for (std::size_t m = 0; m < s.size() && carried; ++m)
      carried = m == k || contains(group, m) || !rests_on(k, m);
    if (!carried || out.size() == kMaxRiders) return {};
    out.push_back(k);
  }
  return out;
}

std::optional<std::size_t> in_the_way(const PickScene& s, const std::vector<std::size_t>& group,
                                      const Polygon& area, double z0, double z1, bool leaning_too) {
  for (std::size_t j = 0; j < s.size(); ++j) {
    if (!contains(group, j) && (leaning_too || has_sealable_face(s.world.boxes[j])) &&
        near(z0, z1, s.bounds[j].z0, s.bounds[j].z1) && separation(area, s.outline[j]) < -kMargin)
      return j;
  }
  return std::nullopt;
}

std::optional<Refusal> way_out_refusal(const PickScene& s, const std::vector<std::size_t>& moving,
                                       double lift, double out_depth, const Eigen::Vector3d& n) {
  for (auto j : moving) {
    const sim::Bounds& b = s.bounds[j];
    const std::uint32_t id = s.world.boxes[j].id;
    if (const auto over = in_the_way(s, moving, s.outline[j], b.z1, b.z1 + lift, false))
      return Refusal{Refusal::Kind::kRestsOn, s.world.boxes[*over].id, id};
    if (const auto out = in_the_way(s, moving, swept(s.outline[j], -out_depth * n.head<2>()),
                                    b.z0 + lift, b.z1 + lift, true))
      return Refusal{Refusal::Kind::kInTheWay, s.world.boxes[*out].id, id};
  }
  return std::nullopt;
}

std::optional<Refusal> reach_refusal(const sim::RobotModel& robot, const PickCandidate& c,
                                     const sim::JointVector& current) {
  sim::JointVector at = current;
  at[sim::kBaseX] = c.base_x;
  if (!robot.arm_ik(c.grasp, at).empty() && !robot.arm_ik(c.pregrasp, at).empty())
    return std::nullopt;
  Refusal r{Refusal::Kind::kUnreachable};
  r.base_x = c.base_x;
  return r;
}

}  // namespace plr::actions::pick
