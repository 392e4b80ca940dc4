#include "truck/generate.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <map>
#include <numeric>
#include <optional>

#include "plr/pomdp/pomhdp.hpp"
#include "plr/sim/physics.hpp"
#include "truck/fidelity_check.hpp"
#include "truck/truck_heuristics.hpp"

namespace plr::generator {

namespace {

struct Stopped {};

std::string utc_now() {
  const std::time_t t = std::time(nullptr);
  std::tm tm{};
  gmtime_r(&t, &tm);
  char b[32];
  std::strftime(b, sizeof b, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return b;
}

// The particles' starting states: a continuation's leaf belief, or each
// particle's world at rest.
plr::Expected<std::vector<SimOutcome>> starting_states(const Problem& problem, actions::Rig& rig) {
  if (!problem.starts.empty()) {
    if (!problem.particle_ids.empty() && problem.particle_ids.size() != problem.starts.size())
      return plr::make_error(PLR_ERR_INVALID,
                             fmt::format("{}: {} particle ids for {} starting states", problem.name,
                                         problem.particle_ids.size(), problem.starts.size()));
    return problem.starts;
  }
  if (problem.particles.empty())
    return plr::make_error(PLR_ERR_INVALID, problem.name + ": no particles");
  std::vector<SimOutcome> roots;
  for (const sim::World& w : problem.particles) {
    auto r = actions::start_state(rig, w);
    if (!r) return plr::make_error(r.error().code, problem.name + ": " + r.error().message);
    roots.push_back(std::move(*r));
  }
  return roots;
}

std::vector<std::uint32_t> particle_ids(const Problem& problem, std::size_t n) {
  if (!problem.particle_ids.empty()) return problem.particle_ids;
  std::vector<std::uint32_t> ids(n);
  std::iota(ids.begin(), ids.end(), 0u);
  return ids;
}

SimOutcome outcome_of(const TruckModel::State& s) {
  SimOutcome o;
  o.state = s.bytes;
  o.boxes_left = s.boxes_left;
  o.highest_stack_m = s.highest_stack_m;
  o.observation = s.observation;
  return o;
}

// Each root particle (the model's states 0..n-1) run down `strategy`; the
// particles grouped by where the tree ends for them. The steps are the
// search's own (cached), so this simulates nothing the search did not.
std::vector<Leaf> find_leaves(const TruckModel& model, const sim::Strategy& strategy,
                              const std::vector<std::uint32_t>& ids) {
  std::map<std::pair<std::vector<sim::Observation>, bool>, Leaf> by_path;
  pomdp::Rng rng;
  for (std::size_t i = 0; i < ids.size(); ++i) {
    auto state = static_cast<pomdp::StateId>(i);
    std::uint32_t node = strategy.root;
    std::vector<sim::Observation> path;
    bool empty = model.state(state).observation == kEmptyObservation;
    while (!empty) {
      const auto action = static_cast<pomdp::ActionId>(strategy.nodes[node].action);
      state = model.step(state, action, rng).next;
      if (model.state(state).observation == kEmptyObservation) {
        empty = true;
        break;
      }
      path.push_back(static_cast<sim::Observation>(model.state(state).observation));
      const auto child = strategy.next(node, path.back());
      if (!child) break;
      node = *child;
    }
    Leaf& leaf = by_path[{path, empty}];
    leaf.path = path;
    leaf.empty = empty;
    leaf.particles.push_back(ids[i]);
    leaf.states.push_back(outcome_of(model.state(state)));
  }
  std::vector<Leaf> out;
  for (auto& [key, leaf] : by_path) {
    leaf.share = static_cast<double>(leaf.particles.size()) / static_cast<double>(ids.size());
    out.push_back(std::move(leaf));
  }
  return out;
}

}  // namespace

Problem make_problem(const sim::World& world, sim::EnvFamily family, std::string name,
                     int particles, std::uint64_t seed) {
  Problem p;
  p.family = std::string(sim::to_string(family));
  p.name = std::move(name);
  p.world = sim::without_masses(world);
  for (int i = 0; i < particles; ++i) {
    p.particles.push_back(sim::sample_masses(p.world, family, sim::particle_seed(seed, i)));
  }
  return p;
}

Problem make_problem(sim::EnvFamily family, std::uint64_t world_seed, int particles,
                     std::uint64_t seed) {
  Problem p =
      make_problem(sim::make_environment(family, world_seed), family,
                   fmt::format("{}-{}", sim::to_string(family), world_seed), particles, seed);
  p.world_seed = world_seed;
  return p;
}

sim::Strategy to_strategy(const pomdp::PolicyTree& tree, const std::string& name) {
  sim::Strategy s;
  s.name = name;
  s.root = tree.root;
  for (const pomdp::PolicyNode& n : tree.nodes) {
    sim::StrategyNode node;
    node.action = static_cast<sim::Action>(n.action);
    for (const auto& [o, child] : n.children) {
      if (o < sim::kNumObservations)
        node.children.emplace_back(static_cast<sim::Observation>(o), child);
    }
    s.nodes.push_back(std::move(node));
  }
  return s;
}

plr::Expected<GenerateResult> generate(
    const Problem& problem, const GenerateOptions& options, actions::Rig& rig, Simulator& simulator,
    const plr::jobs::Store* store,
    const std::function<bool(const GenerateProgress&)>& on_progress) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  if (options.truck.horizon < 1 || options.truck.horizon > 50)
    return plr::make_error(PLR_ERR_INVALID,
                           fmt::format("horizon: {} is not in 1..50", options.truck.horizon));
  rig.set_fidelity(options.fidelity);
  simulator.set_fidelity(options.fidelity);
  auto started = starting_states(problem, rig);
  if (!started) return started.error();
  const std::vector<SimOutcome>& roots = *started;
  const std::vector<std::uint32_t> ids = particle_ids(problem, roots.size());
  TruckModel model(simulator, roots, options.truck, store);
  using K = TruckHeuristic::Kind;
  const TruckHeuristic anchor(model, K::kAnchor), lower(model, K::kLower),
      any(model, K::kAnyBoxLeft), boxes(model, K::kBoxesLeft), stack(model, K::kHighestStack);
  pomdp::PomhdpOptions po;
  po.epsilon1 = options.epsilon1;
  po.epsilon2 = options.epsilon2;
  po.seed = options.seed;
  po.target_gap = options.target_gap;
  po.max_depth = options.truck.horizon + 1;
  // The lower heuristic is an estimate, not a bound.
  po.prune_actions = false;
  GenerateResult out;
  sim::LibraryEntry& e = out.entry;
  GenerateProgress progress;
  progress.trial_budget = options.trials;
  const auto seconds = [&] { return std::chrono::duration<double>(Clock::now() - t0).count(); };
  try {
    pomdp::Pomhdp solver(model, anchor, lower, {&any, &boxes, &stack}, po);
    auto report = [&] {
      progress.trials = solver.total_trials();
      progress.nodes = solver.num_nodes();
      progress.results = model.results();
      progress.simulated = model.simulated();
      progress.lower = solver.lower();
      progress.upper = solver.upper();
      progress.wall_s = seconds();
      if (on_progress && !on_progress(progress)) throw Stopped{};
    };
    report();
    e.curve.push_back({seconds(), solver.lower(), solver.upper(), 0});
    while (solver.total_trials() < options.trials && seconds() < options.max_wall_s &&
           solver.upper() - solver.lower() > options.target_gap) {
      pomdp::Budget b;
      b.iterations = 1;
      solver.solve(b);
      e.curve.push_back({seconds(), solver.lower(), solver.upper(), solver.total_trials()});
      report();
    }
    progress.unrolling = true;
    report();
    out.tree = solver.policy_tree(options.truck.horizon, options.complete_tree);
    e.lower = solver.lower();
    e.upper = solver.upper();
    e.provenance.trials = solver.total_trials();
    e.provenance.nodes = solver.num_nodes();
  } catch (const SimulationError& err) {
    return plr::make_error(PLR_ERR_INTERNAL, problem.name + ": simulation failed: " + err.what());
  } catch (const Stopped&) {
    return plr::make_error(PLR_ERR_CANCELLED, problem.name + ": stopped");
  }
  e.name = problem.name;
  e.family = problem.family;
  e.world_seed = problem.world_seed;
  e.world = problem.world;
  e.observation_json = problem.observation_json;
  e.strategy = to_strategy(out.tree, problem.name);
  if (auto ok = sim::validate(e.strategy); !ok)
    return plr::make_error(PLR_ERR_INTERNAL, problem.name + ": " + ok.error().message);
  sim::Provenance& p = e.provenance;
  p.seed = options.seed;
  p.particles = static_cast<std::uint32_t>(roots.size());
  p.horizon = static_cast<std::uint32_t>(options.truck.horizon);
  p.trial_budget = options.trials;
  p.simulations = model.results();
  p.wall_s = seconds();
  p.workers = static_cast<std::uint32_t>(simulator.workers());
  p.epsilon1 = options.epsilon1;
  p.epsilon2 = options.epsilon2;
  p.seconds_per_box = options.truck.seconds_per_box;
  p.created = utc_now();
  if (!problem.parent.empty()) {
    e.parent = problem.parent;
    e.leaf = problem.leaf;
    for (std::size_t i = 0; i < roots.size(); ++i)
      e.start.push_back({ids[i], actions::state_hash(*roots[i].state), roots[i].boxes_left});
  }
  TreeValue at_level;
  try {
    out.leaves = find_leaves(model, e.strategy, ids);
    if (options.fidelity != sim::Fidelity::kFull)
      at_level = tree_value(model, e.strategy, roots.size());
  } catch (const SimulationError& err) {
    return plr::make_error(PLR_ERR_INTERNAL, problem.name + ": simulation failed: " + err.what());
  }
  out.simulated = model.simulated();
  out.simulated_robot_s = model.simulated_robot_s();
  out.simulated_wall_s = model.simulated_wall_s();
  if (options.fidelity != sim::Fidelity::kFull) {
    const auto c0 = Clock::now();
    const std::clock_t cpu0 = std::clock();
    e.fidelity = sim::to_string(options.fidelity);
    auto check = check_at_full(problem, e.strategy, options, at_level,
                               static_cast<std::uint32_t>(roots.size()), rig, simulator, store);
    if (!check) return check.error();
    e.check = *check;
    out.check_wall_s = std::chrono::duration<double>(Clock::now() - c0).count();
    out.check_cpu_s = static_cast<double>(std::clock() - cpu0) / CLOCKS_PER_SEC;
  }
  return out;
}

plr::Expected<std::vector<Leaf>> replay_leaves(const Problem& problem,
                                               const sim::LibraryEntry& entry,
                                               const GenerateOptions& options, actions::Rig& rig,
                                               Simulator& simulator,
                                               const plr::jobs::Store* store) {
  auto level = sim::parse_fidelity(entry.fidelity);
  if (!level) return plr::make_error(PLR_ERR_INVALID, entry.name + ": " + level.error().message);
  rig.set_fidelity(*level);
  simulator.set_fidelity(*level);
  auto roots = starting_states(problem, rig);
  if (!roots) return roots.error();
  TruckOptions truck = options.truck;
  if (entry.provenance.horizon > 0) truck.horizon = static_cast<int>(entry.provenance.horizon);
  const TruckModel model(simulator, *roots, truck, store);
  try {
    return find_leaves(model, entry.strategy, particle_ids(problem, roots->size()));
  } catch (const SimulationError& err) {
    return plr::make_error(PLR_ERR_INTERNAL, problem.name + ": simulation failed: " + err.what());
  }
}

std::vector<std::size_t> continued_leaves(const std::vector<Leaf>& leaves, double min_share) {
  // A continuation pays where runs get to (the share of particles) and by
  // what is left to unload there: on a tie of shares, the most boxes left.
  const auto left = [](const Leaf& l) {
    std::uint64_t n = 0;
    for (const SimOutcome& s : l.states) n += s.boxes_left;
    return l.states.empty() ? 0.0 : static_cast<double>(n) / static_cast<double>(l.states.size());
  };
  std::vector<std::size_t> out;
  std::optional<std::size_t> most;
  for (std::size_t i = 0; i < leaves.size(); ++i) {
    if (leaves[i].empty) continue;
    if (!most || leaves[i].particles.size() > leaves[*most].particles.size() ||
        (leaves[i].particles.size() == leaves[*most].particles.size() &&
         left(leaves[i]) > left(leaves[*most])))
      most = i;
    if (leaves[i].share >= min_share - 1e-12) out.push_back(i);
  }
  if (most && std::find(out.begin(), out.end(), *most) == out.end()) {
    out.push_back(*most);
    std::sort(out.begin(), out.end());
  }
  return out;
}

plr::Expected<Problem> continuation(const Problem& parent, const std::vector<Leaf>& leaves,
                                    std::size_t index, actions::Rig& rig) {
  const Leaf& leaf = leaves.at(index);
  if (leaf.empty || leaf.states.empty())
    return plr::make_error(PLR_ERR_INVALID,
                           fmt::format("{}: leaf {} has nothing to continue", parent.name, index));
  Problem p;
  p.name = fmt::format("{}.{}", parent.name, index + 1);
  p.family = parent.family;
  p.world_seed = parent.world_seed;
  p.observation_json = parent.observation_json;
  p.parent = parent.name;
  p.leaf = leaf.path;
  p.starts = leaf.states;
  p.particle_ids = leaf.particles;
  // W as the robot sees it there, as at a run's later states, where the
  // chooser looks for the nearest library world.
  auto memory = rig.restore(*leaf.states.front().state);
  if (!memory) return plr::make_error(memory.error().code, p.name + ": " + memory.error().message);
  auto seen = rig.backend().observe();
  if (!seen) return plr::make_error(seen.error().code, p.name + ": " + seen.error().message);
  p.world = sim::without_masses(seen->world);
  return p;
}

}  // namespace plr::generator
