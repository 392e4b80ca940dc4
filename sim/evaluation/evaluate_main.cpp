// plr evaluate: the paper's comparison of H, NN, open-loop, expected-offline
// and PLR on every environment and seed of a settings file, in worker
// processes, resumable; then the report (plots, Tables I and II, findings).
//
//   plr evaluate SETTINGS [--report DIR] [--quick] [--workers N] [--runner local|slurm]
//                [--set KEY=VALUE]...
//
// Each run is a job (plr/jobs); its result goes to the store DIR/runs/ as it
// finishes; started again with the same DIR, only the missing runs run. The
// runs run in child processes, or as Slurm job arrays whose tasks are this
// program again with --slurm-task (docs/cluster.md). docs/evaluation.md.
#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include <cstdio>
#include <fstream>

#include <plr/atomic_file.hpp>

#include "plr/actions/rig.hpp"
#include "plr/evaluation/report_files.hpp"
#include "plr/evaluation/run.hpp"
#include "plr/evaluation/summary.hpp"
#include "plr/jobs/process_runner.hpp"
#include "plr/jobs/progress.hpp"
#include "plr/jobs/slurm_runner.hpp"

namespace {

namespace fs = std::filesystem;
namespace ev = plr::evaluation;
namespace jobs = plr::jobs;

constexpr const char* kRunKind = "evaluation.run";

[[noreturn]] void die(const std::string& what, int code = 2) {
  std::fprintf(stderr, "plr evaluate: %s\n", what.c_str());
  std::exit(code);
}

// The runs in a store were made under the conditions recorded beside them;
// a store made under others (another cap, library, ...) is refused rather
// than mixed in.
void check_conditions(const fs::path& file, const nlohmann::json& conditions) {
  std::ifstream in(file);
  if (!in) {
    if (auto ok = plr::write_file_atomically(file.string(), conditions.dump(1) + "\n"); !ok)
      die(ok.error().message);
    return;
  }
  const auto stored = nlohmann::json::parse(in, nullptr, false);
  if (stored == conditions) return;
  std::string what = "unreadable";
  if (stored.is_object())
    for (const auto& [key, value] : conditions.items())
      if (!stored.contains(key) || stored[key] != value) {
        what = fmt::format("{} {} there, {} now", key, stored.value(key, nlohmann::json()).dump(),
                           value.dump());
        break;
      }
  die(
      fmt::format("{}: the runs there were made under other conditions ({}); report to another "
                  "folder, or delete it to run them again",
                  file.string(), what));
}

struct Args {
  std::string settings;
  std::string report;
  bool quick = false;
  unsigned workers = 0;
  std::string runner;
  std::vector<std::string> overrides;
  std::string slurm_task;
};

Args parse(int argc, char** argv) {
  Args a;
  CLI::App app{
      "The paper's comparison of H, NN, open-loop, expected-offline and PLR on every "
      "environment and seed of a settings file, in worker processes, resumable; then "
      "the report"};
  app.name("plr evaluate");
  app.add_option("settings", a.settings, "Evaluation settings (configs/evaluate.yaml)")->required();
  app.add_option("--report", a.report,
                 "Report folder (default report_eval, with --quick report_eval_quick); its runs/ "
                 "keeps each run's result, so a run is not run again");
  app.add_flag("--quick", a.quick,
               "The settings' quick_seeds and quick_max_robot_time_s instead of seeds and "
               "max_robot_time_s");
  app.add_option("--workers", a.workers, "Worker processes (default: the settings' workers)")
      ->check(CLI::Range(1u, 999u));
  app.add_option("--runner", a.runner,
                 "Where the runs run: local (child processes) or slurm (job arrays, "
                 "docs/cluster.md); default: the settings' runner")
      ->check(CLI::IsMember({"local", "slurm"}));
  app.add_option("--slurm-task", a.slurm_task, "Run one Slurm array task of this batch file")
      ->group("");  // what a task runs, not for people
  app.add_option("--set", a.overrides, "Override a setting: KEY=VALUE (repeatable)")
      ->type_name("KEY=VALUE");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    std::exit(app.exit(e));
  }
  if (a.report.empty()) a.report = a.quick ? "report_eval_quick" : "report_eval";
  return a;
}

}  // namespace

int main(int argc, char** argv) {
  const Args args = parse(argc, argv);
  auto settings = ev::EvaluationSettings::load(args.settings, args.overrides);
  if (!settings) die(settings.error().message);
  if (args.workers > 0) settings->workers = args.workers;
  if (!args.runner.empty()) settings->runner.kind = *jobs::parse_runner(args.runner);
  if (args.quick) settings->max_robot_time_s = settings->quick_max_robot_time_s;
  auto resources = ev::load_resources(*settings);
  if (!resources) die(resources.error().message);

  const fs::path dir = args.report;
  auto store = jobs::Store::open(dir / "runs");
  if (!store) die(store.error().message);
  check_conditions(store->dir() / "conditions.json", ev::run_conditions(*settings, *resources));

  const std::uint64_t seeds = args.quick ? settings->quick_seeds : settings->seeds;
  const std::vector<ev::RunSpec> specs = ev::plan_runs(*settings, seeds);
  std::vector<jobs::Job> all;
  // The input is the run's index; the settings and the rig are the
  // process's own, inherited by each job's child.
  for (std::size_t i = 0; i < specs.size(); ++i)
    all.push_back({kRunKind, ev::run_key(*settings, specs[i]), jobs::to_bytes(std::to_string(i))});
  std::unique_ptr<plr::actions::Rig> rig;
  jobs::Kinds kinds;
  kinds.add(kRunKind, [&](const jobs::Bytes& input) -> plr::Expected<jobs::Bytes> {
    const ev::RunSpec& spec = specs.at(std::stoul(jobs::to_text(input)));
    return jobs::to_bytes(ev::run_one(*rig, *settings, *resources, spec).dump(1));
  });
  auto prepare = [&] {
    plr::actions::ActionOptions options;
    options.observation = settings->observation;
    options.plan_timeout_s = plr::actions::kOfflinePlanTimeoutS;
    auto created = plr::actions::Rig::create(options);
    if (!created) die(created.error().message);
    rig = std::move(*created);
  };
  if (!args.slurm_task.empty()) return jobs::run_array_task(kinds, args.slurm_task, prepare);

  std::unique_ptr<jobs::Runner> runner;
  const jobs::SlurmRunner* slurm = nullptr;
  if (settings->runner.kind == jobs::RunnerSettings::Kind::kSlurm) {
    // A task is this command again, from any folder the nodes share.
    std::vector<std::string> task{jobs::this_program(), fs::absolute(args.settings).string(),
                                  "--report", fs::absolute(dir).string()};
    if (args.quick) task.push_back("--quick");
    for (const auto& o : args.overrides) task.insert(task.end(), {"--set", o});
    task.push_back("--slurm-task");
    auto s = std::make_unique<jobs::SlurmRunner>(*store, task, settings->runner.slurm);
    slurm = s.get();
    runner = std::move(s);
  } else {
    auto local = jobs::ProcessRunner::create(
        {{}, &kinds, settings->workers, settings->timeout_s, 1, true, store->logs()});
    if (!local) die(local.error().message);
    runner = std::move(*local);
  }
  auto outcome = jobs::run_with_progress("plr evaluate", all, *runner, *store,
                                         slurm ? std::function<void()>{} : prepare);
  if (!outcome) die(outcome.error().message);
  if (outcome->stopped)
    die(fmt::format("stopped; {} runs are in {}, run it again to go on",
                    outcome->stored + outcome->ran, store->dir().string()),
        130);

  std::vector<nlohmann::json> results;
  for (std::size_t i = 0; i < all.size(); ++i) {
    const jobs::Result& r = outcome->results[i];
    const ev::RunSpec& s = specs[i];
    if (!r.ok) {
      results.push_back({{"environment", settings->environments[s.environment].name},
                         {"method", ev::to_string(s.method)},
                         {"seed", s.seed},
                         {"error", r.error},
                         {"wall_s", r.wall_s}});
      if (s.full_check) results.back()["fidelity_check"] = true;
      continue;
    }
    auto j = nlohmann::json::parse(jobs::to_text(r.output), nullptr, false);
    if (j.is_discarded() || !j.is_object())
      die(fmt::format("{}: not a run's result (delete it to run it again)",
                      store->result_file(r.key).string()));
    results.push_back(std::move(j));
  }
  nlohmann::json summary = ev::summarize(*settings, results, args.quick);
  if (slurm) summary["runner"] = jobs::to_json(slurm->stats());
  if (auto ok = ev::write_report(summary, dir); !ok) die(ok.error().message);
  for (const auto& f : summary["findings"])
    std::printf("%s\n", f["text"].get<std::string>().c_str());
  for (const auto& c : summary["claims"])
    if (!c["holds"].get<bool>() && c.contains("why"))
      std::printf("%s does not hold: %s\n", c["claim"].get<std::string>().c_str(),
                  c["why"]["text"].get<std::string>().c_str());
  std::printf("report: %s\n", (dir / "report.html").c_str());
  return 0;
}
