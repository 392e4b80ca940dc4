#include "truck/strategy_job.hpp"

#include <fmt/format.h>

#include <filesystem>

#include <nlohmann/json.hpp>

#include "plr/actions/simulation_job.hpp"
#include "plr/jobs/in_process_runner.hpp"
#include "plr/jobs/store.hpp"
#include "plr/sim/world_io.hpp"

namespace plr::generator {

namespace {

plr::Error invalid(const std::string& what) {
  return plr::make_error(PLR_ERR_INVALID, "generator.strategy job: " + what);
}

}  // namespace

plr::Expected<Problem> make_problem(const StrategyJob& job) {
  Problem problem;
  if (job.world.file.empty()) {
    problem = make_problem(job.world.family, job.world.seed, job.particles, job.seed);
  } else {
    auto world = sim::load_world(job.world.file);
    if (!world) return world.error();
    problem = make_problem(*world, job.world.family,
                           std::filesystem::path(job.world.file).stem().string(), job.particles,
                           job.seed);
  }
  problem.observation_json = job.observation_json;
  return problem;
}

jobs::Bytes encode(const StrategyJob& job) {
  const GenerateOptions& o = job.options;
  const TruckOptions& t = o.truck;
  nlohmann::json j = {
      {"family", sim::to_string(job.world.family)},
      {"seed", job.world.seed},
      {"file", job.world.file},
      {"particles", job.particles},
      {"particle_seed", job.seed},
      {"observation", job.observation_json},
      {"checkpoint_dir", job.checkpoint_dir},
      {"truck",
       {t.horizon, t.seconds_per_box, t.action_s, t.min_action_s, t.max_boxes_per_action,
        t.min_seconds_per_box}},
      {"epsilon", {o.epsilon1, o.epsilon2}},
      {"solver_seed", o.seed},
      {"trials", o.trials},
      {"target_gap", o.target_gap},
      {"complete_tree", o.complete_tree},
      // JSON has no infinity: no limit is null.
      {"max_wall_s", std::isfinite(o.max_wall_s) ? nlohmann::json(o.max_wall_s) : nullptr}};
  // Absent at full fidelity: a full job's input is what it was before the setting.
  if (o.fidelity != sim::Fidelity::kFull) j["fidelity"] = sim::to_string(o.fidelity);
  return jobs::to_bytes(j.dump());
}

plr::Expected<StrategyJob> decode_strategy_job(const jobs::Bytes& bytes) {
  const auto j = nlohmann::json::parse(bytes.begin(), bytes.end(), nullptr, false);
  if (j.is_discarded() || !j.is_object()) return invalid("its input is not a JSON object");
  try {
    StrategyJob job;
    const auto family = sim::parse_env_family(j.at("family").get<std::string>());
    if (!family) return invalid("unknown family " + j.at("family").dump());
    job.world = {*family, j.at("seed").get<std::uint64_t>(), j.at("file").get<std::string>()};
    job.particles = j.at("particles").get<int>();
    if (job.particles < 1 || job.particles > 100) return invalid("particles not in 1..100");
    job.seed = j.at("particle_seed").get<std::uint64_t>();
    job.observation_json = j.at("observation").get<std::string>();
    job.checkpoint_dir = j.at("checkpoint_dir").get<std::string>();
    const auto& t = j.at("truck");
    if (!t.is_array() || t.size() != 6) return invalid("truck: 6 numbers expected");
    TruckOptions& truck = job.options.truck;
    truck.horizon = t[0].get<int>();
    if (truck.horizon < 1 || truck.horizon > 50) return invalid("horizon not in 1..50");
    truck.seconds_per_box = t[1].get<double>();
    truck.action_s = t[2].get<double>();
    truck.min_action_s = t[3].get<double>();
    truck.max_boxes_per_action = t[4].get<double>();
    truck.min_seconds_per_box = t[5].get<double>();
    const auto& e = j.at("epsilon");
    if (!e.is_array() || e.size() != 2) return invalid("epsilon: 2 numbers expected");
    job.options.epsilon1 = e[0].get<double>();
    job.options.epsilon2 = e[1].get<double>();
    job.options.seed = j.at("solver_seed").get<std::uint64_t>();
    job.options.trials = j.at("trials").get<std::uint64_t>();
    if (job.options.trials < 1 || job.options.trials > 10'000'000)
      return invalid("trials not in 1..10000000");
    job.options.target_gap = j.at("target_gap").get<double>();
    job.options.complete_tree = j.at("complete_tree").get<bool>();
    if (!j.at("max_wall_s").is_null()) job.options.max_wall_s = j.at("max_wall_s").get<double>();
    if (j.contains("fidelity")) {
      const auto level = sim::parse_fidelity(j.at("fidelity").get<std::string>());
      if (!level) return invalid(level.error().message);
      job.options.fidelity = *level;
    }
    return job;
  } catch (const nlohmann::json::exception& e) {
    return invalid(e.what());
  }
}

void add_strategy_job(jobs::Kinds& kinds) {
  kinds.add(kStrategyKind, [](const jobs::Bytes& input) -> plr::Expected<jobs::Bytes> {
    auto job = decode_strategy_job(input);
    if (!job) return job.error();
    auto problem = make_problem(*job);
    if (!problem) return problem.error();
    auto rig = actions::make_rig(job->observation_json);
    if (!rig) return rig.error();
    jobs::Kinds simulations;
    actions::add_sim_action(simulations);
    jobs::InProcessRunner runner(simulations);
    Simulator simulator(runner, 1, job->observation_json);
    std::optional<jobs::Store> store;
    if (!job->checkpoint_dir.empty()) {
      auto opened = jobs::Store::open(std::filesystem::path(job->checkpoint_dir) / problem->name);
      if (!opened) return opened.error();
      store.emplace(std::move(*opened));
    }
    auto result = generate(*problem, job->options, **rig, simulator, store ? &*store : nullptr);
    if (!result) return result.error();
    sim::Library one;
    one.entries.push_back(std::move(result->entry));
    return sim::serialize(one);
  });
}

}  // namespace plr::generator
