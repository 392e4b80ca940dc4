#include "plr/actions/in_process.hpp"

#include <chrono>

#include "plr/sim/collision.hpp"

namespace plr::actions {

namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

}  // namespace

struct InProcessBackend::Impl {
  UnloaderSimulation& simulation;
  planning::Planner& planner;
  InProcessOptions options;
  // Kept from query to query: the planner scopes its held and ignored boxes
  // to each plan() call, so only the world changes in between.
  std::unique_ptr<sim::CollisionChecker> checker;
  InProcessStats stats;
};

InProcessBackend::InProcessBackend(UnloaderSimulation& simulation, planning::Planner& planner,
                                   InProcessOptions options)
    : impl_(std::make_unique<Impl>(Impl{simulation, planner, options, nullptr, {}})) {}
InProcessBackend::~InProcessBackend() = default;

plr::Expected<Perceived> InProcessBackend::observe() {
  const auto t0 = Clock::now();
  const UnloaderSimulation& s = impl_->simulation;
  Perceived p{s.perceived(), s.q(), s.held(), s.boxes_unloaded(), s.time()};
  impl_->stats.observe_s += seconds_since(t0);
  return p;
}

plr::Expected<planning::DecodedPlanResponse> InProcessBackend::plan(
    const planning::PlanQuery& query, const sim::World& world) {
  Impl& m = *impl_;
  auto t0 = Clock::now();
  if (m.checker && m.options.reuse_checker)
    m.checker->set_world(world);
  else
    m.checker = std::make_unique<sim::CollisionChecker>(m.simulation.robot(), world);
  m.stats.checker_s += seconds_since(t0);
  t0 = Clock::now();
  const planning::PlanResult r = m.planner.plan(query, *m.checker);
  m.stats.plan_s += seconds_since(t0);
  ++m.stats.queries;
  t0 = Clock::now();
  planning::DecodedPlanResponse d;
  d.status = r.status;
  d.message = r.message;
  d.planner = m.planner.name();
  d.stats = r.stats;
  if (!r.trajectory.empty()) {
    for (const auto& [t, s] : r.trajectory.sampled(0.02))
      d.points.push_back({t, s.position, s.velocity});
  }
  m.stats.sample_s += seconds_since(t0);
  return d;
}

plr::Expected<Executed> InProcessBackend::execute(const Motion& motion) {
  const auto t0 = Clock::now();
  auto executed = impl_->simulation.execute(motion);
  impl_->stats.execute_s += seconds_since(t0);
  ++impl_->stats.motions;
  return executed;
}

const InProcessStats& InProcessBackend::stats() const {
  return impl_->stats;
}

void InProcessBackend::reset_stats() {
  impl_->stats = {};
}

}  // namespace plr::actions
