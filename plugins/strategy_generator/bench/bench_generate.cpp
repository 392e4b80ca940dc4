// Strategy generation, measured: time to one strategy (5 particles,
// horizon 6 by default) for A1 and B1 worlds with 1 and 2 local simulation
// workers, and with 2 local + 2 remote ones (a worker kernel in another
// network namespace, over DDS: `plr run` of the generator node, as a user
// runs it); simulated actions per second; the root's bounds at the end; the
// tree's size. Each generation starts from nothing (no stored results). With more
// than one worker count, the strategies must come out the same; the bench
// says whether they did. Then each strategy runs open loop from its own
// world on mass particles not used for planning, against strategy H over
// the same number of actions.
//
//   bench_generate [--quick] [--json] [--worlds A1:1,B1:1] [--workers 1,2,2+2]
//                  [--trials N] [--particles N] [--horizon N] [--eval N]
//                  [--partial-tree] [--fidelity full|adaptive|fast] [--compare-fidelity]
//   bench_generate --library FILE [--eval N] [--json]   (evaluation only)
// --workers: a list of L (local worker processes) or L+R (and R remote
// workers: one worker kernel with R threads in a network namespace; on
// loopback where namespaces are not permitted, which the output says).
// --partial-tree: the strategy stops at beliefs no trial expanded (no
// simulations to unroll it; with --trials 1 that measures the root's batch).
// --quick: one full-size strategy (5 particles, horizon 6) for A1 seed 1
// with 2 local workers, no evaluation.
// --fidelity: the level the generations simulate at (docs/fidelity.md); below
// full each strategy is then re-evaluated at full fidelity on fresh
// particles (its two values printed). --compare-fidelity: every generation
// at full fidelity and at --fidelity's level, side by side: the wall time
// of a POMHDP trial (median over the trials, from the anytime curve) at
// each, and their ratio; with the simulations in this process (--workers 0)
// also a trial's CPU time, which the machine's load does not change. With
// --quick: B1 seed 1 with the shipped library's settings (3 particles,
// horizon 4, 4 trials), simulated in this process.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "bench_cli.hpp"
#include "bench_util.hpp"
#include "plr/actions/in_process.hpp"
#include "plr/episode/open_loop.hpp"
#include "plr/jobs/in_process_runner.hpp"
#include "plr/planning/lattice_planner.hpp"
#include "plr/sim/generators.hpp"
#include "plr/sim/library.hpp"
#include "plr/sim/physics.hpp"
#include "plr/sim/shipped_files.hpp"
#include "remote_fixture.hpp"
#include "truck/fidelity_check.hpp"
#include "truck/generate.hpp"
#include "truck/worker_runner.hpp"

namespace {

using namespace plr;
using generator::GenerateOptions;
using Clock = std::chrono::steady_clock;

struct WorldSpec {
  sim::EnvFamily family;
  std::uint64_t seed;
};

// Where the simulations run: `local` worker processes (0 with no remote
// ones: in this process) and `remote` worker threads on "another machine".
struct Workers {
  int local = 1, remote = 0;
  std::string name() const {
    return remote > 0 ? std::to_string(local) + "+" + std::to_string(remote)
                      : std::to_string(local);
  }
};

// What one generation gave.
struct Generated {
  sim::LibraryEntry entry;
  double wall_s = 0;
  double check_wall_s = 0;  // its re-evaluation at full fidelity (made below full)
  // This process's CPU seconds of each trial: all of a trial's work when
  // the simulations run in this process (--workers 0), whatever the load.
  std::vector<double> trial_cpu_s;
  double search_cpu_s = NAN;  // the whole search and unrolling, without the check
  // Made at full fidelity in a comparison: the strategy valued at full on
  // the fresh particles the lower level's strategy is checked on.
  std::optional<sim::FidelityCheck> fresh;
  std::uint64_t simulated = 0;
  double simulated_robot_s = NAN, simulated_wall_s = NAN;  // unknown over DDS
  std::string note;
};

std::string worker_program(const char* argv0) {
  std::error_code ec;
  const auto self = std::filesystem::read_symlink("/proc/self/exe", ec);
  return ec ? std::string(argv0) : (self.parent_path() / "plr_sim_worker").string();
}

// A generation by `plr run` of the generator node with w.local local
// workers and w.remote remote ones: a simulation_worker kernel with
// w.remote threads in another network namespace, over DDS. The wall time
// is the generator's own (its provenance), without the kernels' start.
plr::Expected<Generated> generate_over_dds(const std::string& bin_dir, const WorldSpec& world,
                                           const GenerateOptions& o, int particles,
                                           const Workers& w) {
  namespace rt = plr::remote_test;
  namespace fs = std::filesystem;
  rt::VethNamespace net;
  const fs::path dir = fs::temp_directory_path() / ("bench_generate_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const int domain = 40 + ::getpid() % 60;
  const std::string plr = bin_dir + "/plr";
  const auto worker = rt::write_file(
      (dir / "worker.yaml").string(),
      fmt::format("pipeline: bench_sim_worker\nnodes:\n  worker:\n    plugin: simulation_worker\n"
                  "    params: {{threads: {}}}\nremote:\n  dds: {{domain: {}, interfaces: [{}], "
                  "export: [\"sim/simulate\"]}}\n",
                  w.remote, domain, net.there));
  rt::Proc worker_kernel(
      net.target(), std::vector<std::string>{plr, "run", worker, "--report", (dir / "w").string()},
      (dir / "worker.log").string());
  if (!rt::eventually(std::chrono::seconds(30), [&] {
        return rt::slurp(worker_kernel.log).find("running (1 nodes)") != std::string::npos;
      }))
    return plr::make_error(PLR_ERR_INTERNAL,
                           "the worker kernel did not start: " + rt::slurp(worker_kernel.log));
  const auto config = rt::write_file(
      (dir / "generate.yaml").string(),
      fmt::format("pipeline: bench_generate\nnodes:\n  generator:\n    plugin: strategy_generator\n"
                  "    params:\n      library: ${{report_dir}}/library.plrl\n"
                  "      worlds: [{{family: {}, seed: {}}}]\n      particles: {}\n"
                  "      horizon: {}\n      trials: {}\n      epsilon1: {}\n      epsilon2: {}\n"
                  "      seed: {}\n      complete_tree: {}\n      workers: {}\n"
                  "      remote_workers: {}\n      progress: false\n      fidelity: {}\n"
                  "remote:\n  dds: {{domain: {}, interfaces: [{}], import: [\"sim/simulate\"]}}\n",
                  sim::to_string(world.family), world.seed, particles, o.truck.horizon, o.trials,
                  o.epsilon1, o.epsilon2, o.seed, o.complete_tree, w.local, w.remote,
                  sim::to_string(o.fidelity), domain, net.here));
  rt::Proc generator(
      "", std::vector<std::string>{plr, "run", config, "--report", (dir / "gen").string()},
      (dir / "generate.log").string());
  if (const int rc = generator.wait(std::chrono::hours(3)); rc != 0)
    return plr::make_error(PLR_ERR_INTERNAL,
                           fmt::format("plr run (exit {}): {}", rc, rt::slurp(generator.log)));
  auto lib = sim::load_library(dir / "gen/library.plrl");
  if (!lib) return lib.error();
  if (lib->entries.size() != 1)
    return plr::make_error(PLR_ERR_INTERNAL, "the library does not hold one strategy");
  Generated g;
  g.entry = std::move(lib->entries.front());
  g.wall_s = g.entry.provenance.wall_s;
  g.simulated = g.entry.provenance.simulations;
  g.note = net.isolated
               ? "remote workers in network namespace " + net.ns
               : "namespaces not permitted (" + net.why_not + "): remote workers on loopback";
  fs::remove_all(dir);
  return g;
}

nlohmann::json nullable(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json();
}

double cpu_s() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// The wall time of each POMHDP trial: the anytime curve has a point after
// each (the first at time 0, before the root's batch).
std::vector<double> trial_walls(const sim::LibraryEntry& e) {
  std::vector<double> out;
  for (std::size_t i = 1; i < e.curve.size(); ++i)
    out.push_back(e.curve[i].wall_s - e.curve[i - 1].wall_s);
  return out;
}

struct Eval {
  double strategy_boxes = 0, strategy_s = 0, h_boxes = 0, h_s = 0, strategy_steps = 0;
  int runs = 0;
};

// Open loop from the strategy's own world against H over `actions`
// actions, on mass particles the generator did not plan with.
std::optional<nlohmann::json> evaluate(const std::string& name, const sim::World& world,
                                       sim::EnvFamily family, const sim::Strategy& strategy,
                                       int actions, int particles, std::uint64_t seed, bool json) {
  auto robot = sim::load_robot();
  auto lattice = planning::LatticeConfig::from_file(
      sim::shipped_file("robots/unloader_lattice.yaml").value().string());
  if (!robot || !lattice) return std::nullopt;
  planning::LatticePlanner planner(std::move(*lattice));
  const actions::ActionModel model(*robot, {});
  Eval ev;
  for (int p = 0; p < particles; ++p) {
    const sim::World truth =
        sim::sample_masses(world, family, sim::particle_seed(seed + 1'000'003, p));
    for (const bool use_strategy : {true, false}) {
      actions::UnloaderSimulation simulation(*robot, truth);
      actions::InProcessBackend backend(simulation, planner);
      actions::Memory memory;
      auto run = episode::run_open_loop(model, backend, memory,
                                        use_strategy ? std::optional(strategy) : std::nullopt, {},
                                        static_cast<std::uint64_t>(actions));
      if (!run) {
        std::fprintf(stderr, "bench_generate: %s\n", run.error().message.c_str());
        return std::nullopt;
      }
      (use_strategy ? ev.strategy_boxes : ev.h_boxes) += run->boxes;
      (use_strategy ? ev.strategy_s : ev.h_s) += run->robot_time_s;
      if (use_strategy) ev.strategy_steps += static_cast<double>(run->strategy_steps);
    }
    ++ev.runs;
  }
  const double n = ev.runs;
  const double rate_s = ev.strategy_s > 0 ? ev.strategy_boxes / ev.strategy_s : 0;
  const double rate_h = ev.h_s > 0 ? ev.h_boxes / ev.h_s : 0;
  if (!json) {
    std::printf(
        "%-6s open loop, %d held-out particles, %d actions: strategy %.2f boxes in %.1f s "
        "(%.3f boxes/s, %.1f of its own steps), H %.2f boxes in %.1f s (%.3f boxes/s)\n",
        name.c_str(), ev.runs, actions, ev.strategy_boxes / n, ev.strategy_s / n, rate_s,
        ev.strategy_steps / n, ev.h_boxes / n, ev.h_s / n, rate_h);
    std::fflush(stdout);
  }
  return nlohmann::json{{"world", name},
                        {"held_out_particles", ev.runs},
                        {"actions", actions},
                        {"strategy_boxes", ev.strategy_boxes / n},
                        {"strategy_robot_s", ev.strategy_s / n},
                        {"strategy_steps", ev.strategy_steps / n},
                        {"h_boxes", ev.h_boxes / n},
                        {"h_robot_s", ev.h_s / n},
                        {"strategy_boxes_per_s", rate_s},
                        {"h_boxes_per_s", rate_h},
                        {"at_least_as_fast_as_h", rate_s >= rate_h}};
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false, json = false;
  std::vector<WorldSpec> worlds{{sim::EnvFamily::kA1, 1}, {sim::EnvFamily::kB1, 1}};
  std::vector<Workers> worker_counts{{1, 0}, {2, 0}, {2, 2}};
  GenerateOptions o;
  int particles = 5, eval_particles = 3;
  std::string library;
  CLI::App app{
      "Strategy generation measured: time to one strategy with local and remote "
      "simulation workers, then each strategy open loop against H"};
  plr::bench::add_quick_flag(app, quick, "A1 seed 1 with 2 local workers, no evaluation");
  plr::bench::add_json_flag(app, json);
  app.add_option_function<std::vector<std::string>>(
         "--worlds",
         [&](const std::vector<std::string>& list) {
           worlds.clear();
           for (const auto& w : list) {
             const auto colon = w.find(':');
             const auto f = sim::parse_env_family(w.substr(0, colon));
             if (!f || colon == std::string::npos)
               throw CLI::ValidationError("--worlds", "not FAMILY:SEED: '" + w + "'");
             worlds.push_back({*f, std::strtoull(w.c_str() + colon + 1, nullptr, 10)});
           }
         },
         "Worlds as FAMILY:SEED (default A1:1,B1:1)")
      ->delimiter(',')
      ->type_name("LIST");
  app.add_option_function<std::vector<std::string>>(
         "--workers",
         [&](const std::vector<std::string>& list) {
           worker_counts.clear();
           for (const auto& w : list) {
             const auto plus = w.find('+');
             Workers spec{std::atoi(w.c_str()),
                          plus == std::string::npos ? 0 : std::atoi(w.c_str() + plus + 1)};
             if (spec.local < 0 || spec.remote < 0)
               throw CLI::ValidationError("--workers", "not L or L+R: '" + w + "'");
             worker_counts.push_back(spec);
           }
         },
         "Worker counts to compare: L local processes, or L+R with R remote workers over DDS "
         "(default 1,2,2+2)")
      ->delimiter(',')
      ->type_name("LIST");
  app.add_option("--trials", o.trials, "Trial budget of each generation")->capture_default_str();
  app.add_option("--particles", particles, "Mass particles the generator plans with")
      ->capture_default_str();
  app.add_option("--horizon", o.truck.horizon, "Actions to the horizon")->capture_default_str();
  app.add_option("--eval", eval_particles, "Held-out particles of the open-loop evaluation")
      ->capture_default_str();
  app.add_flag_callback(
      "--partial-tree", [&] { o.complete_tree = false; },
      "The strategy stops at beliefs no trial expanded");
  app.add_option("--library", library, "Only evaluate every strategy of this library file");
  std::string fidelity = "full";
  bool compare = false;
  app.add_option("--fidelity", fidelity, "Simulation fidelity of the generations")
      ->check(CLI::IsMember({"full", "adaptive", "fast"}))
      ->capture_default_str();
  app.add_flag("--compare-fidelity", compare,
               "Each generation at full fidelity and at --fidelity's level, side by side");
  plr::bench::parse_or_exit(app, argc, argv);
  const sim::Fidelity level = sim::parse_fidelity(fidelity).value();
  if (compare && level == sim::Fidelity::kFull) {
    std::fprintf(stderr, "bench_generate: --compare-fidelity needs --fidelity adaptive or fast\n");
    return 2;
  }
  if (quick && compare) {
    worlds = {{sim::EnvFamily::kB1, 1}};
    worker_counts = {{0, 0}};
    eval_particles = 0;
    particles = 3;
    o.truck.horizon = 4;
    o.trials = 4;
  } else if (quick) {
    worlds = {{sim::EnvFamily::kA1, 1}};
    worker_counts = {{2, 0}};
    eval_particles = 0;
  }
  std::vector<sim::Fidelity> levels{level};
  if (compare) levels = {sim::Fidelity::kFull, level};
  if (!library.empty()) {
    // Only the evaluation, of every strategy of a library.
    auto lib = sim::load_library(library);
    if (!lib) {
      std::fprintf(stderr, "bench_generate: %s\n", lib.error().message.c_str());
      return 1;
    }
    nlohmann::json evals = nlohmann::json::array();
    for (const sim::LibraryEntry& e : lib->entries) {
      const auto family = sim::parse_env_family(e.family);
      if (!family) continue;
      const auto ev =
          evaluate(e.name, e.world, *family, e.strategy, static_cast<int>(e.provenance.horizon),
                   eval_particles, e.provenance.seed, json);
      if (!ev) return 1;
      evals.push_back(*ev);
    }
    if (json) std::printf("%s\n", nlohmann::json{{"evaluation", evals}}.dump(2).c_str());
    return 0;
  }
  auto rig = actions::make_rig("{}");
  if (!rig) {
    std::fprintf(stderr, "bench_generate: %s\n", rig.error().message.c_str());
    return 1;
  }
  const std::string program = worker_program(argv[0]);
  nlohmann::json out = {{"particles", particles},
                        {"horizon", o.truck.horizon},
                        {"trials", o.trials},
                        {"epsilon1", o.epsilon1},
                        {"epsilon2", o.epsilon2},
                        {"fidelity", fidelity},
                        {"runs", nlohmann::json::array()},
                        {"evaluation", nlohmann::json::array()}};
  if (compare) out["fidelity_comparison"] = nlohmann::json::array();
  for (const WorldSpec& w : worlds) {
    const generator::Problem problem = generator::make_problem(w.family, w.seed, particles, o.seed);
    std::string first_strategy;
    std::optional<sim::Strategy> strategy;
    for (const Workers& workers : worker_counts) {
      std::vector<double> median_trial, median_cpu, per_trial_cpu;  // per level, for the comparison
      for (const sim::Fidelity at : levels) {
        o.fidelity = at;
        plr::Expected<Generated> r = Generated{};
        if (workers.remote > 0) {
          std::fprintf(stderr, "%s, %s workers: plr run over DDS\n", problem.name.c_str(),
                       workers.name().c_str());
          r = generate_over_dds(std::filesystem::path(program).parent_path().string(), w, o,
                                particles, workers);
        } else {
          jobs::Kinds kinds;
          std::unique_ptr<jobs::Runner> runner;
          if (workers.local <= 0) {
            actions::add_sim_action(kinds);
            runner = std::make_unique<jobs::InProcessRunner>(kinds);
          } else {
            generator::WorkerOptions worker_options;
            worker_options.local.command = {program};
            worker_options.local.workers = static_cast<unsigned>(workers.local);
            auto pool = generator::WorkerRunner::create(std::move(worker_options));
            if (!pool) {
              std::fprintf(stderr, "bench_generate: %s\n", pool.error().message.c_str());
              return 1;
            }
            runner = std::move(*pool);
          }
          generator::Simulator simulator(*runner, std::max(workers.local, 1), "{}");
          const auto t0 = Clock::now();
          std::vector<double> cpu_marks;  // after each trial (the first: before any)
          const double cpu0 = cpu_s();
          auto made = generator::generate(
              problem, o, **rig, simulator, nullptr, [&](const generator::GenerateProgress& p) {
                if (!p.unrolling && p.trials == cpu_marks.size()) cpu_marks.push_back(cpu_s());
                std::fprintf(stderr,
                             "\r\033[K%s, %s workers, %s: trial %llu/%llu, %zu "
                             "nodes, %llu sims, root [%.1f, %.1f], %.0f s",
                             problem.name.c_str(), workers.name().c_str(),
                             sim::to_string(at).c_str(), (unsigned long long)p.trials,
                             (unsigned long long)p.trial_budget, p.nodes,
                             (unsigned long long)p.simulated, p.lower, p.upper, p.wall_s);
                return true;
              });
          std::fprintf(stderr, "\n");
          if (made) {
            Generated& g = *r;
            g.entry = std::move(made->entry);
            g.wall_s = std::chrono::duration<double>(Clock::now() - t0).count();
            g.simulated = made->simulated;
            g.simulated_robot_s = made->simulated_robot_s;
            g.simulated_wall_s = made->simulated_wall_s;
            g.check_wall_s = made->check_wall_s;
            g.search_cpu_s = cpu_s() - cpu0 - made->check_cpu_s;
            for (std::size_t i = 1; i < cpu_marks.size(); ++i)
              g.trial_cpu_s.push_back(cpu_marks[i] - cpu_marks[i - 1]);
            if (compare && at == sim::Fidelity::kFull) {
              // The same fresh particles as the lower level's check.
              auto fresh = generator::check_at_full(problem, g.entry.strategy, o, {},
                                                    static_cast<std::uint32_t>(particles), **rig,
                                                    simulator, nullptr);
              if (!fresh) {
                std::fprintf(stderr, "bench_generate: %s\n", fresh.error().message.c_str());
                return 1;
              }
              g.fresh = *fresh;
            }
          } else {
            r = made.error();
          }
        }
        if (!r) {
          std::fprintf(stderr, "bench_generate: %s\n", r.error().message.c_str());
          return 1;
        }
        const sim::LibraryEntry& e = r->entry;
        // The search's own time: the re-evaluation at full fidelity is apart.
        const double wall = r->wall_s - r->check_wall_s;
        const std::vector<double> trials = trial_walls(e);
        median_trial.push_back(plr::bench::median(trials));
        median_cpu.push_back(plr::bench::median(r->trial_cpu_s));
        per_trial_cpu.push_back(r->search_cpu_s / std::max<double>(1, double(e.provenance.trials)));
        const std::string yaml = sim::format_yaml(e.strategy);
        if (first_strategy.empty()) first_strategy = yaml;
        strategy = e.strategy;
        out["runs"].push_back(
            {{"world", problem.name},
             {"boxes", problem.world.boxes.size()},
             {"workers", workers.local + workers.remote},
             {"local_workers", workers.local},
             {"remote_workers", workers.remote},
             {"transport", workers.remote > 0 ? r->note : "pipes to local processes"},
             {"particles", particles},
             {"horizon", o.truck.horizon},
             {"wall_s", wall},
             {"trials", e.provenance.trials},
             {"belief_nodes", e.provenance.nodes},
             {"nodes", e.strategy.nodes.size()},
             {"depth", e.strategy.depth()},
             {"simulations", r->simulated},
             {"actions_per_s", double(r->simulated) / wall},
             {"simulated_robot_s", r->simulated_robot_s},
             {"real_time_factor", nullable(r->simulated_robot_s / wall)},
             {"worker_s_per_action",
              nullable(r->simulated_wall_s / std::max<double>(1, double(r->simulated)))},
             {"lower", e.lower},
             {"upper", e.upper},
             {"fidelity", e.fidelity},
             {"trial_wall_s", trials},
             {"trial_wall_s_median", median_trial.back()},
             {"trial_cpu_s", r->trial_cpu_s},
             {"trial_cpu_s_median", median_cpu.back()},
             {"search_cpu_s", nullable(r->search_cpu_s)},
             {"search_cpu_s_per_trial", nullable(per_trial_cpu.back())},
             {"search_cpu_s_per_simulation",
              nullable(r->search_cpu_s / std::max<double>(1, double(r->simulated)))},
             {"full_value_on_fresh_particles",
              r->fresh ? nlohmann::json{{"value", r->fresh->full_value},
                                        {"boxes", r->fresh->full_boxes},
                                        {"particles", r->fresh->full_particles},
                                        {"first_particle", r->fresh->first_particle}}
                       : nlohmann::json()},
             {"check", e.check ? nlohmann::json{{"value", e.check->value},
                                                {"boxes", e.check->boxes},
                                                {"full_value", e.check->full_value},
                                                {"full_boxes", e.check->full_boxes},
                                                {"full_particles", e.check->full_particles},
                                                {"first_particle", e.check->first_particle},
                                                {"wall_s", r->check_wall_s}}
                               : nlohmann::json()},
             {"same_strategy_as_first", yaml == first_strategy}});
        if (!json) {
          std::printf(
              "%-6s %-3s workers, %-8s: %6.1f s, %llu trials (median %.1f s each), %zu tree nodes "
              "(depth %zu), %llu simulated actions (%.2f/s), root [%.1f, %.1f]%s%s\n",
              problem.name.c_str(), workers.name().c_str(), e.fidelity.c_str(), wall,
              (unsigned long long)e.provenance.trials, median_trial.back(), e.strategy.nodes.size(),
              e.strategy.depth(), (unsigned long long)r->simulated, double(r->simulated) / wall,
              e.lower, e.upper, yaml == first_strategy ? "" : "  DIFFERENT STRATEGY",
              workers.remote > 0 ? ("  (" + r->note + ")").c_str() : "");
          if (!r->trial_cpu_s.empty() && workers.local == 0)
            std::printf("       a trial's CPU time in this process: median %.1f s\n",
                        median_cpu.back());
          if (r->fresh)
            std::printf("       at full fidelity on %u fresh particles: %.1f (%.1f boxes)\n",
                        r->fresh->full_particles, r->fresh->full_value, r->fresh->full_boxes);
          if (e.check)
            std::printf(
                "       value at %s %.1f (%.1f boxes) on its %u particles; at full fidelity %.1f "
                "(%.1f boxes) on %u fresh particles (%.1f s)\n",
                e.fidelity.c_str(), e.check->value, e.check->boxes, e.provenance.particles,
                e.check->full_value, e.check->full_boxes, e.check->full_particles, r->check_wall_s);
          std::fflush(stdout);
        }
      }
      if (compare) {
        const double ratio = median_trial[1] > 0 ? median_trial[0] / median_trial[1] : NAN;
        out["fidelity_comparison"].push_back({{"world", problem.name},
                                              {"workers", workers.name()},
                                              {"full_trial_wall_s_median", median_trial[0]},
                                              {"level", fidelity},
                                              {"level_trial_wall_s_median", median_trial[1]},
                                              {"full_over_level", nullable(ratio)}});
        if (workers.local == 0 && workers.remote == 0) {
          const double cpu_ratio = median_cpu[1] > 0 ? median_cpu[0] / median_cpu[1] : NAN;
          auto& c = out["fidelity_comparison"].back();
          c["full_trial_cpu_s_median"] = median_cpu[0];
          c["level_trial_cpu_s_median"] = median_cpu[1];
          c["full_over_level_cpu"] = nullable(cpu_ratio);
          c["full_search_cpu_s_per_trial"] = per_trial_cpu[0];
          c["level_search_cpu_s_per_trial"] = per_trial_cpu[1];
          c["full_over_level_search_cpu"] = nullable(per_trial_cpu[0] / per_trial_cpu[1]);
        }
        if (!json) {
          std::printf("%-6s %-3s workers: a trial takes %.2f s at full, %.2f s at %s: %.2fx\n",
                      problem.name.c_str(), workers.name().c_str(), median_trial[0],
                      median_trial[1], fidelity.c_str(), ratio);
          if (workers.local == 0 && workers.remote == 0)
            std::printf(
                "%-6s %-3s workers: a trial's CPU time %.2f s at full, %.2f s at %s: %.2fx\n",
                problem.name.c_str(), workers.name().c_str(), median_cpu[0], median_cpu[1],
                fidelity.c_str(), median_cpu[0] / median_cpu[1]);
        }
      }
    }
    if (eval_particles <= 0 || !strategy) continue;
    const auto ev = evaluate(problem.name, problem.world, w.family, *strategy, o.truck.horizon,
                             eval_particles, o.seed, json);
    if (!ev) return 1;
    out["evaluation"].push_back(*ev);
  }
  if (json) std::printf("%s\n", out.dump(2).c_str());
  return 0;
}
