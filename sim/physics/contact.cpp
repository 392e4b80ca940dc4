#include "contact.hpp"

#include <algorithm>
#include <cmath>
#include <iterator>

namespace plr::sim::detail {
namespace {

constexpr std::uint8_t kBoxBox = 0, kBoxLink = 1, kBoxPlane = 2;
constexpr double kWakeMargin = 0.01;  // m around a moving box within which sleepers wake
// A box lies on a belt when its contact normal is within 45 degrees of the
// belt surface's (the shape's local +z).
constexpr double kOnSurface = 0.7;

// Two oriented boxes (poses, half extents) apart by more than `margin` along
// one of their face normals: a cheap test before FCL's, which finds no
// contact for them (separating axis theorem; the margin is far beyond
// rounding, and beyond FCL's tolerance for a cylinder inside the box).
bool separated(const Eigen::Isometry3d& pa, const Eigen::Vector3d& ha, const Eigen::Isometry3d& pb,
               const Eigen::Vector3d& hb, double margin) {
  const Eigen::Matrix3d abs_c = (pa.linear().transpose() * pb.linear()).cwiseAbs();
  const Eigen::Vector3d d = pb.translation() - pa.translation();
  const Eigen::Vector3d da = pa.linear().transpose() * d, db = pb.linear().transpose() * d;
  return (da.cwiseAbs().array() > (ha + abs_c * hb).array() + margin).any() ||
         (db.cwiseAbs().array() > (hb + abs_c.transpose() * ha).array() + margin).any();
}

}  // namespace

Contacts::Contacts(const PhysicsOptions& options, const Trailer& trailer)
    : options_(options), trailer_(trailer), broad_(trailer), request_(8, true) {}

void Contacts::set_boxes(const std::vector<Body>& bodies) {
  box_shapes_.clear();
  box_shapes_.reserve(bodies.size());
  for (const Body& b : bodies) box_shapes_.emplace_back(b.box.size);
  broad_ = BroadPhase(trailer_);
}

void Contacts::set_links(const std::vector<LinkGeometry>& links) {
  link_shapes_.clear();
  link_half_.clear();
  for (const LinkGeometry& l : links) {
    if (l.shape == LinkGeometry::Shape::kCylinder) {
      link_shapes_.push_back(std::make_unique<fcl::Cylinderd>(l.size.x(), l.size.z()));
      link_half_.emplace_back(l.size.x(), l.size.x(), 0.5 * l.size.z());
    } else {
      link_shapes_.push_back(std::make_unique<fcl::Boxd>(l.size));
      link_half_.push_back(0.5 * l.size);
    }
  }
}

void Contacts::sweep_links(const std::vector<Body>& bodies,
                           const std::vector<Eigen::Vector3d>& from,
                           const std::vector<Eigen::Vector3d>& to) {
  link_reach_.clear();
  moved_.clear();
  if (from.size() != link_half_.size() || to.size() != link_half_.size()) return;
  broad_.update(bodies);
  link_reach_.resize(link_half_.size());
  for (std::size_t l = 0; l < link_half_.size(); ++l) {
    // A shape lies within its half diagonal of its centre however it turns;
    // the margin covers the rounding of the centre's interpolation.
    const Eigen::Vector3d r = Eigen::Vector3d::Constant(link_half_[l].norm() + 1e-6);
    broad_.query(from[l].cwiseMin(to[l]) - r, from[l].cwiseMax(to[l]) + r,
                 BroadPhase::kSleeping | BroadPhase::kMoving, link_reach_[l]);
  }
}

bool Contacts::collide(const fcl::CollisionGeometryd& ga, const Eigen::Isometry3d& pa,
                       const fcl::CollisionGeometryd& gb, const Eigen::Isometry3d& pb) {
  fcl::CollisionResultd result;
  fcl::collide(&ga, pa, &gb, pb, request_, result);
  points_.clear();
  for (std::size_t i = 0; i < result.numContacts(); ++i) {
    const auto& c = result.getContact(i);
    // FCL's normal points from a to b; the force on a pushes along -normal.
    if (c.penetration_depth > 0.0) points_.push_back({c.pos, -c.normal, c.penetration_depth, 0.0});
  }
  for (Point& pt : points_) pt.weight = 1.0 / static_cast<double>(points_.size());
  return !points_.empty();
}

bool Contacts::take(const Patch& patch) {
  points_.clear();
  for (const PatchPoint& pt : patch.points) {
    points_.push_back({pt.p, patch.normal, pt.depth, pt.weight});
  }
  return !points_.empty();
}

void Contacts::apply(State& state, int a, int b, const Other& o, const PairKey& key, double mu,
                     double dt, std::vector<Wrench>& wrenches) {
  Body& body = state.bodies[static_cast<std::size_t>(a)];
  const double ma = body.box.mass;
  // Box pairs use the reduced mass whether the other box is awake or not, so
  // a neighbour falling asleep does not change the force (and kick this box).
  const double m = o.mass > 0.0 ? ma * o.mass / (ma + o.mass) : ma;
  const double omega = options_.contact_omega;
  const double k = m * omega * omega;
  const double c = 2.0 * options_.damping_ratio * m * omega;
  // Box-box and box-trailer contacts are damped by damp(), after this step's
  // forces; robot shapes keep the explicit damper.
  const bool implicit = key.kind != kBoxLink;
  // Their damping follows the mass the contact carries (its spring force / g)
  // where that exceeds the pair's reduced mass: a heavy stack swaying on a
  // light box is damped like one on a heavy box (the damping is implicit, so
  // any amount is stable).
  double carried = m;
  if (implicit) {
    double push = 0.0;
    for (const Point& pt : points_) push += pt.weight * k * pt.depth;
    carried = std::max(m, push / options_.gravity);
  }
  const double c_box = 2.0 * options_.box_damping_ratio * carried * omega;
  const Eigen::Vector3d ca = body.box.pose.translation();
  const auto relative_velocity = [&](const Eigen::Vector3d& p) -> Eigen::Vector3d {
    return (body.v + body.w.cross(p - ca)) - (o.v + o.w.cross(p - o.centre) + o.belt);
  };
  Wrench on_a, on_b;
  double normal_sum = 0.0;
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero(), normal = Eigen::Vector3d::Zero();
  for (const Point& pt : points_) {
    const double vn = relative_velocity(pt.p).dot(pt.n);
    const double fn = pt.weight * std::max(0.0, k * pt.depth - (implicit ? 0.0 : c * vn));
    if (implicit) {
      dampers_.push_back(
          {a, b, pt.p, pt.n, pt.weight * c_box, pt.weight * k * pt.depth * dt, false});
    }
    const Eigen::Vector3d f = fn * pt.n;
    on_a.force += f;
    on_a.torque += (pt.p - ca).cross(f);
    on_b.force -= f;
    on_b.torque -= (pt.p - o.centre).cross(f);
    normal_sum += fn;
    centroid += pt.weight * pt.p;
    normal += pt.weight * pt.n;
  }
  normal.normalize();
  // Friction: a tangential spring-damper at the contact centroid plus a
  // torsional one about the normal, each capped by Coulomb's law; the springs
  // keep resting boxes from creeping or spinning.
  if (normal_sum > 0.0) {
    const Eigen::Vector3d vr = relative_velocity(centroid);
    const Eigen::Vector3d vt = vr - normal * normal.dot(vr);
    Eigen::Vector3d s = Eigen::Vector3d::Zero();
    double twist = 0.0;
    const auto old =
        std::lower_bound(old_pairs_.begin(), old_pairs_.end(), key,
                         [](const PairState& p, const PairKey& k2) { return p.key < k2; });
    if (old != old_pairs_.end() && old->key == key) {
      s = old->bristle - normal * normal.dot(old->bristle);
      twist = old->twist;
    }
    s += vt * dt;
    const double kt = 0.5 * k, ct = 0.5 * c;
    Eigen::Vector3d ft = -kt * s - (implicit ? 0.0 : ct) * vt;
    const double limit = mu * normal_sum;
    if (ft.norm() > limit) {
      ft *= limit / ft.norm();
      s = -ft / kt;  // slipping: the spring stays at the Coulomb limit
    }
    if (implicit) {  // the damper gets what Coulomb leaves of the limit
      dampers_.push_back({a, b, centroid, normal, 0.5 * c_box, (limit - ft.norm()) * dt, true});
    }
    on_a.force += ft;
    on_a.torque += (centroid - ca).cross(ft);
    // A belt surface passes its friction to the belt, and so to its motor.
    if (key.kind == kBoxLink) belt_force_[key.b] += ft.dot(o.belt_dir);
    on_b.force -= ft;
    on_b.torque -= (centroid - o.centre).cross(ft);

    double arm = 0.0, arm2 = 0.0;  // contact patch size around the centroid
    for (const Point& pt : points_) {
      const Eigen::Vector3d r = pt.p - centroid;
      const double d2 = (r - normal * normal.dot(r)).squaredNorm();
      arm += pt.weight * std::sqrt(d2);
      arm2 += pt.weight * d2;
    }
    if (arm > 1e-4) {
      const double spin = normal.dot(body.w - o.w);
      twist += spin * dt;
      double torque = -(kt * twist + ct * spin) * arm2;
      const double torque_limit = mu * normal_sum * arm;
      if (std::abs(torque) > torque_limit) {
        torque = std::copysign(torque_limit, torque);
        twist = -torque / (kt * arm2);
      }
      on_a.torque += torque * normal;
      on_b.torque -= torque * normal;
    } else {
      twist = 0.0;
    }
    state.pairs.push_back({key, s, twist});
  }
  if (key.kind == kBoxLink) link_force_[key.b] += on_b.force;
  Wrench& wa = wrenches[static_cast<std::size_t>(a)];
  wa.force += on_a.force;
  wa.torque += on_a.torque;
  if (b >= 0) {
    Wrench& wb = wrenches[static_cast<std::size_t>(b)];
    wb.force += on_b.force;
    wb.torque += on_b.torque;
  }
}

void Contacts::compute(State& state, const std::vector<int>& moving,
                       const std::vector<Mover>& links, double dt, std::vector<Wrench>& wrenches,
                       std::vector<int>& wake, const std::vector<std::uint8_t>* active) {
  std::vector<Body>& bodies = state.bodies;
  clear_wrenches(wrenches, bodies.size(), moving);
  merged_.clear();
  std::set_union(moved_.begin(), moved_.end(), moving.begin(), moving.end(),
                 std::back_inserter(merged_));
  moved_.swap(merged_);
  old_pairs_.swap(state.pairs);
  state.pairs.clear();
  dampers_.clear();
  link_force_.assign(links.size(), Eigen::Vector3d::Zero());
  belt_force_.assign(links.size(), 0.0);
  broad_.update(bodies, moving);
  const auto corner_speed = [](const Body& b) { return b.v.norm() + b.w.norm() * b.radius; };
  const auto deepest = [&]() {
    double depth = 0.0;
    for (const Point& pt : points_) depth = std::max(depth, pt.depth);
    return depth;
  };

  // Trailer planes: floor, ceiling, side walls, front wall (the rear is open).
  const double hw = 0.5 * trailer_.width;
  const std::array<std::pair<Eigen::Vector3d, double>, 5> planes{{
      {Eigen::Vector3d::UnitZ(), 0.0},
      {-Eigen::Vector3d::UnitZ(), -trailer_.height},
      {Eigen::Vector3d::UnitY(), -hw},
      {-Eigen::Vector3d::UnitY(), -hw},
      {-Eigen::Vector3d::UnitX(), -trailer_.depth},
  }};
  const Eigen::Vector3d zero = Eigen::Vector3d::Zero();
  const Other ground{0.0, zero, zero, zero, zero, zero};

  const Eigen::Vector3d margin = Eigen::Vector3d::Constant(kWakeMargin);
  for (const int i : moving) {
    Body& a = bodies[static_cast<std::size_t>(i)];
    if (a.mode != Mode::kAwake) continue;
    const std::size_t ai = static_cast<std::size_t>(i);
    const Eigen::Vector3d &alo = broad_.lo(ai), &ahi = broad_.hi(ai);
    for (std::size_t p = 0; p < planes.size(); ++p) {
      const auto& [normal, offset] = planes[p];
      // Quick reject: the AABB is on the inner side.
      const Eigen::Vector3d probe = (normal.array() > 0).select(alo, ahi);
      if (normal.dot(probe) >= offset) continue;
      box_plane_patch(a.box.size, a.box.pose, normal, offset, patch_);
      if (take(patch_)) {
        apply(state, i, -1, ground, {a.box.id, static_cast<std::uint32_t>(p), kBoxPlane},
              options_.friction_trailer, dt, wrenches);
      }
    }
    // A box moving fast wakes the sleeping boxes next to it even without
    // contact: a support falling away leaves the box above it hanging.
    const double speed = corner_speed(a);
    const bool fast = speed > options_.wake_speed;
    // At adaptive fidelity a box on a path to the action wakes them moving
    // slower, as it comes within the margin towards them (closing the gap
    // between the centres at sleep_speed or more; not yet touching: boxes
    // in contact wake by pressing, as at full fidelity, or every nudge in a
    // pile would wake the pile).
    const bool approaching =
        !fast && active != nullptr && (*active)[ai] != 0 && speed > options_.sleep_speed;
    const auto closing = [&](const Body& b) {
      const Eigen::Vector3d d = b.box.pose.translation() - a.box.pose.translation();
      return a.v.dot(d) > options_.sleep_speed * d.norm();
    };
    broad_.query(alo - margin, ahi + margin, BroadPhase::kSleeping | BroadPhase::kMoving, near_);
    for (const int j : near_) {
      const std::size_t bj = static_cast<std::size_t>(j);
      const Body& b = bodies[bj];
      if (j == i || (b.mode == Mode::kAwake && j < i)) continue;
      // Near the box itself: its world-aligned bounds reach further when it
      // is turned, and woke boxes it could not touch.
      const bool close =
          (fast || approaching) && b.mode == Mode::kAsleep &&
          !separated(a.box.pose, 0.5 * a.box.size, b.box.pose, 0.5 * b.box.size, kWakeMargin);
      if (fast && close) wake.push_back(j);
      if (disjoint(alo, ahi, broad_.lo(bj), broad_.hi(bj))) {
        if (approaching && close && closing(b)) wake.push_back(j);
        continue;
      }
      box_box_patch(a.box.size, a.box.pose, b.box.size, b.box.pose, patch_);
      if (!take(patch_)) {
        if (approaching && close && closing(b)) wake.push_back(j);
        continue;
      }
      // Pressed into hard by a slow box (e.g. a growing load): wake up too.
      if (b.mode == Mode::kAsleep && deepest() > options_.wake_depth) wake.push_back(j);
      const Other other{b.box.mass, b.box.pose.translation(), b.v, b.w, zero, zero};
      const PairKey key{std::min(a.box.id, b.box.id), std::max(a.box.id, b.box.id), kBoxBox};
      // Held boxes take the reaction too: the cups feel it.
      apply(state, i, b.mode == Mode::kAsleep ? -1 : j, other, key, options_.friction_box, dt,
            wrenches);
    }
  }

  // Robot shapes against boxes.
  for (std::size_t l = 0; l < links.size(); ++l) {
    const Mover& link = links[l];
    const Eigen::Vector3d e = link.pose.linear().cwiseAbs() * link_half_[l];
    const Eigen::Vector3d llo = link.pose.translation() - e, lhi = link.pose.translation() + e;
    const bool moving = link.speed > 1e-6 || link.belt_dir.squaredNorm() > 0.0;
    // Sleeping boxes only notice a shape that moves.
    const unsigned which = moving ? BroadPhase::kMoving | BroadPhase::kSleeping
                                  : static_cast<unsigned>(BroadPhase::kMoving);
    if (link_reach_.size() == links.size()) {
      merged_.clear();
      std::set_union(link_reach_[l].begin(), link_reach_[l].end(), moved_.begin(), moved_.end(),
                     std::back_inserter(merged_));
      broad_.filter(llo, lhi, which, merged_, near_);
    } else {
      broad_.query(llo, lhi, which, near_);
    }
    for (const int j : near_) {
      const std::size_t bj = static_cast<std::size_t>(j);
      const Body& b = bodies[bj];
      if (b.mode == Mode::kHeld) continue;
      if (separated(b.box.pose, 0.5 * b.box.size, link.pose, link_half_[l], 1e-3)) continue;
      if (!collide(box_shapes_[bj], b.box.pose, *link_shapes_[l], link.pose)) continue;
      if (b.mode == Mode::kAsleep) {
        if (!fast_ || on_belt(link) || deepest() > options_.wake_depth) wake.push_back(j);
        continue;
      }
      const Other other{0.0, link.pose.translation(), link.v, link.w, link.belt, link.belt_dir};
      apply(state, j, -1, other, {b.box.id, static_cast<std::uint32_t>(l), kBoxLink},
            options_.friction_robot, dt, wrenches);
    }
  }

  // Held boxes that move wake the sleeping boxes next to them.
  for (const int i : moving) {
    const std::size_t k = static_cast<std::size_t>(i);
    const Body& h = bodies[k];
    if (fast_ || h.mode != Mode::kHeld || corner_speed(h) <= 1e-6) continue;
    broad_.query(broad_.lo(k) - margin, broad_.hi(k) + margin, BroadPhase::kSleeping, near_);
    for (const int j : near_) {
      const Body& b = bodies[static_cast<std::size_t>(j)];
      if (!separated(h.box.pose, 0.5 * h.box.size, b.box.pose, 0.5 * b.box.size, kWakeMargin))
        wake.push_back(j);
    }
  }
  std::sort(state.pairs.begin(), state.pairs.end(),
            [](const PairState& x, const PairState& y) { return x.key < y.key; });
  std::sort(wake.begin(), wake.end());
  wake.erase(std::unique(wake.begin(), wake.end()), wake.end());
}

bool Contacts::on_belt(const Mover& link) const {
  if (link.belt_dir.squaredNorm() == 0.0) return false;
  const Eigen::Vector3d up = link.pose.linear().col(2);
  for (const Point& pt : points_)
    if (pt.n.dot(up) > kOnSurface) return true;
  return false;
}

void Contacts::pressed(const State& state, const std::vector<Mover>& links,
                       const std::vector<int>& held,
                       const std::vector<Eigen::Isometry3d>& held_poses, std::vector<int>& wake) {
  const std::vector<Body>& bodies = state.bodies;
  for (std::size_t l = 0; l < links.size() && l < link_shapes_.size(); ++l) {
    const Mover& link = links[l];
    const bool belt = link.belt_dir.squaredNorm() > 0.0;
    if (link.speed <= 1e-6 && !belt) continue;
    const Eigen::Vector3d e = link.pose.linear().cwiseAbs() * link_half_[l];
    broad_.query(link.pose.translation() - e, link.pose.translation() + e, BroadPhase::kSleeping,
                 near_);
    for (const int j : near_) {
      const auto bj = static_cast<std::size_t>(j);
      const Body& b = bodies[bj];
      if (separated(b.box.pose, 0.5 * b.box.size, link.pose, link_half_[l], 1e-3)) continue;
      if (!collide(box_shapes_[bj], b.box.pose, *link_shapes_[l], link.pose)) continue;
      double depth = 0.0;
      for (const Point& pt : points_) depth = std::max(depth, pt.depth);
      if (on_belt(link) || depth > options_.wake_depth) wake.push_back(j);
    }
  }
  for (std::size_t k = 0; k < held.size(); ++k) {
    const Body& h = bodies[static_cast<std::size_t>(held[k])];
    const Eigen::Isometry3d& pose = held_poses[k];
    const Eigen::Vector3d e = pose.linear().cwiseAbs() * (0.5 * h.box.size);
    broad_.query(pose.translation() - e, pose.translation() + e, BroadPhase::kSleeping, near_);
    for (const int j : near_) {
      const Body& b = bodies[static_cast<std::size_t>(j)];
      box_box_patch(h.box.size, pose, b.box.size, b.box.pose, patch_);
      double depth = 0.0;
      for (const PatchPoint& pt : patch_.points) depth = std::max(depth, pt.depth);
      if (depth > options_.wake_depth) wake.push_back(j);
    }
  }
  std::sort(wake.begin(), wake.end());
  wake.erase(std::unique(wake.begin(), wake.end()), wake.end());
}

void Contacts::damp(State& state, const std::vector<int>& moving, double dt,
                    std::vector<Wrench>& wrenches) {
  std::vector<Body>& bodies = state.bodies;
  inverse_inertia_.resize(bodies.size());
  for (const int m : moving) {
    const auto i = static_cast<std::size_t>(m);
    const Body& b = bodies[i];
    if (b.mode != Mode::kAwake) continue;
    const Eigen::Vector3d s2 = b.box.size.cwiseProduct(b.box.size);
    const Eigen::Vector3d inverse(12.0 / (b.box.mass * (s2.y() + s2.z())),
                                  12.0 / (b.box.mass * (s2.x() + s2.z())),
                                  12.0 / (b.box.mass * (s2.x() + s2.y())));
    const Eigen::Matrix3d r = b.box.pose.linear();
    inverse_inertia_[i] = r * inverse.asDiagonal() * r.transpose();
  }
  for (const Damper& d : dampers_) {
    Body& a = bodies[static_cast<std::size_t>(d.a)];
    Body* b = d.b >= 0 ? &bodies[static_cast<std::size_t>(d.b)] : nullptr;
    const bool b_free = b != nullptr && b->mode == Mode::kAwake;
    const Eigen::Vector3d ra = d.p - a.box.pose.translation();
    Eigen::Vector3d vrel = a.v + a.w.cross(ra), rb = Eigen::Vector3d::Zero();
    if (b != nullptr) {
      rb = d.p - b->box.pose.translation();
      vrel -= b->v + b->w.cross(rb);
    }
    // Normal dampers act along n; tangential ones against the sliding velocity.
    Eigen::Vector3d dir = d.n;
    double speed = vrel.dot(d.n);
    if (d.tangential) {
      const Eigen::Vector3d vt = vrel - d.n * speed;
      speed = vt.norm();
      if (speed < 1e-12) continue;
      dir = vt / speed;
    }
    const Eigen::Matrix3d& ia = inverse_inertia_[static_cast<std::size_t>(d.a)];
    const Eigen::Vector3d ta = ra.cross(dir), tb = rb.cross(dir);
    double inverse_mass = 1.0 / a.box.mass + ta.dot(ia * ta);
    if (b_free) {
      inverse_mass +=
          1.0 / b->box.mass + tb.dot(inverse_inertia_[static_cast<std::size_t>(d.b)] * tb);
    }
    // The relative speed decays as exp(-c t / m_eff) over the step; a normal
    // damper pulls no harder than its spring pushes, a tangential one stays
    // within Coulomb's limit.
    const double impulse =
        std::max(-d.limit, -(1.0 - std::exp(-dt * d.c * inverse_mass)) * speed / inverse_mass);
    a.v += (impulse / a.box.mass) * dir;
    a.w += ia * (impulse * ta);
    if (b_free) {
      b->v -= (impulse / b->box.mass) * dir;
      b->w -= inverse_inertia_[static_cast<std::size_t>(d.b)] * (impulse * tb);
    } else if (b != nullptr && b->mode == Mode::kHeld) {  // the cups feel it
      Wrench& wb = wrenches[static_cast<std::size_t>(d.b)];
      wb.force -= (impulse / dt) * dir;
      wb.torque -= (impulse / dt) * tb;
    }
  }
}

}  // namespace plr::sim::detail
