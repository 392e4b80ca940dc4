#include "plr/actions/rig.hpp"

#include "plr/actions/state_bytes.hpp"
#include "plr/sim/shipped_files.hpp"

namespace plr::actions {

Rig::Rig(sim::RobotModel robot, planning::LatticeConfig lattice, ActionOptions options)
    : robot_(std::move(robot)),
      planner_(std::move(lattice)),
      model_(robot_, std::move(options)),
      simulation_(robot_, sim::World{}),
      backend_(simulation_, planner_) {
  // An outcome here must be a function of the state it starts from (a
  // snapshot restored elsewhere runs on bit for bit): no answers that depend
  // on the queries before.
  planner_.set_experience(false);
}

plr::Expected<std::unique_ptr<Rig>> Rig::create(ActionOptions options) {
  auto robot = sim::load_robot();
  if (!robot) return robot.error();
  const auto lattice_file = sim::shipped_file("robots/unloader_lattice.yaml");
  if (!lattice_file) return lattice_file.error();
  auto lattice = planning::LatticeConfig::from_file(lattice_file->string());
  if (!lattice) return lattice.error();
  if (auto ok = options.check(); !ok) return ok.error();
  return std::unique_ptr<Rig>(new Rig(std::move(*robot), std::move(*lattice), std::move(options)));
}

void Rig::reset(const sim::World& truth) {
  UnloaderOptions options;
  options.fidelity = fidelity_;
  simulation_ = UnloaderSimulation(robot_, truth, home_configuration(), options);
}

void Rig::set_fidelity(sim::Fidelity fidelity) {
  fidelity_ = fidelity;
  simulation_.set_fidelity(fidelity);
}

std::vector<std::uint8_t> Rig::snapshot(const Memory& memory) const {
  flatbuffers::FlatBufferBuilder fbb;
  fbb.Finish(build(fbb, SimState{simulation_.save(), memory}));
  return {fbb.GetBufferPointer(), fbb.GetBufferPointer() + fbb.GetSize()};
}

plr::Expected<Memory> Rig::restore(const std::vector<std::uint8_t>& bytes) {
  flatbuffers::Verifier verifier(bytes.data(), bytes.size());
  if (!verifier.VerifyBuffer<plr::msg::TruckState>(nullptr))
    return plr::make_error(PLR_ERR_INVALID, "state: not a TruckState");
  auto state = from_message(*flatbuffers::GetRoot<plr::msg::TruckState>(bytes.data()), "state");
  if (!state) return state.error();
  simulation_.restore(*state->saved);
  return std::move(state->memory);
}

}  // namespace plr::actions
