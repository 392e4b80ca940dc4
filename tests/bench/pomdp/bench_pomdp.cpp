// POMDP solver benchmark: POMHDP and POMCP side by side on one model file
// (.pomdp or .pomdpx).
//   bench_pomdp MODEL [--budget S] [--pomcp-budget S] [--offline S]
//               [--episodes N] [--time-limit S] [--workers N] [--online-gap G]
//               [--seed N] [--json] [--quick]
// POMHDP first solves offline from the initial belief (root bounds), then
// both solvers are evaluated online, replanning from the exact belief at every
// step within the per-step budget. Every episode starts from an empty search
// and keeps it between its steps (--warm keeps it between episodes too, which
// is not the fresh online search the published figures are measured with).
// Episodes run on --workers threads, each with its own solvers. An online
// POMHDP step stops early once the root's bounds are within --online-gap
// (the budget is a maximum, as for any anytime solver). POMCP's rollouts take
// the MDP's greedy action on the sampled state (--pomcp-random-rollouts:
// uniformly random actions).
#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>

#include <fmt/format.h>
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include "plr/pomdp/evaluate.hpp"
#include "plr/pomdp/heuristics.hpp"
#include "plr/pomdp/model_io.hpp"
#include "plr/pomdp/pomcp.hpp"
#include "plr/pomdp/pomhdp.hpp"

#include "bench_cli.hpp"

using namespace plr::pomdp;

namespace {

using Clock = std::chrono::steady_clock;

double since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// The machine's one-minute load average (the 2 cores are shared).
double load_average() {
  double l = 0.0;
  return getloadavg(&l, 1) == 1 ? l : -1.0;
}

// The process's peak resident memory so far.
double peak_rss_mb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_maxrss) / 1024.0;
}

// Values at the initial belief published for the standard problems
// (SARSOP's, see docs/pomdp.md), by file name.
std::optional<double> published_value(const std::string& stem) {
  if (stem.starts_with("Tiger")) return 19.37;
  if (stem.starts_with("RockSample_4_4")) return 17.92;
  if (stem.starts_with("RockSample_5_7")) return 24.24;
  if (stem.starts_with("RockSample_7_8")) return 21.27;
  if (stem.starts_with("Tag")) return -6.13;
  return std::nullopt;
}

// A progress bar on stderr, redrawn at most ten times a second.
class Progress {
 public:
  explicit Progress(std::string label) : label_(std::move(label)) {}
  void operator()(int done, int total) {
    if (done < total && since(last_) < 0.1) return;
    last_ = Clock::now();
    constexpr int kWidth = 30;
    const int filled = total > 0 ? done * kWidth / total : kWidth;
    std::fprintf(stderr, "\r%-22s [%s%s] %d/%d episodes, %.0f s", label_.c_str(),
                 std::string(static_cast<std::size_t>(filled), '#').c_str(),
                 std::string(static_cast<std::size_t>(kWidth - filled), '.').c_str(), done, total,
                 since(start_));
    std::fflush(stderr);
    drawn_ = true;
  }
  // Ends the bar's line (a run that stops on its time limit ends short of
  // the total).
  void finish() {
    if (drawn_) std::fprintf(stderr, "\n");
    drawn_ = false;
  }

 private:
  std::string label_;
  bool drawn_ = false;
  Clock::time_point start_ = Clock::now(), last_ = Clock::time_point{};
};

nlohmann::json to_json(const Evaluation& e, double budget) {
  return {{"value", e.mean},
          {"ci95", e.ci95},
          {"stddev", e.stddev},
          {"episodes", e.returns.size()},
          {"mean_steps", e.mean_steps},
          {"budget_per_step_s", budget},
          {"median_step_s", e.median_step_seconds},
          {"max_step_s", e.max_step_seconds},
          {"iterations_per_step", e.mean_iterations_per_step},
          {"first_step_lower", e.first_step.lower},
          {"first_step_upper", e.first_step.upper},
          {"first_step_iterations", e.first_step.iterations},
          {"max_nodes", e.max_nodes},
          {"max_memory_bytes", e.max_memory_bytes},
          {"lost_beliefs", e.lost_beliefs},
          {"cv_value", e.cv_mean},
          {"cv_ci95", e.cv_ci95},
          {"cv_beta", e.cv_beta},
          {"seconds", e.seconds}};
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"POMHDP and POMCP side by side on one POMDP model"};
  std::string file;
  double budget = -1.0, pomcp_budget = -1.0, offline = -1.0, time_limit = -1.0,
         pomcp_time_limit = -1.0;
  int episodes = -1;
  std::uint64_t seed = 1, pomcp_sims = std::numeric_limits<std::uint64_t>::max();
  bool json = false, quick = false, anchor_only = false, warm = false, random_rollouts = false;
  int workers = 2;
  double online_gap = 0.1;
  PomhdpOptions options;
  app.add_option("model", file, "model file (.pomdp or .pomdpx)")->required();
  app.add_option("--budget", budget, "POMHDP seconds per step online (default 1, quick 0.1)");
  app.add_option("--pomcp-budget", pomcp_budget,
                 "POMCP seconds per step (default: --budget, quick 0.02)");
  app.add_option("--offline", offline, "POMHDP offline solve seconds (default 60, quick 5)");
  app.add_option("--episodes", episodes, "episodes per solver at most (default 20000, quick 100)");
  app.add_option("--time-limit", time_limit,
                 "POMHDP: no new episode after this many seconds (default 540, quick 15)");
  app.add_option("--pomcp-time-limit", pomcp_time_limit,
                 "POMCP: no new episode after this many seconds (default 180, quick 10)");
  app.add_option("--pomcp-sims", pomcp_sims, "POMCP simulations per step at most");
  app.add_option("--epsilon1", options.epsilon1, "POMHDP inflation of inadmissible heuristics");
  app.add_option("--epsilon2", options.epsilon2, "POMHDP bound of searches by the anchor");
  app.add_option("--trial-gap-fraction", options.trial_gap_fraction,
                 "POMHDP trial stop: this fraction of the root's gap (HSVI's rule)");
  app.add_flag("--anchor-only", anchor_only, "POMHDP without inadmissible heuristics");
  double memory_mb = 1024.0;
  app.add_option("--memory-mb", memory_mb,
                 "POMHDP graph memory limit in MB (older nodes are given back beyond it)");
  app.add_flag("--warm", warm,
               "keep each worker's search between episodes (not a fresh search per episode)");
  app.add_option("--workers", workers, "episodes run side by side on this many threads");
  app.add_option("--online-gap", online_gap,
                 "POMHDP online: a step's search stops once the root's gap is below this");
  app.add_flag("--pomcp-random-rollouts", random_rollouts,
               "POMCP rollouts with uniformly random actions (default: the MDP's greedy action)");
  app.add_option("--seed", seed, "random seed");
  plr::bench::add_json_flag(app, json);
  plr::bench::add_quick_flag(app, quick, "the shorter budgets and limits above");
  CLI11_PARSE(app, argc, argv);
  if (budget < 0) budget = quick ? 0.1 : 1.0;
  if (pomcp_budget < 0) pomcp_budget = quick ? 0.02 : budget;
  if (offline < 0) offline = quick ? 5.0 : 60.0;
  if (episodes < 0) episodes = quick ? 100 : 20000;
  if (time_limit < 0) time_limit = quick ? 15.0 : 540.0;
  if (pomcp_time_limit < 0) pomcp_time_limit = quick ? 10.0 : 180.0;

  const double load_at_start = load_average();
  auto t0 = Clock::now();
  auto loaded = load_model(file);
  if (!loaded) {
    std::fprintf(stderr, "%s\n", loaded.error().message.c_str());
    return 1;
  }
  const TabularModel& model = *loaded;
  const double load_s = since(t0);
  t0 = Clock::now();
  const TabularHeuristics h = make_tabular_heuristics(model);
  const double bounds_s = since(t0);
  const std::string stem = std::filesystem::path(file).stem().string();
  const auto published = published_value(stem);

  // Offline: bounds at the initial belief.
  options.seed = seed;
  options.max_memory_bytes = static_cast<std::size_t>(memory_mb * 1e6);
  const auto inadmissible = anchor_only ? std::vector<const Heuristic*>{} : h.inadmissible();
  Pomhdp offline_solver(model, *h.upper, *h.lower, inadmissible, options);
  const PlanStats off = offline_solver.solve({offline, std::numeric_limits<std::uint64_t>::max()});

  EvaluationOptions eval;
  eval.episodes = episodes;
  eval.seed = seed;
  eval.max_seconds = time_limit;
  const bool tty = isatty(STDERR_FILENO) != 0;

  const double offline_rss_mb = peak_rss_mb();
  eval.workers = workers;
  // The control variate: the MDP value of the episode's start state (its
  // mean over the initial belief is known exactly).
  eval.control = [&h](StateId s) { return h.most_likely->value(Belief({{s, 1.0}})); };

  eval.per_step = {budget, std::numeric_limits<std::uint64_t>::max()};
  PomhdpOptions online_options = options;
  online_options.warm_start = warm;
  online_options.target_gap = online_gap;
  Progress p1("POMHDP online");
  if (tty || !json) eval.progress = [&p1](int d, int t) { p1(d, t); };
  const Evaluation pomhdp = evaluate(
      model,
      [&](int w) {
        PomhdpOptions o = online_options;
        o.seed = seed + static_cast<std::uint64_t>(w);
        return std::make_unique<Pomhdp>(model, *h.upper, *h.lower, inadmissible, o);
      },
      eval);
  p1.finish();

  eval.per_step = {pomcp_budget, pomcp_sims};
  eval.max_seconds = pomcp_time_limit;
  PomcpOptions pomcp_options;
  pomcp_options.warm_start = warm;
  if (!random_rollouts) pomcp_options.rollout_policy = rollout_policy_from(h.mdp_greedy);
  Progress p2("POMCP online");
  if (tty || !json) eval.progress = [&p2](int d, int t) { p2(d, t); };
  const Evaluation pomcp = evaluate(
      model,
      [&](int w) {
        PomcpOptions o = pomcp_options;
        o.seed = seed + static_cast<std::uint64_t>(w);
        return std::make_unique<Pomcp>(model, o);
      },
      eval);
  p2.finish();
  const double total_rss_mb = peak_rss_mb();

  if (json) {
    nlohmann::json out = {
        {"model", file},
        {"states", model.num_states()},
        {"actions", model.num_actions()},
        {"observations", model.num_observations()},
        {"discount", model.discount()},
        {"load_s", load_s},
        {"bounds_s", bounds_s},
        {"quick", quick},
        {"warm_start", warm},
        {"workers", workers},
        {"online_gap", online_gap},
        {"peak_rss_mb", {{"offline", offline_rss_mb}, {"total", total_rss_mb}}},
        {"load_average", {{"start", load_at_start}, {"end", load_average()}}},
        {"pomcp_rollouts", random_rollouts ? "random" : "mdp-greedy"},
        {"memory_limit_mb", memory_mb},
        {"time_limit_s", {{"pomhdp", time_limit}, {"pomcp", pomcp_time_limit}}},
        {"published_value", published ? nlohmann::json(*published) : nlohmann::json()},
        {"pomhdp", to_json(pomhdp, budget)},
        {"pomcp", to_json(pomcp, pomcp_budget)}};
    out["pomhdp"]["offline"] = {{"lower", off.lower},
                                {"upper", off.upper},
                                {"gap", off.upper - off.lower},
                                {"seconds", off.seconds},
                                {"budget_s", offline},
                                {"trials", off.iterations},
                                {"nodes", off.nodes},
                                {"memory_bytes", off.memory_bytes},
                                {"reclaims", offline_solver.reclaims()}};
    std::printf("%s\n", out.dump().c_str());
    return 0;
  }
  std::printf(
      "%s: %d states, %d actions, %d observations, discount %g (read in %.2f s, bounds %.2f s)\n",
      file.c_str(), model.num_states(), model.num_actions(), model.num_observations(),
      model.discount(), load_s, bounds_s);
  if (published) std::printf("published optimum at the initial belief: %.2f\n", *published);
  std::printf(
      "\nPOMHDP offline from the initial belief (budget %.0f s): lower %.4f, upper %.4f, gap %.4f\n"
      "  %.2f s, %llu trials, %zu belief nodes, %.1f MB (limit %.0f MB, reached %llu times)\n",
      offline, off.lower, off.upper, off.upper - off.lower, off.seconds,
      static_cast<unsigned long long>(off.iterations), off.nodes, off.memory_bytes / 1e6, memory_mb,
      static_cast<unsigned long long>(offline_solver.reclaims()));
  std::printf("  peak resident memory after the offline solve: %.0f MB\n", offline_rss_mb);
  std::printf(
      "\nonline on %d workers, %s (value = mean discounted return, 95%% CI; POMHDP steps stop "
      "at a root gap of %g):\n",
      workers,
      warm ? "searches kept between episodes (warm starts)"
           : "an empty search at the start of every episode",
      online_gap);
  std::printf("%-7s %9s %8s %18s %18s %9s %9s %10s %10s %12s %10s %9s %8s\n", "solver", "budget_s",
              "episodes", "value +- ci95", "cv value +- ci95", "lower_0", "upper_0", "med_step_s",
              "max_step_s", "iter/step", "max_nodes", "max_MB", "total_s");
  for (const auto& [name, e, b] :
       {std::tuple{"POMHDP", &pomhdp, budget}, std::tuple{"POMCP", &pomcp, pomcp_budget}}) {
    std::printf(
        "%-7s %9.3g %8zu %10.3f +- %5.3f %10.3f +- %5.3f %9.3f %9.3f %10.4f %10.4f %12.1f %10zu "
        "%9.1f %8.1f\n",
        name, b, e->returns.size(), e->mean, e->ci95, e->cv_mean, e->cv_ci95, e->first_step.lower,
        e->first_step.upper, e->median_step_seconds, e->max_step_seconds,
        e->mean_iterations_per_step, e->max_nodes, e->max_memory_bytes / 1e6, e->seconds);
  }
  std::printf(
      "(cv value: the same mean estimated with the start state's MDP value as a control "
      "variate;\n lower_0/upper_0: root bounds after the first step's search; POMCP's are its "
      "value estimate)\n");
  std::printf("load average %.1f at the start, %.1f at the end; peak resident memory %.0f MB\n",
              load_at_start, load_average(), total_rss_mb);
  if (pomhdp.lost_beliefs + pomcp.lost_beliefs > 0) {
    std::printf("episodes cut by an observation the belief ruled out: POMHDP %d, POMCP %d\n",
                pomhdp.lost_beliefs, pomcp.lost_beliefs);
  }
  return 0;
}
