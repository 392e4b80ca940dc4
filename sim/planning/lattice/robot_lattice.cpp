#include "robot_lattice.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>

namespace plr::planning {

using search::StateId;
using sim::JointVector;

// ---- JointLattice -------------------------------------------------------

JointLattice::JointLattice(const ModeLattice& lattice, const sim::CollisionChecker& checker,
                           const JointVector& start, const Goal& goal, bool escape,
                           const ExperienceStore* experience, double experience_weight)
    : lattice_(lattice),
      checker_(checker),
      robot_(checker.robot()),
      goal_(goal),
      escape_(escape),
      start_(start) {
  if (const auto* jg = std::get_if<JointGoal>(&goal_)) {
    joint_goal_ = start;
    for (int j : lattice_.joints) joint_goal_[j] = jg->q[j];
  }
  if (experience != nullptr && !experience->paths().empty() && !escape_) {
    experience_ = std::make_unique<ExperienceGraph>(
        *experience, start, lattice_.joints, experience_weight,
        [this](const JointVector& a, const JointVector& b) { return time(a, b); },
        [this](const JointVector& q) {
          State st;
          st.q = q;
          fill_plate(st);
          return plain_heuristic(st);
        });
  }
  states_.reserve(4096);
  intern(Key{}, start);
}

double JointLattice::time(const JointVector& a, const JointVector& b) const {
  double t = 0.0;
  for (int j : lattice_.joints) t = std::max(t, std::abs(b[j] - a[j]) / robot_.limits(j).velocity);
  return t;
}

void JointLattice::fill_plate(State& st) const {
  if (!std::holds_alternative<PoseGoal>(goal_)) return;
  const sim::PlateTarget t = robot_.plate_target(st.q);
  st.plate = t.position;
  st.yaw = t.yaw;
}

bool JointLattice::within_goal(const State& st) const {
  if (const auto* jg = std::get_if<JointGoal>(&goal_)) {
    for (int j : lattice_.joints) {
      if (std::abs(st.q[j] - jg->q[j]) > jg->tolerance) return false;
    }
    return true;
  }
  if (const auto* pg = std::get_if<PoseGoal>(&goal_)) {
    return (st.plate - pg->target.position).norm() <= pg->position_tolerance &&
           std::abs(std::remainder(st.yaw - pg->target.yaw, 2.0 * M_PI)) <= pg->yaw_tolerance;
  }
  return false;
}

StateId JointLattice::intern(const Key& key, const JointVector& q, bool off_lattice) {
  const auto it = index_.find(key);
  if (it != index_.end()) return it->second;
  const auto id = static_cast<StateId>(states_.size());
  State st;
  st.q = q;
  st.key = key;
  st.off_lattice = off_lattice || key[sim::kNumJoints - 1] != 0;
  fill_plate(st);
  st.goal = !escape_ && within_goal(st);
  if (experience_) {
    const auto e = experience_->estimate(q, plain_heuristic(st));
    st.h_e = e.h;
    st.via = e.via;
  }
  states_.push_back(st);
  index_.emplace(key, id);
  return id;
}

StateId JointLattice::add_goal_state(const JointVector& q) {
  for (StateId id : snapped_) {
    if ((states_[static_cast<std::size_t>(id)].q - q).norm() < 1e-9) return id;
  }
  State st;
  st.q = q;
  fill_plate(st);
  st.goal = true;
  st.snapped = true;
  st.valid = 1;  // checked by the caller
  states_.push_back(st);
  snapped_.push_back(static_cast<StateId>(states_.size() - 1));
  return snapped_.back();
}

bool JointLattice::valid(StateId s) {
  State& st = states_[static_cast<std::size_t>(s)];
  if (st.valid < 0) st.valid = checker_.is_valid(st.q) ? 1 : 0;
  return st.valid == 1;
}

bool JointLattice::is_goal(StateId s) {
  if (escape_) return valid(s);
  return states_[static_cast<std::size_t>(s)].goal;
}

double JointLattice::heuristic(StateId s) const {
  const State& st = states_[static_cast<std::size_t>(s)];
  return experience_ ? st.h_e : plain_heuristic(st);
}

double JointLattice::plain_heuristic(const State& st) const {
  if (std::holds_alternative<JointGoal>(goal_)) return time(st.q, joint_goal_);
  if (const auto* pg = std::get_if<PoseGoal>(&goal_)) {
    return (st.plate - pg->target.position).norm() / lattice_.ee_speed;
  }
  return 0.0;
}

void JointLattice::successors(StateId s, std::vector<search::Successor>& out) {
  // Copy: interning may reallocate states_.
  const State from = states_[static_cast<std::size_t>(s)];
  if (from.snapped) return;

  // Adaptive primitives first: straight to the goal when it is near.
  if (const auto* pg = std::get_if<PoseGoal>(&goal_)) {
    if ((from.plate - pg->target.position).norm() <= lattice_.snap_distance) {
      for (const JointVector& q : robot_.arm_ik(pg->target, from.q)) {
        if (!checker_.is_valid(q) || !checker_.is_motion_valid(from.q, q, false)) continue;
        out.push_back({add_goal_state(q), std::max(time(from.q, q), 1e-6)});
      }
    }
  } else if (!escape_ && std::holds_alternative<JointGoal>(goal_) &&
             time(from.q, joint_goal_) <= lattice_.snap_time &&
             checker_.is_motion_valid(from.q, joint_goal_,
                                      false)) {  // goal validity checked before the search
    // The straight move costs exactly the heuristic, a lower bound on any
    // path from here: no other successor can lead to a cheaper path.
    out.push_back({add_goal_state(joint_goal_), std::max(time(from.q, joint_goal_), 1e-6)});
    return;
  }
  if (experience_) experience_successors(from, out);

  const std::size_t dims = lattice_.joints.size();
  for (const auto& prim : lattice_.primitives) {
    Key key = from.key;
    JointVector q = from.q;
    bool inside = true;
    for (std::size_t d = 0; d < dims && inside; ++d) {
      if (prim[d] == 0) continue;
      const int j = lattice_.joints[d];
      key[d] += prim[d];
      q[j] = from.off_lattice ? from.q[j] + prim[d] * lattice_.resolution[d]
                              : start_[j] + key[d] * lattice_.resolution[d];
      inside = q[j] >= robot_.limits(j).lower && q[j] <= robot_.limits(j).upper;
    }
    if (!inside) continue;
    const StateId id = intern(from.off_lattice ? off_lattice_key(q) : key, q);
    if (!escape_) {
      if (!valid(id) || !checker_.is_motion_valid(from.q, q, false)) continue;
    }
    out.push_back({id, std::max(time(from.q, q), 1e-6)});
  }

  // Escaping contact is mostly a matter of backing the plate off: Cartesian
  // plate steps through the IK reach that in one move where single joint
  // steps would need combinations.
  if (escape_ && lattice_.plate_step > 0.0) {
    const sim::PlateTarget here = robot_.plate_target(from.q);
    for (int axis = 0; axis < 3; ++axis) {
      for (double sign : {1.0, -1.0}) {
        sim::PlateTarget t = here;
        t.position[axis] += sign * lattice_.plate_step;
        const auto sols = robot_.arm_ik(t, from.q);
        if (sols.empty() || (sols.front() - from.q).cwiseAbs().maxCoeff() > 0.1) continue;
        const JointVector& q = sols.front();
        out.push_back({intern(off_lattice_key(q), q, true), std::max(time(from.q, q), 1e-6)});
      }
    }
  }
}

JointLattice::Key JointLattice::node_key(std::int32_t node) {
  // Keyed by node, not configuration: each node has its own path to follow.
  Key key{};
  key[0] = node;
  key[sim::kNumJoints - 1] = 2;
  return key;
}

StateId JointLattice::node_state(std::int32_t node) {
  const Key key = node_key(node);
  const StateId id = intern(key, experience_->nodes()[static_cast<std::size_t>(node)].q, true);
  states_[static_cast<std::size_t>(id)].node = node;
  return id;
}

void JointLattice::experience_successors(const State& from, std::vector<search::Successor>& out) {
  const auto& nodes = experience_->nodes();
  if (from.node < 0) {
    // Onto the stored path h_E leads to, when it is near.
    // Each node is joined once, from the first state that leads there: a
    // node the search has reached is followed from there, and joining it
    // again from every state near it only pulls the search back (a stored
    // path that does not lead to this goal held M1 searches at their budget).
    if (from.via < 0 || index_.count(node_key(from.via)) != 0) return;
    const JointVector& q = nodes[static_cast<std::size_t>(from.via)].q;
    if (time(from.q, q) > lattice_.snap_time) return;
    const StateId id = node_state(from.via);
    if (!valid(id) || !checker_.is_motion_valid(from.q, q, false)) return;
    out.push_back({id, std::max(time(from.q, q), 1e-6)});
    ++experience_edges_;
    return;
  }
  // Along the stored path both ways: the next node, and the node of least
  // h_E reached while the segments are free (one edge; path_configs
  // unfolds it).
  const ExperienceGraph::Node& here = nodes[static_cast<std::size_t>(from.node)];
  for (int dir : {1, -1}) {
    double cost = 0.0, best_h = std::numeric_limits<double>::infinity(), best_cost = 0.0;
    StateId best = search::kNoState;
    std::int32_t prev = from.node;
    for (std::int32_t i = here.index + dir;; i += dir) {
      const std::int32_t n = experience_->node_at(here.path, i);
      if (n < 0) break;
      const StateId id = node_state(n);
      const JointVector& a = nodes[static_cast<std::size_t>(prev)].q;
      const JointVector& b = nodes[static_cast<std::size_t>(n)].q;
      std::int8_t& free = experience_->segment_free(std::min(n, prev));
      if (free < 0) free = valid(id) && checker_.is_motion_valid(a, b, false) ? 1 : 0;
      if (free == 0) break;
      cost += std::max(time(a, b), 1e-6);
      if (i == here.index + dir) {
        out.push_back({id, cost});
      } else if (nodes[static_cast<std::size_t>(n)].h < best_h) {
        best = id;
        best_h = nodes[static_cast<std::size_t>(n)].h;
        best_cost = cost;
      }
      prev = n;
    }
    if (best != search::kNoState) out.push_back({best, best_cost});
  }
  ++experience_edges_;
}

std::vector<JointVector> JointLattice::path_configs(const std::vector<StateId>& ids) const {
  std::vector<JointVector> path;
  for (std::size_t k = 0; k < ids.size(); ++k) {
    const State& st = states_[static_cast<std::size_t>(ids[k])];
    if (k > 0 && st.node >= 0) {
      const State& before = states_[static_cast<std::size_t>(ids[k - 1])];
      if (before.node >= 0) {
        const auto& nodes = experience_->nodes();
        const auto& a = nodes[static_cast<std::size_t>(before.node)];
        const auto& b = nodes[static_cast<std::size_t>(st.node)];
        const int dir = b.index > a.index ? 1 : -1;
        for (std::int32_t i = a.index + dir; i != b.index; i += dir)
          path.push_back(nodes[static_cast<std::size_t>(experience_->node_at(a.path, i))].q);
      }
    }
    path.push_back(st.q);
  }
  return path;
}

JointLattice::Key JointLattice::off_lattice_key(const JointVector& q) const {
  // Off-lattice states are told apart by their configuration at 1e-5.
  Key key{};
  for (std::size_t d = 0; d < lattice_.joints.size(); ++d) {
    key[d] = static_cast<std::int32_t>(std::lround(q[lattice_.joints[d]] * 1e5));
  }
  key[sim::kNumJoints - 1] = 1;
  return key;
}

// ---- LineLattice --------------------------------------------------------

LineLattice::LineLattice(const ModeLattice& lattice, const sim::CollisionChecker& checker,
                         const JointVector& start, const PoseGoal& goal)
    : lattice_(lattice), checker_(checker), robot_(checker.robot()) {
  from_ = robot_.plate_target(start);
  to_ = goal.target;
  // Yaw turns the shorter way round.
  to_.yaw = from_.yaw + std::remainder(to_.yaw - from_.yaw, 2.0 * M_PI);
  const double length = (to_.position - from_.position).norm();
  count_ = std::max(2, static_cast<int>(std::ceil(length / lattice_.resolution[0])) + 1);
  configs_.reserve(static_cast<std::size_t>(count_));
  configs_.push_back(start);
  valid_.assign(static_cast<std::size_t>(count_), -1);
}

sim::PlateTarget LineLattice::target_at(int i) const {
  const double s = static_cast<double>(i) / (count_ - 1);
  return {from_.position + s * (to_.position - from_.position),
          from_.yaw + s * (to_.yaw - from_.yaw)};
}

bool LineLattice::ensure(int i) {
  while (static_cast<int>(configs_.size()) <= i) {
    if (broken_at_ >= 0) return false;
    const int k = static_cast<int>(configs_.size());
    const JointVector& prev = configs_.back();
    const auto sols = robot_.arm_ik(target_at(k), prev);
    // Nearest solution; a large jump means the IK changed branch.
    if (sols.empty() || (sols.front() - prev).cwiseAbs().maxCoeff() > 0.25) {
      broken_at_ = k;
      return false;
    }
    configs_.push_back(sols.front());
  }
  return true;
}

bool LineLattice::stays_on_line(int i, int j) const {
  const JointVector& a = configs_[static_cast<std::size_t>(i)];
  const JointVector& b = configs_[static_cast<std::size_t>(j)];
  const Eigen::Vector3d p0 = from_.position, dir = (to_.position - from_.position).normalized();
  for (double f : {0.25, 0.5, 0.75}) {
    const Eigen::Vector3d p = robot_.plate_pose(a + f * (b - a)).translation();
    const Eigen::Vector3d off = p - p0;
    if ((off - off.dot(dir) * dir).norm() > lattice_.line_tolerance) return false;
  }
  return true;
}

double LineLattice::heuristic(StateId s) const {
  return (count_ - 1 - s) * lattice_.resolution[0] / lattice_.ee_speed;
}

void LineLattice::successors(StateId s, std::vector<search::Successor>& out) {
  // Along a line the longest feasible step dominates the shorter ones: its
  // joint-space time is at most theirs summed (triangle inequality), and the
  // states it skips can only lead to the same line. Try steps longest first.
  const int i = s;
  std::vector<int> steps;
  for (const auto& prim : lattice_.primitives) {
    if (prim[0] > 0) steps.push_back(prim[0]);  // forward only
  }
  std::sort(steps.begin(), steps.end(), std::greater<>());
  int tried = -1;
  for (int step : steps) {
    const int j = std::min(i + step, count_ - 1);
    if (j == tried || !ensure(j)) continue;
    tried = j;
    if (!stays_on_line(i, j)) continue;
    std::int8_t& v = valid_[static_cast<std::size_t>(j)];
    if (v < 0) v = checker_.is_valid(configs_[static_cast<std::size_t>(j)]) ? 1 : 0;
    if (v == 0) continue;
    const JointVector& a = configs_[static_cast<std::size_t>(i)];
    const JointVector& b = configs_[static_cast<std::size_t>(j)];
    if (!checker_.is_motion_valid(a, b, false)) continue;
    double t = 0.0;
    for (int q : lattice_.joints)
      t = std::max(t, std::abs(b[q] - a[q]) / robot_.limits(q).velocity);
    out.push_back({j, std::max(t, 1e-6)});
    return;
  }
}

}  // namespace plr::planning
