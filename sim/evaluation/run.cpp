#include "plr/evaluation/run.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <chrono>
#include <fstream>
#include <iterator>
#include <memory>
#include <optional>
#include <set>

#include <plr/frame.hpp>

#include "plr/actions/run_stats.hpp"
#include "plr/chooser/features.hpp"
#include "plr/episode/engine.hpp"
#include "plr/sim/physics.hpp"
#include "plr/sim/world_io.hpp"

namespace plr::evaluation {

namespace {

// Masses drawn for an evaluation seed: apart from the generator's particles
// (sim::particle_seed(generator seed, particle)).
constexpr std::uint64_t kMassStream = 0x6576616c;  // "eval"

std::uint64_t mass_seed(std::uint64_t seed) {
  return sim::particle_seed(seed ^ (kMassStream << 32), 0);
}

std::vector<const sim::LibraryEntry*> training_entries(const Resources& r, sim::EnvFamily family) {
  std::vector<const sim::LibraryEntry*> out;
  // Continuations start mid-trailer: a training world is a strategy's for a fresh one.
  for (const auto& e : r.library.entries)
    if (e.family == sim::to_string(family) && !e.is_continuation()) out.push_back(&e);
  return out;
}

// The entry with its continuations (load_resources makes them), if known.
const sim::Chain* chain_of(const Resources& r, const sim::LibraryEntry* entry) {
  const auto i = static_cast<std::size_t>(entry - r.library.entries.data());
  return i < r.chains.size() ? &r.chains[i] : nullptr;
}

bool excluded_root(const sim::Strategy& s, const episode::RunRules& rules) {
  return rules.excluded(s.nodes[s.root].action);
}

// The sources of the methods: where each run's strategies come from.
episode::StrategySource method_source(const EvaluationSettings& settings, const Resources& r,
                                      Method method, const sim::LibraryEntry* own) {
  const episode::StrategySource h = episode::hardcoded_source(settings.h);
  switch (method) {
    case Method::kHardcoded:
      return h;
    case Method::kOpenLoop:
    case Method::kExpectedOffline: {
      // The precomputed sequence from the start, followed as it was
      // generated: the training world's strategy and, where its tree ends,
      // the continuation for the leaf reached (grafted: plr/sim/chain.hpp),
      // and nothing after the last.
      const sim::Chain* c = chain_of(r, own);
      const sim::Strategy& chained = c ? c->strategy : own->strategy;
      auto used = std::make_shared<bool>(false);
      return [own, used, &chained](
                 const actions::Perceived&, const sim::SceneAnalysis&,
                 const episode::RunRules&) -> plr::Expected<episode::StrategyChoice> {
        if (*used)
          return episode::StrategyChoice{
              std::nullopt, "library:" + own->name,
              "the precomputed strategy ended (its tree ended or did not plan for what was "
              "seen)"};
        *used = true;
        return episode::StrategyChoice{chained, "library:" + own->name, {}, true};
      };
    }
    case Method::kNearest:
    case Method::kPlr: {
      const bool plr = method == Method::kPlr;
      const double max_distance = settings.max_distance;
      const sim::ObservationParams obs = settings.observation;
      return [&r, h, plr, max_distance, obs](
                 const actions::Perceived& seen, const sim::SceneAnalysis& scene,
                 const episode::RunRules& rules) -> plr::Expected<episode::StrategyChoice> {
        const chooser::Features f = chooser::features(seen.world, obs);
        const chooser::Nearest nn = r.index->nearest(r.model->scaling().apply(f));
        const sim::LibraryEntry& entry = r.library.entries[nn.entry];
        if (!plr) {
          // NN alone follows its strategies as generated, and has nothing
          // else to run: a first action that moved nothing here would only
          // be tried again.
          if (excluded_root(entry.strategy, rules))
            return episode::StrategyChoice{
                std::nullopt, "library:" + entry.name,
                fmt::format("the nearest strategy {}'s first action moved nothing here",
                            entry.name)};
          return episode::StrategyChoice{entry.strategy, "library:" + entry.name, {}, true};
        }
        // As the strategy_chooser plug-in decides.
        const chooser::Verdict verdict = r.model->decide(f);
        if ((max_distance <= 0 || nn.distance <= max_distance) && verdict.nearest &&
            !excluded_root(entry.strategy, rules))
          return episode::StrategyChoice{entry.strategy, "library:" + entry.name, {}};
        return h(seen, scene, rules);
      };
    }
  }
  return h;
}

// How a whole-trailer run ended: emptied, cut at the robot-time cap or the
// action limit, or stopped before them with no action left that moves a box.
const char* ending(const EvaluationSettings& settings, const episode::Episode& e) {
  if (e.final_world.boxes.empty()) return "empty";
  if (settings.max_robot_time_s > 0 && e.robot_time_s >= settings.max_robot_time_s) return "cap";
  if (settings.max_actions > 0 && e.actions >= settings.max_actions) return "action limit";
  return "stuck";
}

// Which library entry of a chain each action came from (the link), for
// open-loop and expected-offline.
class LinkRecorder final : public episode::Observer {
 public:
  LinkRecorder(const sim::Library& library, const sim::Chain& chain)
      : library_(library), chain_(chain) {}
  void starting(const episode::ActionStart& a, const episode::Episode&) override {
    pending_ = a.node < chain_.entry_of_node.size() && a.strategy.name == chain_.strategy.name
                   ? library_.entries[chain_.entry_of_node[a.node]].name
                   : std::string();
  }
  void recorded(const episode::EpisodeStep&, const episode::Episode&) override {
    links_.push_back(pending_);
  }
  const std::vector<std::string>& links() const { return links_; }

 private:
  const sim::Library& library_;
  const sim::Chain& chain_;
  std::string pending_;
  std::vector<std::string> links_;
};

}  // namespace

plr::Expected<Resources> load_resources(const EvaluationSettings& settings) {
  Resources r;
  const bool uses_model =
      std::any_of(settings.methods.begin(), settings.methods.end(),
                  [](Method m) { return m == Method::kNearest || m == Method::kPlr; });
  const bool uses_library = uses_model ||
                            std::any_of(settings.methods.begin(), settings.methods.end(),
                                        [](Method m) { return needs_training_world(m); }) ||
                            std::any_of(settings.environments.begin(), settings.environments.end(),
                                        [](const Environment& e) { return e.training; });
  if (uses_library) {
    if (!std::filesystem::exists(settings.library))
      return plr::make_error(
          PLR_ERR_UNAVAILABLE,
          fmt::format("{}: no library; make it with `plr run configs/generate.yaml --report {}`",
                      settings.library.string(), settings.library.parent_path().string()));
    auto library = sim::load_library(settings.library);
    if (!library) return library.error();
    if (library->entries.empty())
      return plr::make_error(PLR_ERR_INVALID, settings.library.string() + ": the library is empty");
    r.library = std::move(*library);
    for (std::size_t i = 0; i < r.library.entries.size(); ++i) {
      // Runs start from strategies for fresh trailers; a continuation
      // stands for itself.
      if (r.library.entries[i].is_continuation()) {
        const sim::LibraryEntry& e = r.library.entries[i];
        r.chains.push_back({e.strategy, std::vector<std::size_t>(e.strategy.nodes.size(), i), 1});
        continue;
      }
      auto chain = sim::chain(r.library, i);
      if (!chain)
        return plr::make_error(PLR_ERR_INVALID,
                               settings.library.string() + ": " + chain.error().message);
      r.chains.push_back(std::move(*chain));
    }
  }
  if (uses_model) {
    if (!std::filesystem::exists(settings.model))
      return plr::make_error(PLR_ERR_UNAVAILABLE,
                             fmt::format("{}: no chooser model; train it with `plr chooser train "
                                         "configs/train_chooser.yaml`",
                                         settings.model.string()));
    auto model = chooser::Model::load(settings.model);
    if (!model) return model.error();
    if (model->library_crc() != chooser::fingerprint(r.library))
      return plr::make_error(
          PLR_ERR_INVALID,
          fmt::format("{}: trained with another library (CRC {:08x}, {} is {:08x}); train it "
                      "again with `plr chooser train configs/train_chooser.yaml`",
                      settings.model.string(), model->library_crc(), settings.library.string(),
                      chooser::fingerprint(r.library)));
    r.index.emplace(r.library, model->scaling(), settings.observation);
    r.model.emplace(std::move(*model));
  }
  for (const Environment& e : settings.environments)
    if (e.training && training_entries(r, e.family).empty())
      return plr::make_error(
          PLR_ERR_INVALID,
          fmt::format("{}: no {} strategy, so the training environment {} has no world",
                      settings.library.string(), sim::to_string(e.family), e.name));
  return r;
}

std::string run_key(const EvaluationSettings& settings, const RunSpec& run) {
  return fmt::format("{}_{}_seed{}{}", settings.environments[run.environment].name,
                     to_string(run.method), run.seed, run.full_check ? "_full" : "");
}

bool applies(const EvaluationSettings& settings, const RunSpec& run) {
  return !needs_training_world(run.method) || settings.environments[run.environment].training;
}

std::vector<RunSpec> plan_runs(const EvaluationSettings& settings, std::uint64_t seeds) {
  std::vector<RunSpec> out;
  const bool checks = settings.fidelity != sim::Fidelity::kFull;
  for (const bool check : {false, true}) {
    if (check && !checks) break;
    const std::uint64_t n = check ? std::min(seeds, settings.fidelity_check_seeds) : seeds;
    for (std::size_t e = 0; e < settings.environments.size(); ++e)
      for (const Method m : settings.methods)
        for (std::uint64_t s = settings.first_seed; s < settings.first_seed + n; ++s)
          if (const RunSpec spec{e, m, s, check}; applies(settings, spec)) out.push_back(spec);
  }
  return out;
}

plr::Expected<StartWorld> start_world(const EvaluationSettings& settings,
                                      const Resources& resources, const RunSpec& run) {
  const Environment& env = settings.environments[run.environment];
  StartWorld w;
  if (env.training) {
    // The library's worlds in turn, with masses the generator did not plan
    // with: as a trailer of a known layout would come.
    const auto entries = training_entries(resources, env.family);
    w.entry = entries[(run.seed - settings.first_seed) % entries.size()];
    const sim::LibraryEntry& e = *w.entry;
    if (run.method == Method::kExpectedOffline) {
      // The masses of one of the generator's particles: the world as the
      // strategy expected it, so each observation is one it planned for.
      const auto particles = std::max<std::uint32_t>(1, e.provenance.particles);
      const int p = static_cast<int>((run.seed - settings.first_seed) % particles);
      w.truth = sim::sample_masses(e.world, env.family, sim::particle_seed(e.provenance.seed, p));
      w.name = fmt::format("{}, particle {}", e.name, p);
    } else {
      w.truth = sim::sample_masses(e.world, env.family, mass_seed(run.seed));
      w.name = fmt::format("{}, masses of seed {}", e.name, run.seed);
    }
  } else if (!env.world.empty()) {
    auto world = sim::load_world(env.world);
    if (!world) return world.error();
    w.truth = sim::sample_masses(sim::without_masses(*world), env.family, mass_seed(run.seed));
    w.name = fmt::format("{}, masses of seed {}", env.world.filename().string(), run.seed);
  } else {
    w.truth = sim::make_environment(env.family, run.seed);
    w.name = fmt::format("{}:{}", sim::to_string(env.family), run.seed);
  }
  return w;
}

nlohmann::json run_conditions(const EvaluationSettings& settings, const Resources& resources) {
  const sim::ObservationParams& o = settings.observation;
  nlohmann::json out = {
      {"max_robot_time_s", settings.max_robot_time_s},
      {"max_actions", settings.max_actions},
      {"max_distance", settings.max_distance},
      {"observation",
       {o.h_pile, o.wall_depth, o.min_pile_depth, o.pile_mid, o.pile_high, o.wall_mid, o.wall_high,
        o.side_band}},
      {"h", {settings.h.h_min, settings.h.d_min}},
      {"library", fmt::format("{:08x}", chooser::fingerprint(resources.library))}};
  // Only below full, so folders of full-fidelity runs made before the
  // setting existed keep their conditions.
  if (settings.fidelity != sim::Fidelity::kFull)
    out["fidelity"] = sim::to_string(settings.fidelity);
  if (resources.model) {
    std::ifstream in(settings.model, std::ios::binary);
    const std::vector<std::uint8_t> bytes{std::istreambuf_iterator<char>(in), {}};
    out["model"] = fmt::format("{:08x}", plr::crc32(bytes.data(), bytes.size()));
  }
  return out;
}

nlohmann::json run_one(actions::Rig& rig, const EvaluationSettings& settings,
                       const Resources& resources, const RunSpec& run) {
  const auto t0 = std::chrono::steady_clock::now();
  nlohmann::json out = {{"environment", settings.environments[run.environment].name},
                        {"method", to_string(run.method)},
                        {"seed", run.seed}};
  auto start = start_world(settings, resources, run);
  if (!start) {
    out["error"] = start.error().message;
    return out;
  }
  out["world"] = start->name;
  const sim::Fidelity level = run.full_check ? sim::Fidelity::kFull : settings.fidelity;
  out["fidelity"] = sim::to_string(level);
  if (run.full_check) out["fidelity_check"] = true;
  rig.set_fidelity(level);
  rig.reset(start->truth);
  episode::EngineSettings engine_settings;
  engine_settings.limits = {settings.max_actions, 24, settings.max_robot_time_s};
  std::optional<LinkRecorder> links;
  if (const sim::Chain* c = start->entry ? chain_of(resources, start->entry) : nullptr;
      c && needs_training_world(run.method)) {
    links.emplace(resources.library, *c);
    engine_settings.observers.push_back(&*links);
  }
  episode::Engine engine(rig.model(), rig.backend(),
                         method_source(settings, resources, run.method, start->entry),
                         std::move(engine_settings));
  const auto ran = engine.run();
  // What the run did, also when it failed: its figures until then.
  const episode::Episode& e = engine.episode();
  nlohmann::json curve = nlohmann::json::array({{0.0, 0}});
  for (const auto& p : e.curve.points()) curve.push_back({p.robot_time_s, p.boxes});
  nlohmann::json steps = nlohmann::json::array();
  std::uint64_t library_actions = 0;
  std::set<std::string> links_run;
  for (std::size_t i = 0; i < e.steps.size(); ++i) {
    const auto& s = e.steps[i];
    if (s.source.rfind("library:", 0) == 0) ++library_actions;
    steps.push_back({{"action", sim::to_string(s.action)},
                     {"source", s.source},
                     {"observation", sim::to_string(s.observation)},
                     {"applicable", s.outcome.applicable},
                     {"boxes", s.outcome.boxes},
                     {"robot_time_s", s.outcome.robot_time_s}});
    // The chain's entry the action came from, where the run follows one.
    if (links && i < links->links().size() && !links->links()[i].empty()) {
      steps.back()["link"] = links->links()[i];
      links_run.insert(links->links()[i]);
    }
  }
  if (!ran) {
    out["error"] = ran.error().message;
  } else {
    out["boxes_total"] = e.boxes_total;
    out["boxes_unloaded"] = e.boxes_unloaded;
    out["robot_time_s"] = e.robot_time_s;
    out["wasted_s"] = e.wasted_s;
    out["wasted_share"] = episode::wasted_share(e);
    out["actions"] = e.actions;
    out["library_actions"] = library_actions;
    out["strategies_asked"] = e.strategies_asked;
    out["strategy_steps"] = e.strategy_steps;
    if (links) out["links_run"] = links_run.size();
    out["robot_trailer_collisions"] = e.robot_trailer_contacts;
    out["stop_reason"] = e.stop_reason;
    out["ended"] = ending(settings, e);
  }
  out["curve"] = curve;
  out["steps"] = steps;
  out["planner_modes"] = actions::modes_json(e.planner);
  out["action_stats"] = {{"pick", actions::action_json(e.pick)},
                         {"sweep", actions::action_json(e.sweep)}};
  out["wall_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace plr::evaluation
