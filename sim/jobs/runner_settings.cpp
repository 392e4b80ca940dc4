#include "plr/jobs/runner_settings.hpp"

namespace plr::jobs {

std::optional<RunnerSettings::Kind> parse_runner(const std::string& name) {
  if (name == "local") return RunnerSettings::Kind::kLocal;
  if (name == "slurm") return RunnerSettings::Kind::kSlurm;
  return std::nullopt;
}

void read_runner_settings(const plr::yaml::Map& top, RunnerSettings& out) {
  if (auto name = top.find(kRunnerKey).one_of({"local", "slurm"})) out.kind = *parse_runner(*name);
  const plr::yaml::Map s = top.find(kSlurmKey).map(
      "the Slurm settings", {"partition", "account", "time_limit", "max_parallel", "max_attempts",
                             "sbatch_args", "poll_s", "job_name"});
  SlurmOptions& o = out.slurm;
  if (auto v = s.find("partition").string()) o.partition = *v;
  if (auto v = s.find("account").string()) o.account = *v;
  if (auto v = s.find("time_limit").string("a Slurm time, e.g. 01:00:00")) o.time_limit = *v;
  if (auto v = s.find("max_parallel").integer(0, 100000))
    o.max_parallel = static_cast<unsigned>(*v);
  if (auto v = s.find("max_attempts").integer(1, 100)) o.max_attempts = static_cast<unsigned>(*v);
  if (auto v = s.find("poll_s").number(0.05, 3600)) o.poll_s = *v;
  if (auto v = s.find("job_name").string()) o.job_name = *v;
  for (const plr::yaml::Node& arg : s.find("sbatch_args").list("a list of sbatch options", 0, 64))
    if (auto a = arg.string()) o.sbatch_args.push_back(*a);
}

}  // namespace plr::jobs
