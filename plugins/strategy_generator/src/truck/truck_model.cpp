#include "truck/truck_model.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace plr::generator {

TruckModel::TruckModel(Simulator& simulator, const std::vector<SimOutcome>& roots,
                       TruckOptions options, const plr::jobs::Store* store)
    : simulator_(simulator), options_(options), store_(store), roots_(roots.size()) {
  // Roots first, one state each even when two particles look alike: the
  // particles are the belief.
  for (const SimOutcome& r : roots) {
    State s;
    s.bytes = r.state;
    s.hash = actions::state_hash(*r.state);
    s.boxes_left = r.boxes_left;
    s.highest_stack_m = r.highest_stack_m;
    s.observation = r.observation;
    states_.push_back(std::move(s));
  }
}

double TruckModel::min_reward() const {
  // An action's time (a long one is a few minutes) plus the terminal
  // estimate of a full trailer.
  return -(600.0 + options_.seconds_per_box * 1000.0);
}

pomdp::Belief TruckModel::initial_belief() const {
  pomdp::Belief b;
  for (std::size_t i = 0; i < roots_; ++i) b.add(static_cast<pomdp::StateId>(i), 1.0);
  b.normalize();
  return b;
}

bool TruckModel::is_terminal(pomdp::StateId id) const {
  const State& s = state(id);
  return s.observation == kEmptyObservation || s.depth >= options_.horizon;
}

pomdp::StateId TruckModel::intern(const SimOutcome& o, int depth) const {
  const std::uint64_t h = actions::state_hash(*o.state);
  if (const auto it = index_.find({h, depth}); it != index_.end()) return it->second;
  State s;
  s.bytes = o.state;
  s.hash = h;
  s.depth = depth;
  s.boxes_left = o.boxes_left;
  s.highest_stack_m = o.highest_stack_m;
  s.observation = o.observation;
  const auto id = static_cast<pomdp::StateId>(states_.size());
  states_.push_back(std::move(s));
  index_.emplace(std::pair{h, depth}, id);
  return id;
}

void TruckModel::fill(const std::vector<SimRequest>& requests) const {
  std::vector<SimRequest> todo;
  std::vector<std::uint64_t> keys;
  for (const SimRequest& r : requests) {
    const std::uint64_t key =
        actions::work_key(actions::state_hash(*r.state), r.action, simulator_.fidelity());
    if (results_.count(key) || std::find(keys.begin(), keys.end(), key) != keys.end()) continue;
    keys.push_back(key);
    todo.push_back(r);
  }
  if (todo.empty()) return;
  auto out = simulator_.run(todo, store_);
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (!out[i].outcome) throw SimulationError(out[i].outcome.error().message);
    if (!out[i].stored) {
      ++simulated_;
      simulated_robot_s_ += out[i].outcome->robot_time_s;
      simulated_wall_s_ += out[i].outcome->wall_s;
    }
    results_.emplace(keys[i], std::move(*out[i].outcome));
  }
}

void TruckModel::prefetch(const pomdp::Belief& belief) const {
  std::vector<SimRequest> requests;
  for (const pomdp::Particle& p : belief.particles()) {
    if (is_terminal(p.state)) continue;
    for (int a = 0; a < sim::kNumActions; ++a) {
      if (steps_.count({p.state, a})) continue;
      requests.push_back({state(p.state).bytes, static_cast<sim::Action>(a)});
    }
  }
  fill(requests);
}

bool TruckModel::dominated(const pomdp::Belief& belief, pomdp::ActionId action) const {
  pomdp::Rng unused;
  for (const pomdp::Particle& p : belief.particles()) {
    if (is_terminal(p.state)) continue;
    const pomdp::Step s = step(p.state, action, unused);
    if (s.terminal || state(s.next).hash != state(p.state).hash) return false;
  }
  return true;
}

pomdp::Step TruckModel::step(pomdp::StateId id, pomdp::ActionId action, pomdp::Rng&) const {
  if (const auto it = steps_.find({id, action}); it != steps_.end()) return it->second;
  const auto a = static_cast<sim::Action>(action);
  const std::uint64_t key = actions::work_key(state(id).hash, a, simulator_.fidelity());
  if (!results_.count(key)) fill({{state(id).bytes, a}});
  const SimOutcome& o = results_.at(key);
  const int depth = state(id).depth + 1;
  pomdp::Step s;
  s.next = intern(o, depth);
  s.observation = o.observation == kEmptyObservation ? kGoalObservation : o.observation;
  s.terminal = is_terminal(s.next);
  s.reward = -o.robot_time_s;
  if (o.observation != kEmptyObservation && depth >= options_.horizon)
    s.reward -= options_.seconds_per_box * o.boxes_left;
  steps_.emplace(std::pair{id, action}, s);
  return s;
}

}  // namespace plr::generator
