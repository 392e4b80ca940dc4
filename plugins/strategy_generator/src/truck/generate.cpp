#include "truck/generate.hpp"

#include <fmt/format.h>

#include <chrono>
#include <ctime>

#include "plr/pomdp/pomhdp.hpp"
#include "plr/sim/physics.hpp"
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
  if (problem.particles.empty())
    return plr::make_error(PLR_ERR_INVALID, problem.name + ": no particles");
  if (options.truck.horizon < 1 || options.truck.horizon > 50)
    return plr::make_error(PLR_ERR_INVALID,
                           fmt::format("horizon: {} is not in 1..50", options.truck.horizon));
  std::vector<SimOutcome> roots;
  for (const sim::World& w : problem.particles) {
    auto r = actions::start_state(rig, w);
    if (!r) return plr::make_error(r.error().code, problem.name + ": " + r.error().message);
    roots.push_back(std::move(*r));
  }
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
  p.particles = static_cast<std::uint32_t>(problem.particles.size());
  p.horizon = static_cast<std::uint32_t>(options.truck.horizon);
  p.trial_budget = options.trials;
  p.simulations = model.results();
  p.wall_s = seconds();
  p.workers = static_cast<std::uint32_t>(simulator.workers());
  p.epsilon1 = options.epsilon1;
  p.epsilon2 = options.epsilon2;
  p.seconds_per_box = options.truck.seconds_per_box;
  p.created = utc_now();
  out.simulated = model.simulated();
  out.simulated_robot_s = model.simulated_robot_s();
  out.simulated_wall_s = model.simulated_wall_s();
  return out;
}

}  // namespace plr::generator
