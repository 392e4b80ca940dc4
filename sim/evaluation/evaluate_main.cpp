// plr evaluate: the paper's comparison of H, NN, open-loop, expected-offline
// and PLR on every environment and seed of a settings file, in worker
// processes, resumable; then the report (plots, Tables I and II, findings).
//
//   plr evaluate SETTINGS [--report DIR] [--quick] [--workers N] [--set KEY=VALUE]...
//
// Each run's result goes to DIR/runs/ as it finishes; started again with the
// same DIR, only the missing runs run. docs/evaluation.md.
#include <unistd.h>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include <chrono>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "plr/actions/process_pool.hpp"
#include "plr/actions/rig.hpp"
#include "plr/evaluation/report_files.hpp"
#include "plr/evaluation/run.hpp"
#include "plr/evaluation/summary.hpp"

namespace {

namespace fs = std::filesystem;
namespace ev = plr::evaluation;
using Clock = std::chrono::steady_clock;

constexpr std::uintmax_t kMaxResultBytes = 64u << 20;

[[noreturn]] void die(const std::string& what, int code = 2) {
  std::fprintf(stderr, "plr evaluate: %s\n", what.c_str());
  std::exit(code);
}

struct Args {
  std::string settings;
  std::string report = "report_eval";
  bool quick = false;
  unsigned workers = 0;
  std::vector<std::string> overrides;
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
                 "Report folder; its runs/ keeps each run's result, so a run is not run again")
      ->capture_default_str();
  app.add_flag("--quick", a.quick, "The settings' quick_seeds instead of seeds");
  app.add_option("--workers", a.workers, "Worker processes (default: the settings' workers)")
      ->check(CLI::Range(1u, 999u));
  app.add_option("--set", a.overrides, "Override a setting: KEY=VALUE (repeatable)")
      ->type_name("KEY=VALUE");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    std::exit(app.exit(e));
  }
  return a;
}

// One line redrawn on a terminal; a line per run otherwise.
class ProgressLine {
 public:
  explicit ProgressLine(std::size_t total, unsigned workers)
      : total_(total), workers_(workers), tty_(isatty(STDERR_FILENO) == 1), t0_(Clock::now()) {}
  void step(const std::string& what) {
    ++done_;
    const double s = std::chrono::duration<double>(Clock::now() - t0_).count();
    const double eta = s / static_cast<double>(done_) * static_cast<double>(total_ - done_);
    const int width = 30;
    const int filled = static_cast<int>(width * done_ / std::max<std::size_t>(total_, 1));
    const std::string line =
        fmt::format("[{}{}] {}/{} runs  {:.0f} min left  {} done", std::string(filled, '#'),
                    std::string(width - filled, '.'), done_, total_, eta / 60, what);
    (void)workers_;
    std::fprintf(stderr, tty_ ? "\r%-100.100s" : "%s\n", line.c_str());
    std::fflush(stderr);
  }
  void finish() {
    if (tty_ && done_ > 0) std::fprintf(stderr, "\n");
  }

 private:
  std::size_t total_, done_ = 0;
  unsigned workers_;
  bool tty_;
  Clock::time_point t0_;
};

nlohmann::json read_result(const fs::path& file) {
  std::error_code ec;
  const auto size = fs::file_size(file, ec);
  if (ec || size > kMaxResultBytes)
    die(fmt::format("{}: {}", file.string(), ec ? ec.message() : "larger than 64 MiB"));
  std::ifstream in(file);
  auto j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.is_object())
    die(fmt::format("{}: not a result file (delete it to run it again)", file.string()));
  return j;
}

}  // namespace

int main(int argc, char** argv) {
  const Args args = parse(argc, argv);
  auto settings = ev::EvaluationSettings::load(args.settings, args.overrides);
  if (!settings) die(settings.error().message);
  if (args.workers > 0) settings->workers = args.workers;
  auto resources = ev::load_resources(*settings);
  if (!resources) die(resources.error().message);

  const fs::path dir = args.report, runs_dir = dir / "runs";
  std::error_code ec;
  fs::create_directories(runs_dir, ec);
  if (ec) die(runs_dir.string() + ": " + ec.message());

  const std::uint64_t seeds = args.quick ? settings->quick_seeds : settings->seeds;
  std::vector<ev::RunSpec> specs;
  std::vector<plr::actions::PoolRun> all;
  for (std::size_t e = 0; e < settings->environments.size(); ++e)
    for (const ev::Method m : settings->methods)
      for (std::uint64_t s = settings->first_seed; s < settings->first_seed + seeds; ++s) {
        const ev::RunSpec spec{e, m, s};
        if (!ev::applies(*settings, spec)) continue;
        specs.push_back(spec);
        all.push_back(
            {fmt::format("{} {} seed {}", settings->environments[e].name, ev::to_string(m), s),
             runs_dir / ev::result_file_name(*settings, spec)});
      }
  std::vector<std::size_t> todo;
  for (std::size_t i = 0; i < all.size(); ++i)
    if (!fs::exists(all[i].result)) todo.push_back(i);
  if (todo.size() < all.size())
    std::fprintf(stderr, "plr evaluate: %zu of %zu runs already in %s\n", all.size() - todo.size(),
                 all.size(), runs_dir.c_str());

  if (!todo.empty()) {
    plr::actions::ActionOptions options;
    options.observation = settings->observation;
    // Plans are bounded by expansions, so results do not depend on the
    // machine's load; the time limit is only a safety net.
    options.plan_timeout_s = 1800.0;
    auto rig = plr::actions::Rig::create(options);
    if (!rig) die(rig.error().message);
    std::vector<plr::actions::PoolRun> runs;
    for (std::size_t i : todo) runs.push_back(all[i]);
    ProgressLine progress(runs.size(), settings->workers);
    const std::string error = plr::actions::run_in_processes(
        runs, {settings->workers, settings->timeout_s, true},
        [&](std::size_t i) { return ev::run_one(**rig, *settings, *resources, specs[todo[i]]); },
        [&](std::size_t i, const std::string& why, double wall_s) {
          const ev::RunSpec& s = specs[todo[i]];
          return nlohmann::json{{"environment", settings->environments[s.environment].name},
                                {"method", ev::to_string(s.method)},
                                {"seed", s.seed},
                                {"error", why},
                                {"wall_s", wall_s}};
        },
        [&](std::size_t i) { progress.step(runs[i].name); });
    progress.finish();
    if (!error.empty()) die(error);
  }

  std::vector<nlohmann::json> results;
  for (const auto& r : all) results.push_back(read_result(r.result));
  const nlohmann::json summary = ev::summarize(*settings, results, args.quick);
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
