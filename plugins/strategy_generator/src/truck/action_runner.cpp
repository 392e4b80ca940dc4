#include "truck/action_runner.hpp"

#include <plr/msg/generator_generated.h>

#include <algorithm>
#include <chrono>

#include "plr/actions/in_process.hpp"
#include "plr/actions/state_bytes.hpp"
#include "plr/planning/lattice_planner.hpp"
#include "plr/sim/shipped_files.hpp"

namespace plr::generator {

struct ActionRunner::Impl {
  sim::RobotModel robot;
  planning::LatticePlanner planner;
  actions::ActionModel model;
  actions::UnloaderSimulation simulation;
  actions::InProcessBackend backend;

  Impl(sim::RobotModel r, planning::LatticeConfig lattice, actions::ActionOptions options)
      : robot(std::move(r)),
        planner(std::move(lattice)),
        model(robot, std::move(options)),
        simulation(robot, sim::World{}),
        backend(simulation, planner) {}

  // Looks at the simulation's state after `memory`'s actions.
  plr::Expected<SimOutcome> describe(const actions::Memory& memory) {
    auto seen = backend.observe();
    if (!seen) return seen.error();
    SimOutcome o;
    const sim::SceneAnalysis scene = model.scene(*seen, memory);
    o.observation = scene.observation ? static_cast<int>(*scene.observation) : kEmptyObservation;
    o.boxes_left = static_cast<std::uint32_t>(seen->world.boxes.size());
    for (const sim::Box& b : seen->world.boxes) {
      o.highest_stack_m = std::max(o.highest_stack_m, sim::bounds(b).z1);
    }
    flatbuffers::FlatBufferBuilder fbb;
    fbb.Finish(actions::build(fbb, actions::SimState{simulation.save(), memory}));
    o.state = std::make_shared<const std::vector<std::uint8_t>>(
        fbb.GetBufferPointer(), fbb.GetBufferPointer() + fbb.GetSize());
    return o;
  }
};

ActionRunner::ActionRunner(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
ActionRunner::~ActionRunner() = default;

plr::Expected<std::unique_ptr<ActionRunner>> ActionRunner::create(
    const sim::ObservationParams& observation) {
  auto robot = sim::load_robot();
  if (!robot) return robot.error();
  const auto lattice_file = sim::shipped_file("robots/unloader_lattice.yaml");
  if (!lattice_file) return lattice_file.error();
  auto lattice = planning::LatticeConfig::from_file(lattice_file->string());
  if (!lattice) return lattice.error();
  actions::ActionOptions options;
  options.observation = observation;
  if (auto ok = options.check(); !ok) return ok.error();
  return std::unique_ptr<ActionRunner>(new ActionRunner(
      std::make_unique<Impl>(std::move(*robot), std::move(*lattice), std::move(options))));
}

const actions::ActionModel& ActionRunner::model() const {
  return impl_->model;
}

plr::Expected<SimOutcome> ActionRunner::start(const sim::World& truth) {
  impl_->simulation = actions::UnloaderSimulation(impl_->robot, truth);
  return impl_->describe({});
}

plr::Expected<SimOutcome> ActionRunner::run(const SimRequest& request) {
  const auto t0 = std::chrono::steady_clock::now();
  const auto* message = flatbuffers::GetRoot<plr::msg::TruckState>(request.state->data());
  auto state = actions::from_message(*message, "state");
  if (!state) return state.error();
  impl_->simulation.restore(*state->saved);
  actions::Memory memory = std::move(state->memory);
  auto outcome = impl_->model.run(request.action, impl_->backend, memory);
  if (!outcome)
    return plr::make_error(outcome.error().code,
                           sim::to_string(request.action) + ": " + outcome.error().message);
  auto o = impl_->describe(memory);
  if (!o) return o.error();
  o->applicable = outcome->applicable;
  o->boxes = outcome->boxes;
  o->robot_time_s = outcome->robot_time_s;
  o->wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return o;
}

std::vector<plr::Expected<SimOutcome>> LocalSimulator::run(const std::vector<SimRequest>& batch) {
  std::vector<plr::Expected<SimOutcome>> out;
  out.reserve(batch.size());
  busy_ = 1;
  for (const SimRequest& r : batch) out.push_back(runner_.run(r));
  busy_ = 0;
  return out;
}

}  // namespace plr::generator
