#include "plr/actions/in_process.hpp"

#include "plr/sim/collision.hpp"

namespace plr::actions {

struct InProcessBackend::Impl {
  UnloaderSimulation& simulation;
  planning::Planner& planner;
};

InProcessBackend::InProcessBackend(UnloaderSimulation& simulation, planning::Planner& planner)
    : impl_(std::make_unique<Impl>(Impl{simulation, planner})) {}
InProcessBackend::~InProcessBackend() = default;

plr::Expected<Perceived> InProcessBackend::observe() {
  const UnloaderSimulation& s = impl_->simulation;
  return Perceived{s.perceived(), s.q(), s.held(), s.boxes_unloaded(), s.time()};
}

plr::Expected<planning::DecodedPlanResponse> InProcessBackend::plan(
    const planning::PlanQuery& query, const sim::World& world) {
  sim::CollisionChecker checker(impl_->simulation.robot(), world);
  const planning::PlanResult r = impl_->planner.plan(query, checker);
  planning::DecodedPlanResponse d;
  d.status = r.status;
  d.message = r.message;
  d.planner = impl_->planner.name();
  d.stats = r.stats;
  if (!r.trajectory.empty()) {
    for (const auto& [t, s] : r.trajectory.sampled(0.02))
      d.points.push_back({t, s.position, s.velocity});
  }
  return d;
}

plr::Expected<Executed> InProcessBackend::execute(const Motion& motion) {
  return impl_->simulation.execute(motion);
}

}  // namespace plr::actions
