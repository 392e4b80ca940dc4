#include "truck/fidelity_check.hpp"

#include <fmt/format.h>

#include "plr/sim/generators.hpp"
#include "truck/generate.hpp"

namespace plr::generator {

TreeValue tree_value(const TruckModel& model, const sim::Strategy& strategy,
                     std::size_t particles) {
  TreeValue out;
  if (particles == 0) return out;
  const TruckOptions& o = model.options();
  pomdp::Rng rng;
  for (std::size_t i = 0; i < particles; ++i) {
    auto state = static_cast<pomdp::StateId>(i);
    const std::uint32_t start_boxes = model.state(state).boxes_left;
    double value = 0.0;
    std::uint32_t node = strategy.root;
    while (!model.is_terminal(state)) {
      const pomdp::Step s =
          model.step(state, static_cast<pomdp::ActionId>(strategy.nodes[node].action), rng);
      value += s.reward;
      state = s.next;
      if (s.terminal) break;
      const auto child =
          strategy.next(node, static_cast<sim::Observation>(model.state(state).observation));
      if (!child) {
        const TruckModel::State& at = model.state(state);
        value -= (o.horizon - at.depth) * o.min_action_s + o.seconds_per_box * at.boxes_left;
        break;
      }
      node = *child;
    }
    out.value += value;
    out.boxes += start_boxes - model.state(state).boxes_left;
  }
  out.value /= static_cast<double>(particles);
  out.boxes /= static_cast<double>(particles);
  return out;
}

namespace {

plr::Expected<std::vector<SimOutcome>> fresh_particles(const Problem& problem, std::uint64_t seed,
                                                       std::uint32_t n, actions::Rig& rig) {
  const auto family = sim::parse_env_family(problem.family);
  if (!family)
    return plr::make_error(PLR_ERR_INVALID,
                           problem.name + ": family '" + problem.family + "' has no mass prior");
  std::vector<SimOutcome> out;
  for (std::uint32_t j = 0; j < n; ++j) {
    const std::uint64_t masses = sim::particle_seed(seed, static_cast<int>(kFreshParticle + j));
    if (problem.starts.empty()) {
      auto r = actions::start_state(rig, sim::sample_masses(problem.world, *family, masses));
      if (!r) return plr::make_error(r.error().code, problem.name + ": " + r.error().message);
      out.push_back(std::move(*r));
      continue;
    }
    // A continuation's belief is made of states the parent reached: the
    // same state with other masses is a fresh particle of it.
    const SimOutcome& base = problem.starts[j % problem.starts.size()];
    auto memory = rig.restore(*base.state);
    if (!memory)
      return plr::make_error(memory.error().code, problem.name + ": " + memory.error().message);
    const sim::World drawn = sim::sample_masses(rig.simulation().perceived(), *family, masses);
    std::vector<std::pair<std::uint32_t, double>> list;
    for (const sim::Box& b : drawn.boxes) list.emplace_back(b.id, b.mass);
    if (auto ok = rig.simulation().set_masses(list); !ok)
      return plr::make_error(ok.error().code, problem.name + ": " + ok.error().message);
    SimOutcome o = base;
    o.state = std::make_shared<const std::vector<std::uint8_t>>(rig.snapshot(*memory));
    out.push_back(std::move(o));
  }
  return out;
}

}  // namespace

plr::Expected<sim::FidelityCheck> check_at_full(const Problem& problem,
                                                const sim::Strategy& strategy,
                                                const GenerateOptions& options, TreeValue at_level,
                                                std::uint32_t particles, actions::Rig& rig,
                                                Simulator& simulator,
                                                const plr::jobs::Store* store) {
  const sim::Fidelity rig_level = rig.simulation().physics().fidelity();
  const sim::Fidelity level = simulator.fidelity();
  rig.set_fidelity(sim::Fidelity::kFull);
  simulator.set_fidelity(sim::Fidelity::kFull);
  const auto restore = [&] {
    rig.set_fidelity(rig_level);
    simulator.set_fidelity(level);
  };
  auto roots = fresh_particles(problem, options.seed, particles, rig);
  if (!roots) {
    restore();
    return roots.error();
  }
  sim::FidelityCheck c;
  c.value = at_level.value;
  c.boxes = at_level.boxes;
  c.full_particles = particles;
  c.first_particle = kFreshParticle;
  try {
    const TruckModel model(simulator, *roots, options.truck, store);
    const TreeValue full = tree_value(model, strategy, roots->size());
    c.full_value = full.value;
    c.full_boxes = full.boxes;
  } catch (const SimulationError& err) {
    restore();
    return plr::make_error(PLR_ERR_INTERNAL,
                           problem.name + ": simulation at full fidelity failed: " + err.what());
  }
  restore();
  return c;
}

}  // namespace plr::generator
