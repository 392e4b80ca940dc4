#include "plr/actions/job_runner.hpp"

#include <algorithm>
#include <chrono>

#include <nlohmann/json.hpp>

namespace plr::actions {

plr::Expected<std::unique_ptr<JobRunner>> JobRunner::create(
    const sim::ObservationParams& observation) {
  ActionOptions options;
  options.observation = observation;
  auto rig = Rig::create(std::move(options));
  if (!rig) return rig.error();
  return std::unique_ptr<JobRunner>(new JobRunner(std::move(*rig)));
}

plr::Expected<std::unique_ptr<JobRunner>> JobRunner::create(const std::string& observation_json) {
  const auto parsed = nlohmann::json::parse(observation_json, nullptr, false);
  if (parsed.is_discarded() || !parsed.is_object())
    return plr::make_error(PLR_ERR_INVALID, "observation_json: not a JSON object");
  auto params = sim::ObservationParams::from_json(parsed);
  if (!params)
    return plr::make_error(PLR_ERR_INVALID, "observation_json: " + params.error().message);
  return create(*params);
}

plr::Expected<SimOutcome> JobRunner::describe(const Memory& memory) {
  auto seen = rig_->backend().observe();
  if (!seen) return seen.error();
  SimOutcome o;
  const sim::SceneAnalysis scene = rig_->model().scene(*seen, memory);
  o.observation = scene.observation ? static_cast<int>(*scene.observation) : kEmptyObservation;
  o.boxes_left = static_cast<std::uint32_t>(seen->world.boxes.size());
  for (const sim::Box& b : seen->world.boxes) {
    o.highest_stack_m = std::max(o.highest_stack_m, sim::bounds(b).z1);
  }
  o.state = std::make_shared<const std::vector<std::uint8_t>>(rig_->snapshot(memory));
  return o;
}

plr::Expected<SimOutcome> JobRunner::start(const sim::World& truth) {
  rig_->reset(truth);
  return describe({});
}

plr::Expected<SimOutcome> JobRunner::run(const SimRequest& request) {
  const auto t0 = std::chrono::steady_clock::now();
  auto memory = rig_->restore(*request.state);
  if (!memory) return memory.error();
  auto outcome = rig_->model().run(request.action, rig_->backend(), *memory);
  if (!outcome)
    return plr::make_error(outcome.error().code,
                           sim::to_string(request.action) + ": " + outcome.error().message);
  auto o = describe(*memory);
  if (!o) return o.error();
  o->applicable = outcome->applicable;
  o->boxes = outcome->boxes;
  o->robot_time_s = outcome->robot_time_s;
  o->wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return o;
}

}  // namespace plr::actions
