#include "plr/evaluation/settings.hpp"

#include <plr/yaml_reader.hpp>

namespace plr::evaluation {

namespace {

constexpr std::size_t kMaxEnvironments = 64;
constexpr std::int64_t kMaxSeeds = 10000;

constexpr Method kMethods[] = {Method::kHardcoded, Method::kNearest, Method::kOpenLoop,
                               Method::kExpectedOffline, Method::kPlr};

}  // namespace

const char* to_string(Method method) {
  switch (method) {
    case Method::kHardcoded:
      return "H";
    case Method::kNearest:
      return "NN";
    case Method::kOpenLoop:
      return "open-loop";
    case Method::kExpectedOffline:
      return "expected-offline";
    case Method::kPlr:
      return "PLR";
  }
  return "?";
}

std::optional<Method> parse_method(const std::string& name) {
  for (const Method m : kMethods)
    if (name == to_string(m)) return m;
  return std::nullopt;
}

bool needs_training_world(Method method) {
  return method == Method::kOpenLoop || method == Method::kExpectedOffline;
}

plr::Expected<EvaluationSettings> EvaluationSettings::load(
    const std::filesystem::path& file, const std::vector<std::string>& overrides) {
  auto doc = yaml::open_with_overrides(file.string(), "the evaluation settings", overrides);
  if (!doc) return doc.error();
  EvaluationSettings s;
  const yaml::Map top = doc->root().map(
      "evaluation settings",
      {"format",       "library", "model",       "environments",         "methods",
       "first_seed",   "seeds",   "quick_seeds", "max_robot_time_s",     "quick_max_robot_time_s",
       "max_actions",  "workers", "timeout_s",   "max_distance",         "observation",
       "h_min",        "d_min",   "fidelity",    "fidelity_check_seeds", jobs::kRunnerKey,
       jobs::kSlurmKey});
  (void)top.required("format").one_of({"plr-evaluation"});
  if (auto l = top.required("library").string()) s.library = *l;
  if (auto m = top.required("model").string()) s.model = *m;
  for (const yaml::Node& item :
       top.required("environments").list("a list of environments", 1, kMaxEnvironments)) {
    const yaml::Map e = item.map("an environment", {"name", "family", "training", "world"});
    Environment env;
    if (auto n = e.required("name").string()) env.name = *n;
    if (env.name.find_first_not_of("ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789"
                                   "_-") != std::string::npos)
      e.required("name").error("letters, digits, '_' and '-' only (it names files)");
    if (auto f = e.required("family").string()) {
      if (auto family = sim::parse_env_family(*f))
        env.family = *family;
      else
        e.required("family").error("not a family (" + sim::env_family_names() + ")");
    }
    if (auto t = e.find("training").boolean()) env.training = *t;
    if (auto w = e.find("world").string()) env.world = *w;
    if (env.training && !env.world.empty())
      e.find("world").error("a training environment's worlds are the library's");
    for (const Environment& other : s.environments)
      if (other.name == env.name) e.required("name").error("named twice");
    s.environments.push_back(std::move(env));
  }
  for (const yaml::Node& item : top.required("methods").list("a list of methods", 1, 16)) {
    const auto name = item.one_of({"H", "NN", "open-loop", "expected-offline", "PLR"});
    if (name) s.methods.push_back(*parse_method(*name));
  }
  if (auto n = top.find("first_seed").integer(0, std::int64_t{1} << 40)) s.first_seed = *n;
  if (auto n = top.find("seeds").integer(1, kMaxSeeds)) s.seeds = *n;
  if (auto n = top.find("quick_seeds").integer(1, kMaxSeeds)) s.quick_seeds = *n;
  if (auto v = top.find("max_robot_time_s").number(1, 1e6)) s.max_robot_time_s = *v;
  if (auto v = top.find("quick_max_robot_time_s").number(1, 1e6)) s.quick_max_robot_time_s = *v;
  if (auto n = top.find("max_actions").integer(0, 1000000)) s.max_actions = *n;
  if (auto n = top.find("workers").integer(1, 256)) s.workers = static_cast<unsigned>(*n);
  if (auto v = top.find("timeout_s").number(1, 1e7)) s.timeout_s = *v;
  if (auto v = top.find("max_distance").number(0, 1e9)) s.max_distance = *v;
  if (auto f = top.find("fidelity").one_of({"full", "adaptive", "fast"}))
    s.fidelity = *sim::parse_fidelity(*f);
  if (auto n = top.find("fidelity_check_seeds").integer(0, kMaxSeeds)) s.fidelity_check_seeds = *n;
  sim::read_strategy_settings(top, s.h, s.observation);
  jobs::read_runner_settings(top, s.runner);
  if (!doc->ok()) return doc->error();
  if (auto ok = s.h.check(); !ok) return ok.error();
  return s;
}

}  // namespace plr::evaluation
