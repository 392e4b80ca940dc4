// Strategy H to the end of the run on many seeds of every family, in process
// (the action model on the simulation, no bus), in parallel worker processes.
// Per family: the unloaded fraction (mean and the worst seed), robot time,
// boxes per robot-second, why runs stopped, why boxes were left,
// robot-trailer collisions, the share of robot time wasted (issue 46), and
// the planner's searches per mode: the expansions of the solved ones and
// how many spent a whole budget. Issue 18's target is printed beside them:
// every run >= 98 % unloaded.
//
//   bench_unload [--quick] [--json] [--seeds N] [--first S] [--families A1,C]
//                [--workers W] [--out DIR] [--timeout S] [--fidelity full|adaptive|fast]
//                [--experience on|off] [--plan-while-moving on|off] [--record-queries]
// Defaults: seeds 1-20 of every family, one worker per core, results in
// ./bench_unload. --quick: seeds 1-5. Each run is a job (plr/jobs); its
// result goes to the result store DIR as it finishes, with each action it
// took; beside it in DIR the settled start
// (F_seedS.start.yaml) and the world it left (F_seedS.final.yaml) when
// boxes remain, and the queries that spent a whole budget
// (F_seedS.failed_queries.bin; all runs' in DIR/failed_queries.bin, a
// query set for bench_planner); a stopped benchmark started again with the same DIR runs
// only what is missing. A run past --timeout (wall seconds, default
// 3600) is killed and counted as such. --fidelity: how accurately the boxes
// are simulated (plr/sim/fidelity.hpp; default full). --experience: the
// lattice planner reuses earlier paths within a trailer, or not (default:
// as the shipped lattice file says). --plan-while-moving: the next step is
// planned while a motion runs (ActionOptions::plan_while_moving; default
// on). --record-queries: every M1 and M2
// query of a run, in order, with its world (F_seedS.pick_queries.bin, one
// trailer's recurring motions for bench_planner --recurring).
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "bench_cli.hpp"
#include "bench_families.hpp"
#include "bench_util.hpp"
#include "plr/actions/in_process.hpp"
#include "plr/actions/rig.hpp"
#include "plr/atomic_file.hpp"
#include "plr/episode/engine.hpp"
#include "plr/jobs/process_runner.hpp"
#include "plr/jobs/progress.hpp"
#include "plr/planning/lattice_planner.hpp"
#include "plr/planning/query_set.hpp"
#include "plr/sim/generators.hpp"
#include "plr/sim/physics.hpp"
#include "plr/sim/shipped_files.hpp"
#include "plr/sim/world_io.hpp"

namespace {

namespace fs = std::filesystem;
namespace jobs = plr::jobs;
using plr::sim::EnvFamily;
using Clock = std::chrono::steady_clock;

constexpr double kTargetFraction = 0.98;  // issue 18: every run

struct Options {
  std::uint64_t first = 1, seeds = 20;
  std::vector<EnvFamily> families;
  unsigned workers = 0;
  std::string out = "bench_unload";
  double timeout_s = 3600;
  bool json = false;
  plr::sim::Fidelity fidelity = plr::sim::Fidelity::kFull;
  std::string experience;  // "on", "off", "" (the lattice file's)
  std::string plan_while_moving = "on";
  bool record_queries = false;
};

// A run; its settled start and the world it leaves are saved beside
// `file`'s name (F_seedS.start.yaml, F_seedS.final.yaml).
struct Job {
  EnvFamily family;
  std::uint64_t seed;
  fs::path file;
  plr::sim::Fidelity fidelity;
  std::string experience;
  bool record_queries = false;
  bool plan_while_moving = true;
};

constexpr const char* kRunKind = "unload.run";

[[noreturn]] void die(const std::string& what) {
  std::fprintf(stderr, "bench_unload: %s\n", what.c_str());
  std::_Exit(1);
}

template <typename T>
T value_or_die(plr::Expected<T> e) {
  if (!e) die(e.error().message);
  return std::move(*e);
}

// The planner's answers during a run: the expansions each solved query
// took, per mode (what sizes a mode's budget, docs/planner.md), and the
// queries that spent a whole budget, kept with their world as frames of a
// query set (plr/planning/query_set.hpp) for bench_planner.
class Recorder final : public plr::actions::Backend {
 public:
  Recorder(plr::actions::Backend& inner, bool record_picks)
      : inner_(inner), record_picks_(record_picks) {}
  plr::Expected<plr::actions::Perceived> observe() override { return inner_.observe(); }
  plr::Expected<plr::actions::Executed> execute(const plr::actions::Motion& m) override {
    return inner_.execute(m);
  }
  plr::Expected<plr::planning::DecodedPlanResponse> plan(const plr::planning::PlanQuery& q,
                                                         const plr::sim::World& world) override {
    auto r = inner_.plan(q, world);
    if (!r) return r;
    if (record_picks_ &&
        (q.mode == plr::planning::PlanMode::kArm || q.mode == plr::planning::PlanMode::kArmBase))
      picks.push_back(plr::planning::frame_query(q, world));
    const std::string mode = fmt::format("M{}", static_cast<int>(q.mode));
    if (r->status == plr::planning::PlanStatus::kSolved) {
      solved[mode].push_back(r->stats.expansions);
    } else if (r->stats.budget_exhausted) {
      ++spent[mode];
      frames.push_back(plr::planning::frame_query(q, world));
    }
    return r;
  }

  std::map<std::string, std::vector<std::uint64_t>> solved;
  std::map<std::string, std::uint64_t> spent;
  std::vector<std::vector<std::uint8_t>> frames;
  std::vector<std::vector<std::uint8_t>> picks;

 private:
  plr::actions::Backend& inner_;
  bool record_picks_;
};

// One run, in the worker process: H from the family's environment to the end.
nlohmann::json run(const Job& job) {
  const auto start = Clock::now();
  const plr::sim::RobotModel robot = value_or_die(plr::sim::load_robot());
  plr::planning::LatticePlanner planner(value_or_die(plr::planning::LatticeConfig::from_file(
      value_or_die(plr::sim::shipped_file("robots/unloader_lattice.yaml")))));
  if (!job.experience.empty()) planner.set_experience(job.experience == "on");
  plr::actions::UnloaderOptions sim_options;
  sim_options.fidelity = job.fidelity;
  plr::actions::UnloaderSimulation simulation(robot,
                                              plr::sim::make_environment(job.family, job.seed),
                                              plr::actions::home_configuration(), sim_options);
  plr::actions::InProcessBackend in_process(simulation, planner);
  Recorder backend(in_process, job.record_queries);
  // The settled start, beside the world the run leaves: a run can be replayed
  // or drawn from the two.
  auto start_world = job.file;
  if (auto saved =
          plr::sim::save_world(simulation.truth(), start_world.replace_extension(".start.yaml"));
      !saved)
    die(saved.error().message);
  // As configs/unload_sim.yaml: plans are bounded by expansions, so the
  // outcome does not depend on the load. The time limit is only a safety
  // net; on a machine the other workers (or other jobs) load tenfold, a
  // budget's search takes minutes, and the run's own timeout is the net.
  plr::actions::ActionOptions options;
  options.plan_timeout_s = plr::actions::kOfflinePlanTimeoutS;
  options.plan_while_moving = job.plan_while_moving;
  const plr::actions::ActionModel model(robot, options);
  const auto episode = value_or_die(plr::episode::run_episode(
      model, backend, plr::episode::hardcoded_source(plr::sim::HardcodedParams{})));
  // Each action, so that a run can be read step by step.
  nlohmann::json steps = nlohmann::json::array();
  // Planning while moving: plans made during a motion, those used, and the
  // modelled planning their motions covered.
  std::uint64_t plans_ahead = 0, plans_ahead_used = 0;
  double plan_hidden_s = 0.0;
  for (const auto& s : episode.steps) {
    plans_ahead += s.outcome.plans_ahead;
    plans_ahead_used += s.outcome.plans_ahead_used;
    plan_hidden_s += s.outcome.plan_hidden_s;
  }
  for (const auto& s : episode.steps)
    steps.push_back({{"action", plr::sim::to_string(s.action)},
                     {"observation", plr::sim::to_string(s.observation)},
                     {"wall_height", s.wall_height},
                     {"pile_height", s.pile_height},
                     {"pile_depth", s.pile_depth},
                     {"applicable", s.outcome.applicable},
                     {"why", s.outcome.why},
                     {"boxes", s.outcome.boxes},
                     {"robot_time_s", s.outcome.robot_time_s},
                     {"plan_s", s.outcome.plan_model_s},
                     {"failed_grasp", s.outcome.failed_grasp},
                     {"robot_trailer_contacts", s.outcome.robot_trailer_contacts},
                     {"notes", s.notes}});
  if (!episode.final_world.boxes.empty()) {
    auto world = job.file;
    if (auto saved =
            plr::sim::save_world(episode.final_world, world.replace_extension(".final.yaml"));
        !saved)
      die(saved.error().message);
  }
  auto failed_queries = job.file;
  failed_queries.replace_extension(".failed_queries.bin");
  if (auto saved = plr::planning::save_query_set(backend.frames, failed_queries); !saved)
    die(saved.error().message);
  if (job.record_queries) {
    auto picks = job.file;
    if (auto saved = plr::planning::save_query_set(backend.picks,
                                                   picks.replace_extension(".pick_queries.bin"));
        !saved)
      die(saved.error().message);
  }
  nlohmann::json left = nlohmann::json::array();
  for (const auto& l : episode.left)
    left.push_back({{"id", l.id}, {"reason", to_string(l.reason)}, {"detail", l.detail}});
  return {{"family", std::string(to_string(job.family))},
          {"seed", job.seed},
          {"experience", planner.experience()},
          {"plan_while_moving", job.plan_while_moving},
          {"boxes_total", episode.boxes_total},
          {"boxes_unloaded", episode.boxes_unloaded},
          {"robot_time_s", episode.robot_time_s},
          {"wasted_s", episode.wasted_s},
          {"wasted_share", plr::episode::wasted_share(episode)},
          {"plans_ahead", plans_ahead},
          {"plans_ahead_used", plans_ahead_used},
          {"plan_hidden_s", plan_hidden_s},
          {"actions", episode.actions},
          {"failed_grasps", episode.failed_grasps},
          {"robot_trailer_collisions", episode.robot_trailer_contacts},
          {"stop_reason", episode.stop_reason},
          {"left", left},
          {"left_by_reason", plr::episode::count_by_reason(episode.left)},
          {"steps", steps},
          {"solved_expansions", backend.solved},
          {"budget_spent", backend.spent},
          {"wall_s", std::chrono::duration<double>(Clock::now() - start).count()}};
}

// What a run that ended without a result counts as.
nlohmann::json failed(const Job& job, const jobs::Result& r) {
  if (r.error.rfind("killed", 0) == 0)
    return {{"family", std::string(to_string(job.family))},
            {"seed", job.seed},
            {"timed_out", true},
            {"stop_reason", r.error},
            {"wall_s", r.wall_s}};
  return {{"family", std::string(to_string(job.family))},
          {"seed", job.seed},
          {"failed", true},
          {"stop_reason", r.error}};
}

void save(const fs::path& file, const nlohmann::json& j) {
  if (auto ok = plr::write_file_atomically(file.string(), j.dump(1) + "\n"); !ok)
    die(ok.error().message);
}

// Runs every run as a job in a child process of its own (plr/jobs); those
// whose result is in the store DIR are not run again.
std::vector<nlohmann::json> run_all(const std::vector<Job>& runs, const Options& o) {
  auto store = jobs::Store::open(o.out);
  if (!store) die(store.error().message);
  jobs::Kinds kinds;
  kinds.add(kRunKind, [&](const jobs::Bytes& input) -> plr::Expected<jobs::Bytes> {
    return jobs::to_bytes(run(runs.at(std::stoul(jobs::to_text(input)))).dump(1));
  });
  std::vector<jobs::Job> all;
  for (std::size_t i = 0; i < runs.size(); ++i)
    all.push_back({kRunKind, runs[i].file.stem().string(), jobs::to_bytes(std::to_string(i))});
  auto runner = value_or_die(
      jobs::ProcessRunner::create({{}, &kinds, o.workers, o.timeout_s, 1, true, store->logs()}));
  auto outcome = jobs::run_with_progress("bench_unload", all, *runner, *store);
  if (!outcome) die(outcome.error().message);
  if (outcome->stopped) die("stopped; run it again with the same --out to go on");
  std::vector<nlohmann::json> results;
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const jobs::Result& r = outcome->results[i];
    if (!r.ok) {
      results.push_back(failed(runs[i], r));
      continue;
    }
    auto j = nlohmann::json::parse(jobs::to_text(r.output), nullptr, false);
    if (j.is_discarded()) die(store->result_file(r.key).string() + ": not a run's result");
    results.push_back(std::move(j));
  }
  return results;
}

// The q-quantile of `v` (nearest rank); 0 for none.
std::uint64_t quantile(std::vector<std::uint64_t> v, double q) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
  return v[std::clamp<std::size_t>(rank, 1, v.size()) - 1];
}

// Per mode: the expansions of the solved queries (how many, quantiles) and
// the queries that spent a whole budget.
nlohmann::json searches(const std::vector<nlohmann::json>& runs, const std::string& family) {
  std::map<std::string, std::vector<std::uint64_t>> solved;
  std::map<std::string, std::uint64_t> spent;
  for (const auto& r : runs) {
    if (family != "all" && r.value("family", "") != family) continue;
    if (r.contains("solved_expansions"))
      for (const auto& [mode, v] : r["solved_expansions"].items())
        for (const auto& n : v) solved[mode].push_back(n.get<std::uint64_t>());
    if (r.contains("budget_spent"))
      for (const auto& [mode, n] : r["budget_spent"].items()) spent[mode] += n.get<std::uint64_t>();
  }
  nlohmann::json out = nlohmann::json::object();
  for (const auto& [mode, v] : solved)
    out[mode] = {{"solved", v.size()},       {"p50", quantile(v, 0.5)},
                 {"p95", quantile(v, 0.95)}, {"p99", quantile(v, 0.99)},
                 {"max", quantile(v, 1.0)},  {"budget_spent", spent[mode]}};
  for (const auto& [mode, n] : spent)
    if (!out.contains(mode)) out[mode] = {{"solved", 0}, {"budget_spent", n}};
  return out;
}

nlohmann::json summarize(const std::vector<nlohmann::json>& runs, EnvFamily family) {
  std::vector<double> fractions, robot_s, wasted;
  double boxes = 0, seconds = 0;
  std::uint64_t collisions = 0, below = 0, emptied = 0, boxes_left = 0;
  std::map<std::string, int> stops;
  std::map<std::string, std::uint64_t> left;
  // How often H met each structure and height class (its steps' observations).
  std::map<std::string, std::uint64_t> seen;
  for (const char* structure : {"pile", "wall"})
    for (const char* height : {"low", "mid", "high"})
      seen[fmt::format("{}/{}", structure, height)] = 0;
  std::string worst;
  double worst_fraction = 2;
  for (const auto& r : runs) {
    if (r.value("family", "") != to_string(family)) continue;
    ++stops[r.value("stop_reason", "?")];
    const auto total = r.value("boxes_total", 0u);
    const double f = total > 0 ? r.value("boxes_unloaded", 0u) / static_cast<double>(total) : 0.0;
    fractions.push_back(f);
    if (f < kTargetFraction) ++below;
    if (total > 0 && r.value("boxes_unloaded", 0u) == total) ++emptied;
    boxes_left += total - std::min(total, r.value("boxes_unloaded", 0u));
    if (f < worst_fraction) {
      worst_fraction = f;
      worst =
          fmt::format("seed {}: {}/{}", r.value("seed", 0), r.value("boxes_unloaded", 0u), total);
    }
    if (r.contains("robot_time_s")) {
      robot_s.push_back(r["robot_time_s"].get<double>());
      seconds += r["robot_time_s"].get<double>();
      boxes += r.value("boxes_unloaded", 0u);
    }
    if (r.contains("wasted_share")) wasted.push_back(r["wasted_share"].get<double>());
    collisions += r.value("robot_trailer_collisions", 0u);
    if (r.contains("left_by_reason"))
      for (const auto& [k, v] : r["left_by_reason"].items()) left[k] += v.get<std::uint64_t>();
    if (r.contains("steps"))
      for (const auto& step : r["steps"]) {
        const std::string o = step.value("observation", "");
        if (const auto cut = o.rfind('/'); cut != std::string::npos) ++seen[o.substr(0, cut)];
      }
  }
  double mean = 0;
  for (double f : fractions) mean += f;
  mean = fractions.empty() ? 0 : mean / static_cast<double>(fractions.size());
  return {{"runs", fractions.size()},
          {"unloaded_fraction_mean", mean},
          {"unloaded_fraction_worst", fractions.empty() ? 0.0 : worst_fraction},
          {"worst", worst},
          {"runs_below_target", below},
          {"emptied", emptied},
          {"boxes_left", boxes_left},
          {"robot_time_s_median", plr::bench::median(robot_s)},
          {"wasted_share_median", plr::bench::median(wasted)},
          {"boxes_per_robot_s", seconds > 0 ? boxes / seconds : 0.0},
          {"robot_trailer_collisions", collisions},
          {"stop_reasons", stops},
          {"left_by_reason", left},
          {"observations", seen},
          {"searches", searches(runs, std::string(to_string(family)))}};
}

void print_table(const nlohmann::json& families) {
  std::printf("strategy H, in process; target: every run >= %.0f %% unloaded, no collision\n\n",
              100 * kTargetFraction);
  std::printf("%-6s %5s %7s %5s %8s %24s %7s %10s %9s %8s %6s\n", "family", "runs", "emptied",
              "left", "mean", "worst", "<98 %", "robot s", "boxes/s", "wasted", "coll.");
  auto number = [](const nlohmann::json& v) { return v.is_number() ? v.get<double>() : 0.0; };
  for (const auto& [name, f] : families.items()) {
    std::printf("%-6s %5d %7d %5d %7.1f%% %24s %7d %10.0f %9.3f %7.1f%% %6d\n", name.c_str(),
                f["runs"].get<int>(), f["emptied"].get<int>(), f["boxes_left"].get<int>(),
                100 * f["unloaded_fraction_mean"].get<double>(),
                f["worst"].get<std::string>().c_str(), f["runs_below_target"].get<int>(),
                number(f["robot_time_s_median"]), f["boxes_per_robot_s"].get<double>(),
                100 * number(f["wasted_share_median"]), f["robot_trailer_collisions"].get<int>());
  }
  std::printf(
      "wasted: median share of robot time in actions that unloaded no box, and in "
      "the others' planning (issue 46 target <= 10 %%)\n");
  // ObservationParams split what H meets: every structure's three height
  // classes should occur on every family that has that structure.
  if (!families.empty()) {
    std::printf("\nobservations H met (actions):\n%-6s", "family");
    for (const auto& [cls, n] : families.begin()->at("observations").items())
      std::printf(" %10s", cls.c_str());
    std::printf("\n");
    for (const auto& [name, f] : families.items()) {
      std::printf("%-6s", name.c_str());
      for (const auto& [cls, n] : f["observations"].items()) std::printf(" %10d", n.get<int>());
      std::printf("\n");
    }
  }
  std::printf(
      "\nsearches: expansions of the solved queries (p50/p95/p99/max), queries that "
      "spent a whole budget\n");
  for (const auto& [name, f] : families.items())
    for (const auto& [mode, m] : f["searches"].items())
      std::printf("  %-3s %s %6d solved %6d %6d %6d %6d   %4d spent\n", name.c_str(), mode.c_str(),
                  m["solved"].get<int>(), m.value("p50", 0), m.value("p95", 0), m.value("p99", 0),
                  m.value("max", 0), m["budget_spent"].get<int>());
  std::printf("\nwhy runs stopped / why boxes were left:\n");
  for (const auto& [name, f] : families.items()) {
    for (const auto& [why, n] : f["stop_reasons"].items())
      std::printf("  %-3s %3d runs: %s\n", name.c_str(), n.get<int>(), why.c_str());
    for (const auto& [why, n] : f["left_by_reason"].items())
      std::printf("  %-3s %3d boxes left: %s\n", name.c_str(), n.get<int>(), why.c_str());
  }
}

Options parse(int argc, char** argv) {
  Options o;
  bool quick = false;
  CLI::App app{
      "Strategy H to the end of the run on many seeds of every family, in worker "
      "processes: unloaded fraction, robot time, why runs stopped and boxes were left"};
  plr::bench::add_quick_flag(app, quick, "seeds 1-5");
  plr::bench::add_json_flag(app, o.json);
  app.add_option("--seeds", o.seeds, "Seeds per family")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--first", o.first, "First seed")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  plr::bench::add_families_option(app, o.families, "Families to run (default all)");
  app.add_option("--workers", o.workers, "Worker processes (default one per core)")
      ->check(CLI::PositiveNumber);
  app.add_option("--out", o.out,
                 "Folder of the runs' results; a run already there is not run again")
      ->capture_default_str();
  app.add_option("--timeout", o.timeout_s, "Wall seconds after which a run is killed")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  std::string fidelity = "full";
  app.add_option("--fidelity", fidelity,
                 "How accurately the boxes are simulated: full, adaptive, fast")
      ->capture_default_str();
  app.add_option("--experience", o.experience,
                 "The planner reuses earlier paths within a trailer: on, off (default: as the "
                 "lattice file says)")
      ->check(CLI::IsMember({"on", "off"}));
  app.add_option("--plan-while-moving", o.plan_while_moving,
                 "The next step is planned while a motion runs: on, off")
      ->check(CLI::IsMember({"on", "off"}))
      ->capture_default_str();
  app.add_flag("--record-queries", o.record_queries,
               "Save every M1 and M2 query of a run (F_seedS.pick_queries.bin)");
  plr::bench::parse_or_exit(app, argc, argv);
  const auto level = plr::sim::parse_fidelity(fidelity);
  if (!level) die(level.error().message);
  o.fidelity = *level;
  if (quick) o.seeds = 5;
  if (o.families.empty()) o.families = plr::sim::all_env_families();
  if (o.workers == 0) o.workers = std::max(1L, sysconf(_SC_NPROCESSORS_ONLN));
  return o;
}

}  // namespace

int main(int argc, char** argv) {
  const Options o = parse(argc, argv);
  std::error_code ec;
  fs::create_directories(o.out, ec);
  if (ec) die(o.out + ": " + ec.message());
  std::vector<Job> all;
  for (const EnvFamily f : o.families)
    for (std::uint64_t s = o.first; s < o.first + o.seeds; ++s)
      all.push_back({f, s, fs::path(o.out) / fmt::format("{}_seed{}", to_string(f), s), o.fidelity,
                     o.experience, o.record_queries, o.plan_while_moving == "on"});
  const std::vector<nlohmann::json> runs = run_all(all, o);
  nlohmann::json families = nlohmann::json::object();
  for (const EnvFamily f : o.families) families[std::string(to_string(f))] = summarize(runs, f);
  // The queries that spent a whole budget, of every run: one query set.
  std::vector<std::vector<std::uint8_t>> failed;
  for (const Job& j : all) {
    auto file = j.file;
    auto set = plr::planning::load_query_set(file.replace_extension(".failed_queries.bin"));
    if (!set) continue;  // a run that failed or was killed left none
    for (const auto& q : *set) failed.push_back(plr::planning::frame_query(q.query, q.world));
  }
  if (auto saved = plr::planning::save_query_set(failed, fs::path(o.out) / "failed_queries.bin");
      !saved)
    die(saved.error().message);
  const nlohmann::json report = {
      {"families", families}, {"runs", runs}, {"searches", searches(runs, "all")}};
  save(fs::path(o.out) / "report.json", report);
  if (o.json)
    std::printf("%s\n", families.dump().c_str());
  else
    print_table(families);
  return 0;
}
