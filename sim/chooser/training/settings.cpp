#include "plr/chooser/training/settings.hpp"

#include <plr/message.hpp>
#include <plr/yaml_reader.hpp>

#include <fmt/format.h>

#include "plr/sim/generators.hpp"
#include "plr/sim/physics.hpp"
#include "plr/sim/world_io.hpp"

namespace plr::chooser {

namespace {

constexpr std::size_t kMaxWorlds = 10000;

struct FamilySeed {
  sim::EnvFamily family;
  std::uint64_t seed;
};
std::optional<FamilySeed> family_seed(const std::string& name) {
  const auto colon = name.find(':');
  if (colon == std::string::npos) return std::nullopt;
  const auto family = sim::parse_env_family(name.substr(0, colon));
  if (!family) return std::nullopt;
  try {
    std::size_t used = 0;
    const auto seed = std::stoull(name.substr(colon + 1), &used);
    if (used != name.size() - colon - 1) return std::nullopt;
    return FamilySeed{*family, seed};
  } catch (const std::exception&) {
    return std::nullopt;
  }
}

std::vector<WorldSource> read_worlds(const yaml::Node& node) {
  std::vector<WorldSource> out;
  for (const yaml::Node& item :
       node.list("a list of worlds (A1:3 or a world file)", 1, kMaxWorlds)) {
    const auto name = item.string();
    if (!name) continue;
    if (family_seed(*name)) {
      out.push_back({*name});
    } else if (name->find(':') != std::string::npos) {
      item.error("not a family:seed such as A1:3");
    } else {
      out.push_back({*name});
    }
  }
  return out;
}

}  // namespace

plr::Expected<sim::World> WorldSource::load() const {
  if (const auto fs = family_seed(name)) return sim::make_environment(fs->family, fs->seed);
  return sim::load_world(name);
}

std::optional<sim::EnvFamily> WorldSource::family() const {
  if (const auto fs = family_seed(name)) return fs->family;
  return std::nullopt;
}

plr::Expected<sim::World> WorldSource::layout() const {
  if (const auto fs = family_seed(name)) return sim::generate_world(fs->family, fs->seed);
  return sim::load_world(name);
}

std::uint64_t TrainingSettings::hash(std::uint32_t library_fingerprint) const {
  return plr::fnv1a(describe(library_fingerprint));
}

std::string TrainingSettings::describe(std::uint32_t library_fingerprint) const {
  std::string text = fmt::format(
      "lib {} spw {} ra {} tie {} {} particles {} {} obs {} {} {} {} {} {} {} {} h {} {} svm {} ",
      library_fingerprint, states_per_world, rollout_actions, tie_margin, tie_boxes, particles,
      mass_prior ? sim::to_string(*mass_prior) : "-", observation.h_pile, observation.wall_depth,
      observation.min_pile_depth, observation.pile_mid, observation.pile_high, observation.wall_mid,
      observation.wall_high, observation.side_band, h.h_min, h.d_min, svm.folds);
  for (int c : svm.log2_c) text += fmt::format("c{} ", c);
  for (int g : svm.log2_gamma) text += fmt::format("g{} ", g);
  // Where it ends shapes the model; 0 (the default) keeps older data sets'
  // hashes.
  if (patience > 0) text += fmt::format("min {} patience {} ", min_samples, patience);
  // Only below full: a full-fidelity data set resumes as it was made.
  if (fidelity != sim::Fidelity::kFull) text += "fidelity " + sim::to_string(fidelity) + " ";
  for (const auto* list : {&train, &validation}) {
    text += "| ";
    for (const WorldSource& w : *list) text += w.name + " ";
  }
  return text;
}

plr::Expected<TrainingSettings> TrainingSettings::load(const std::filesystem::path& file,
                                                       const std::vector<std::string>& overrides) {
  auto doc = yaml::open_with_overrides(file.string(), "the training settings", overrides);
  if (!doc) return doc.error();
  TrainingSettings s;
  const yaml::Map top = doc->root().map("chooser training settings",
                                        {"format",          "library",      "out",
                                         "train",           "validation",   "states_per_world",
                                         "rollout_actions", "tie_margin",   "tie_boxes",
                                         "particles",       "mass_prior",   "workers",
                                         "observation",     "h_min",        "d_min",
                                         "folds",           "log2_c",       "log2_gamma",
                                         "min_samples",     "patience",     "fidelity",
                                         jobs::kRunnerKey,  jobs::kSlurmKey});
  (void)top.required("format").one_of({"plr-chooser-training"});
  if (auto l = top.required("library").string()) s.library = *l;
  if (auto o = top.required("out").string()) s.out = *o;
  s.train = read_worlds(top.required("train"));
  s.validation = read_worlds(top.required("validation"));
  if (auto n = top.find("states_per_world").integer(1, 1000)) s.states_per_world = *n;
  if (auto n = top.find("rollout_actions").integer(1, 1000)) s.rollout_actions = *n;
  if (auto n = top.find("tie_margin").number(0.0, 1.0)) s.tie_margin = *n;
  if (auto n = top.find("tie_boxes").integer(0, 1000)) s.tie_boxes = static_cast<std::uint32_t>(*n);
  if (auto n = top.find("particles").integer(1, 64)) s.particles = static_cast<std::uint32_t>(*n);
  if (const yaml::Node n = top.find("mass_prior"); n.present()) {
    if (auto name = n.string()) {
      s.mass_prior = sim::parse_env_family(*name);
      if (!s.mass_prior) n.error("not a family (" + sim::env_family_names() + ")");
    }
  }
  if (auto n = top.find("workers").integer(1, 64)) s.workers = static_cast<int>(*n);
  if (auto f = top.find("fidelity").one_of({"full", "adaptive", "fast"}))
    s.fidelity = *sim::parse_fidelity(*f);
  if (auto n = top.find("folds").integer(2, 100)) s.svm.folds = static_cast<int>(*n);
  if (auto n = top.find("min_samples").integer(1, 1000000))
    s.min_samples = static_cast<std::uint32_t>(*n);
  if (auto n = top.find("patience").integer(0, 100000)) s.patience = static_cast<std::uint32_t>(*n);
  for (auto [key, grid] : {std::pair{"log2_c", &s.svm.log2_c}, {"log2_gamma", &s.svm.log2_gamma}}) {
    const yaml::Node n = top.find(key);
    if (!n.present()) continue;
    grid->clear();
    for (const yaml::Node& v : n.list("a list of integers", 1, 64))
      if (auto i = v.integer(-30, 30)) grid->push_back(static_cast<int>(*i));
  }
  sim::read_strategy_settings(top, s.h, s.observation);
  jobs::read_runner_settings(top, s.runner);
  if (!doc->ok()) return doc->error();
  if (auto ok = s.h.check(); !ok) return ok.error();
  if (s.particles > 1 && !s.mass_prior)
    for (const auto* list : {&s.train, &s.validation})
      for (const WorldSource& w : *list)
        if (!w.family())
          return plr::make_error(PLR_ERR_INVALID,
                                 file.string() + ": particles: " + w.name +
                                     " is a world file; mass_prior names the family whose "
                                     "masses its particles draw");
  return s;
}

}  // namespace plr::chooser
