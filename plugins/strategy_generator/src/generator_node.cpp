// The strategy generator node: for each configured world, one strategy by
// POMHDP over mass particles (truck/generate.hpp), simulated by worker
// processes; the library L written after each strategy (atomically), with
// each strategy's tree and anytime curve as SVG beside it. Progress on
// stderr: trials, tree nodes, root bounds, workers busy, ETA.
//
// Checkpoint and resume: every simulation is a job of the job engine whose
// result goes to a result store per world (checkpoint_dir/<world>) before
// the search uses it, and finished strategies are in the library. Started
// again after a kill, the node skips the library's strategies and the
// search repeats itself, reading the stored results instead of simulating
// anything twice, and ends with the same strategy.
#include <plr/atomic_file.hpp>
#include <plr/interface.hpp>
#include <plr/messages.hpp>
#include <plr/node.hpp>
#include <plr/plugin.hpp>
#include <plr/yaml_reader.hpp>

#include <unistd.h>

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <thread>

#include <plr/msg/jobs_generated.h>

#include "plr/actions/fingerprint.hpp"
#include "plr/jobs/engine.hpp"
#include "plr/jobs/in_process_runner.hpp"
#include "plr/jobs/runner_settings.hpp"
#include "plr/jobs/slurm_runner.hpp"
#include "plr/jobs/this_process.hpp"
#include "plr/sim/library.hpp"
#include "plr/sim/world_io.hpp"
#include "truck/generate.hpp"
#include "truck/strategy_job.hpp"
#include "truck/svg.hpp"
#include "truck/worker_runner.hpp"

namespace {

namespace fs = std::filesystem;
using namespace plr;
using generator::GenerateOptions;
using generator::WorldSpec;
using Clock = std::chrono::steady_clock;

std::string duration(double s) {
  if (!std::isfinite(s) || s < 0) return "-";
  const auto t = static_cast<long>(s + 0.5);
  return t >= 60 ? fmt::format("{}m{:02d}s", t / 60, t % 60) : fmt::format("{}s", t);
}

// A job with a remote worker: a call of its kernel's sim/simulate.
class ServiceCall final : public generator::RemoteCall {
 public:
  explicit ServiceCall(Future<msg::JobFrame> call) : call_(std::move(call)) {}
  ~ServiceCall() override { call_.cancel(); }
  bool done() const override { return call_.ready(); }
  Expected<jobs::Bytes> take() override {
    auto reply = call_.get();
    if (!reply) return reply.error();
    const auto v = reply->view();
    return jobs::Bytes(v.data, v.data + v.size);
  }

 private:
  Future<msg::JobFrame> call_;
};

// The worker program beside this process's executable (build/bin).
std::string default_worker() {
  std::error_code ec;
  const fs::path self = fs::read_symlink("/proc/self/exe", ec);
  return ec ? "plr_sim_worker" : (self.parent_path() / "plr_sim_worker").string();
}

// `runner` and `slurm` of the node's params, read as the evaluation's and
// the chooser's settings files read them (JSON is YAML's flow style).
Expected<jobs::RunnerSettings> read_runner(const nlohmann::json& params) {
  nlohmann::json part = nlohmann::json::object();
  for (const char* key : {jobs::kRunnerKey, jobs::kSlurmKey})
    if (params.contains(key)) part[key] = params[key];
  auto doc = yaml::Document::parse(part.dump(), "generator params");
  if (!doc) return doc.error();
  jobs::RunnerSettings out;
  jobs::read_runner_settings(doc->root().map("params", {jobs::kRunnerKey, jobs::kSlurmKey}), out);
  return doc->result(std::move(out));
}

class GeneratorNode : public Node {
 public:
  using Node::Node;

 protected:
  Status on_configure() override {
    params().allow_only({"library",
                         "checkpoint_dir",
                         "worlds",
                         "particles",
                         "horizon",
                         "epsilon1",
                         "epsilon2",
                         "trials",
                         "target_gap",
                         "seed",
                         "seconds_per_box",
                         "action_s",
                         "workers",
                         "worker_program",
                         "remote_workers",
                         "remote_service",
                         "remote_timeout_s",
                         "observation",
                         "progress",
                         "max_wall_s",
                         "complete_tree",
                         "runner",
                         "slurm",
                         "continuations",
                         "continuation_share",
                         "fidelity"});
    library_ = params().require<std::string>("library");
    checkpoint_dir_ = params().get<std::string>("checkpoint_dir", library_ + ".checkpoint");
    particles_ = params().get<int>("particles", 5);
    seed_ = params().get<std::uint64_t>("seed", 1);
    workers_ = params().get<int>("workers", 2);
    worker_program_ = params().get<std::string>("worker_program", default_worker());
    remote_workers_ = params().get<int>("remote_workers", 0);
    remote_service_ = params().get<std::string>("remote_service", "sim/simulate");
    remote_timeout_s_ = params().get<double>("remote_timeout_s", 600);
    show_progress_ = params().get<bool>("progress", true);
    GenerateOptions& o = options_;
    o.truck.horizon = params().get<int>("horizon", o.truck.horizon);
    o.truck.seconds_per_box = params().get<double>("seconds_per_box", o.truck.seconds_per_box);
    o.truck.action_s = params().get<double>("action_s", o.truck.action_s);
    o.epsilon1 = params().get<double>("epsilon1", o.epsilon1);
    o.epsilon2 = params().get<double>("epsilon2", o.epsilon2);
    o.trials = params().get<std::uint64_t>("trials", o.trials);
    o.target_gap = params().get<double>("target_gap", o.target_gap);
    o.max_wall_s = params().get<double>("max_wall_s", o.max_wall_s);
    o.complete_tree = params().get<bool>("complete_tree", o.complete_tree);
    o.seed = seed_;
    const auto fidelity = params().get<std::string>("fidelity", "full");
    if (const auto level = sim::parse_fidelity(fidelity))
      o.fidelity = *level;
    else
      return make_error(PLR_ERR_INVALID, fmt::format("param 'fidelity': '{}' is not one of full, "
                                                     "adaptive, fast",
                                                     fidelity));
    continuations_ = params().get<int>("continuations", 0);
    continuation_share_ = params().get<double>("continuation_share", 1.0);
    if (continuations_ < 0 || continuations_ > 1000)
      return make_error(PLR_ERR_INVALID,
                        fmt::format("param 'continuations': {} is not in 0..1000", continuations_));
    if (!(continuation_share_ > 0) || continuation_share_ > 1)
      return make_error(PLR_ERR_INVALID, "param 'continuation_share': must be in (0, 1]");
    if (particles_ < 1 || particles_ > 100)
      return make_error(PLR_ERR_INVALID,
                        fmt::format("param 'particles': {} is not in 1..100", particles_));
    if (o.truck.horizon < 1 || o.truck.horizon > 50)
      return make_error(PLR_ERR_INVALID,
                        fmt::format("param 'horizon': {} is not in 1..50", o.truck.horizon));
    if (workers_ < 0 || workers_ > 256)
      return make_error(PLR_ERR_INVALID,
                        fmt::format("param 'workers': {} is not in 0..256", workers_));
    if (remote_workers_ < 0 || remote_workers_ > 256)
      return make_error(PLR_ERR_INVALID, fmt::format("param 'remote_workers': {} is not in 0..256",
                                                     remote_workers_));
    if (!(remote_timeout_s_ > 0) || remote_timeout_s_ > 86400)
      return make_error(PLR_ERR_INVALID, "param 'remote_timeout_s': must be in (0, 86400]");
    if (!(o.epsilon1 >= 1) || !(o.epsilon2 >= 1))
      return make_error(PLR_ERR_INVALID, "params 'epsilon1', 'epsilon2': must be >= 1");
    if (!(o.truck.seconds_per_box > 0) || !(o.truck.action_s > 0))
      return make_error(PLR_ERR_INVALID, "params 'seconds_per_box', 'action_s': must be > 0");
    if (o.trials < 1 || o.trials > 10'000'000)
      return make_error(PLR_ERR_INVALID, "param 'trials': must be in 1..10000000");
    if (auto runner = read_runner(params().json()); !runner)
      return runner.error();
    else
      runner_ = std::move(*runner);
    if (continuations_ > 0 && runner_.kind == jobs::RunnerSettings::Kind::kSlurm)
      return make_error(PLR_ERR_INVALID,
                        "param 'continuations': not made with runner: slurm (each link needs its "
                        "parent's leaves); use local or remote workers");
    const nlohmann::json observation = params().json().value("observation", nlohmann::json());
    if (auto obs = sim::ObservationParams::from_json(observation); !obs)
      return make_error(PLR_ERR_INVALID, "param 'observation': " + obs.error().message);
    observation_json_ = observation.is_null() ? "{}" : observation.dump();
    worlds_.clear();
    const nlohmann::json worlds = params().json().value("worlds", nlohmann::json::array());
    if (!worlds.is_array() || worlds.empty() || worlds.size() > 1000)
      return make_error(PLR_ERR_INVALID, "param 'worlds': a list of 1..1000 {family, seed}");
    for (std::size_t i = 0; i < worlds.size(); ++i) {
      const auto& w = worlds[i];
      const auto where = fmt::format("param 'worlds[{}]'", i);
      const bool has_file = w.is_object() && w.contains("world_file");
      if (!w.is_object() || !w.contains("family") || !w["family"].is_string() ||
          (has_file ? !w["world_file"].is_string()
                    : !w.contains("seed") || !w["seed"].is_number_unsigned()))
        return make_error(PLR_ERR_INVALID,
                          where + ": needs family (A1, B1, ...) and seed (>= 0) or world_file");
      const auto f = sim::parse_env_family(w["family"].get<std::string>());
      if (!f)
        return make_error(PLR_ERR_INVALID,
                          where + ": unknown family '" + w["family"].get<std::string>() + "'");
      WorldSpec spec{*f, w.value("seed", std::uint64_t{0}), ""};
      if (has_file) {
        spec.file = w["world_file"].get<std::string>();
        if (auto world = sim::load_world(spec.file); !world)
          return make_error(PLR_ERR_INVALID, where + ": " + world.error().message);
      }
      worlds_.push_back(std::move(spec));
    }
    auto done = ctx().advertise<msg::PipelineDone>("pipeline/done");
    if (!done) return done.error();
    done_ = *done;
    tty_ = isatty(STDERR_FILENO) == 1;
    return {};
  }

  Status on_activate() override {
    stop_ = false;
    thread_ = std::thread([this] { run(); });
    return {};
  }

  Status on_deactivate() override {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
    return {};
  }

 private:
  void run() {
    std::string why;
    const bool ok = generate_all(why);
    if (show_progress_ && tty_) std::fputs("\n", stderr);
    if (ok)
      log().info("{}", why);
    else if (!stop_)
      log().error("{}", why);
    flatbuffers::FlatBufferBuilder fbb;
    fbb.Finish(msg::CreatePipelineDoneDirect(fbb, ok, why.c_str()));
    (void)done_.publish(fbb);
  }

  bool generate_all(std::string& why) {
    std::error_code ec;
    fs::create_directories(checkpoint_dir_, ec);
    const fs::path lib(library_);
    if (!lib.parent_path().empty()) fs::create_directories(lib.parent_path(), ec);
    sim::Library library;
    if (fs::exists(lib)) {
      auto loaded = sim::load_library(lib);
      if (!loaded) {
        why = loaded.error().message;
        return false;
      }
      library = std::move(*loaded);
    }
    if (runner_.kind == jobs::RunnerSettings::Kind::kSlurm)
      return generate_on_slurm(library, lib, why);
    // The particles' starting states are made here; the simulations run as
    // jobs: in this process with no workers, else on the workers.
    const generator::WorkerRunner* worker_runner = nullptr;
    auto rig = actions::make_rig(observation_json_);
    if (!rig) {
      why = rig.error().message;
      return false;
    }
    jobs::Kinds kinds;
    std::unique_ptr<jobs::Runner> runner;
    int workers = 1;
    if (workers_ == 0 && remote_workers_ == 0) {
      actions::add_sim_action(kinds);
      runner = std::make_unique<jobs::InProcessRunner>(kinds);
    } else {
      generator::WorkerOptions worker_options;
      worker_options.local.command = {worker_program_};
      worker_options.local.workers = static_cast<unsigned>(workers_);
      worker_options.remote_workers = static_cast<unsigned>(remote_workers_);
      const auto timeout = std::chrono::duration_cast<std::chrono::nanoseconds>(
          std::chrono::duration<double>(remote_timeout_s_));
      worker_options.remote_send = [this, timeout](const jobs::Bytes& request) {
        flatbuffers::FlatBufferBuilder fbb(request.size() + 64);
        fbb.PushFlatBuffer(request.data(), request.size());
        return std::make_unique<ServiceCall>(
            ctx().call<msg::JobFrame, msg::JobFrame>(remote_service_, fbb, timeout));
      };
      auto made = generator::WorkerRunner::create(std::move(worker_options));
      if (!made) {
        why = made.error().message;
        return false;
      }
      workers = (*made)->workers();
      worker_runner = made->get();
      runner = std::move(*made);
    }
    generator::Simulator simulator(*runner, workers, observation_json_);
    std::size_t made = 0;
    for (std::size_t i = 0; i < worlds_.size(); ++i) {
      auto problem = generator::make_problem(job_for(worlds_[i]));
      if (!problem) {
        why = problem.error().message;
        return false;
      }
      if (!make_chain(*problem, 0, i, library, lib, **rig, simulator, made, why)) return false;
    }
    if (worker_runner && remote_workers_ > 0)
      log().info("remote workers: {} jobs answered, {} calls failed (re-issued)",
                 worker_runner->remote_done(), worker_runner->remote_failures());
    why = fmt::format("library {}: {} strategies ({} made now)", library_, library.entries.size(),
                      made);
    return true;
  }

  // `problem`'s strategy (made, or found in the library), then, while the
  // chain is shorter than `continuations`, one for each leaf of it that
  // continued_leaves() picks, depth first. Resumable: a strategy in the
  // library is not made again, and its leaves are replayed from its store.
  bool make_chain(const generator::Problem& problem, int link, std::size_t world,
                  sim::Library& library, const fs::path& lib, actions::Rig& rig,
                  generator::Simulator& simulator, std::size_t& made, std::string& why) {
    if (stop_) {
      why = "stopped";
      return false;
    }
    const auto have =
        std::find_if(library.entries.begin(), library.entries.end(),
                     [&](const sim::LibraryEntry& e) { return e.name == problem.name; });
    const bool in_library = have != library.entries.end();
    if (in_library) log().info("{}: in the library already", problem.name);
    if (in_library && link >= continuations_) return true;
    auto store = jobs::Store::open(fs::path(checkpoint_dir_) / problem.name);
    if (!store) {
      why = store.error().message;
      return false;
    }
    std::vector<generator::Leaf> leaves;
    if (in_library) {
      auto replayed = generator::replay_leaves(problem, *have, options_, rig, simulator, &*store);
      if (!replayed) {
        why = replayed.error().message;
        return false;
      }
      leaves = std::move(*replayed);
    } else {
      auto result = generate_one(problem, world, rig, simulator, *store);
      if (!result) {
        why = result.error().message;
        return false;
      }
      leaves = std::move(result->leaves);
      if (!add(library, lib, std::move(result->entry), why)) return false;
      const sim::LibraryEntry& e = library.entries.back();
      if (show_progress_ && tty_) std::fputs("\n", stderr);
      log().info(
          "{}: {} nodes, root bounds [{:.1f}, {:.1f}], {} trials, {} simulations ({} run now), "
          "{:.0f} s; {}",
          e.name, e.strategy.nodes.size(), e.lower, e.upper, e.provenance.trials,
          e.provenance.simulations, result->simulated, e.provenance.wall_s, describe(leaves));
      if (e.check)
        log().info(
            "{}: made at {} fidelity: value {:.1f} ({:.1f} boxes) on its {} particles; at "
            "full fidelity {:.1f} ({:.1f} boxes) on {} fresh particles, {:.0f} s",
            e.name, e.fidelity, e.check->value, e.check->boxes, e.provenance.particles,
            e.check->full_value, e.check->full_boxes, e.check->full_particles,
            result->check_wall_s);
      ++made;
    }
    if (link >= continuations_) return true;
    for (const std::size_t k : generator::continued_leaves(leaves, continuation_share_)) {
      auto next = generator::continuation(problem, leaves, k, rig);
      if (!next) {
        why = next.error().message;
        return false;
      }
      if (!make_chain(*next, link + 1, world, library, lib, rig, simulator, made, why))
        return false;
    }
    return true;
  }

  // Where a strategy ends on its particles, for the log:
  // "leaves: wall/low/left>pile/mid/center 3 (41 boxes left), empty 1".
  static std::string describe(const std::vector<generator::Leaf>& leaves) {
    std::string out = "leaves:";
    for (const generator::Leaf& l : leaves) {
      std::string path;
      for (const sim::Observation o : l.path) path += (path.empty() ? "" : ">") + sim::to_string(o);
      std::uint32_t left = 0;
      for (const auto& s : l.states) left += s.boxes_left;
      if (l.empty) path += path.empty() ? "empty" : ">empty";
      out += fmt::format(" {} {} ({} boxes left)", path, l.particles.size(), left);
    }
    return out;
  }

  // One strategy, with the progress line drawn every second.
  Expected<generator::GenerateResult> generate_one(const generator::Problem& problem,
                                                   std::size_t world, actions::Rig& rig,
                                                   generator::Simulator& simulator,
                                                   const jobs::Store& store) {
    const auto t0 = Clock::now();
    // The line is drawn again every second, also while a batch of
    // simulations runs (workers busy, ETA), from the last trial's figures.
    std::mutex m;
    std::condition_variable cv;
    bool finished = false;
    generator::GenerateProgress last;
    std::thread ticker([&] {
      std::unique_lock lock(m);
      while (!cv.wait_for(lock, std::chrono::seconds(1), [&] { return finished; })) {
        show(problem.name, world, last, simulator, t0);
      }
    });
    auto result = generator::generate(problem, options_, rig, simulator, &store,
                                      [&](const generator::GenerateProgress& p) {
                                        std::lock_guard lock(m);
                                        last = p;
                                        return !stop_.load();
                                      });
    {
      std::lock_guard lock(m);
      finished = true;
    }
    cv.notify_all();
    ticker.join();
    return result;
  }

  generator::StrategyJob job_for(const WorldSpec& world) const {
    return {world, particles_, seed_, options_, observation_json_, checkpoint_dir_};
  }

  static bool has(const sim::Library& library, const std::string& name) {
    return std::any_of(library.entries.begin(), library.entries.end(),
                       [&](const sim::LibraryEntry& e) { return e.name == name; });
  }

  // The library written with `entry` added, and the strategy's tree and
  // anytime curve beside it. The library records how it was made: this
  // command, the node's settings and the action model.
  bool add(sim::Library& library, const fs::path& lib, sim::LibraryEntry entry,
           std::string& why) const {
    library.entries.push_back(std::move(entry));
    auto action_model = actions::action_model_fingerprint();
    if (!action_model) {
      why = action_model.error().message;
      return false;
    }
    library.action_model = *action_model;
    library.made_by = fmt::format("{}\nsettings: {}", jobs::command_line(), params().json().dump());
    if (auto s = sim::save_library(library, lib); !s) {
      why = s.error().message;
      return false;
    }
    const sim::LibraryEntry& e = library.entries.back();
    const fs::path dir = lib.parent_path();
    (void)write_file_atomically((dir / (e.name + ".svg")).string(),
                                generator::strategy_svg(e.strategy));
    (void)write_file_atomically((dir / (e.name + "-anytime.svg")).string(),
                                generator::anytime_svg(e));
    return true;
  }

  // Each missing strategy as an array task of a Slurm job (kind
  // generator.strategy, run by the worker program); their results in the
  // store checkpoint_dir/strategies, the library written in the worlds'
  // order once all have come. Run again, stored strategies are not made
  // again, and a task run again resumes its world's simulations.
  bool generate_on_slurm(sim::Library& library, const fs::path& lib, std::string& why) {
    std::vector<jobs::Job> todo;
    for (const WorldSpec& world : worlds_) {
      const generator::StrategyJob job = job_for(world);
      auto problem = generator::make_problem(job);
      if (!problem) {
        why = problem.error().message;
        return false;
      }
      if (has(library, problem->name))
        log().info("{}: in the library already", problem->name);
      else
        todo.push_back({generator::kStrategyKind, problem->name, generator::encode(job)});
    }
    auto store = jobs::Store::open(fs::path(checkpoint_dir_) / "strategies");
    if (!store) {
      why = store.error().message;
      return false;
    }
    jobs::SlurmRunner runner(*store, {fs::absolute(worker_program_).string(), "--slurm-task"},
                             runner_.slurm);
    jobs::RunOptions options;
    options.stop = [this] { return stop_.load(); };
    std::size_t done = 0;
    options.on_start = [&](std::size_t stored, std::size_t to_run) {
      done = stored;
      log().info("{} strategies as Slurm array tasks: {} stored, {} to run", todo.size(), stored,
                 to_run);
    };
    options.on_done = [&](const jobs::Result& r) {
      log().info("{} ({} of {}): {}", r.key, ++done, todo.size(),
                 r.ok ? "made" : "failed: " + r.error);
    };
    auto outcome = jobs::run(todo, runner, &*store, options);
    if (!outcome) {
      why = outcome.error().message;
      return false;
    }
    log().info("slurm: {}", jobs::to_json(runner.stats()).dump());
    if (outcome->stopped) {
      why = "stopped";
      return false;
    }
    for (const jobs::Result& r : outcome->results) {
      if (!r.ok) {
        why = fmt::format("{}: {} (log: {})", r.key, r.error, store->log_file(r.key).string());
        return false;
      }
      auto one = sim::deserialize_library(r.output.data(), r.output.size(),
                                          store->result_file(r.key).string());
      if (!one || one->entries.size() != 1) {
        why = one ? store->result_file(r.key).string() + ": not one strategy" : one.error().message;
        return false;
      }
      if (!add(library, lib, std::move(one->entries.front()), why)) return false;
    }
    why = fmt::format("library {}: {} strategies ({} made on Slurm now)", library_,
                      library.entries.size(), outcome->ran);
    return true;
  }

  void show(const std::string& name, std::size_t index, const generator::GenerateProgress& p,
            const generator::Simulator& simulator, Clock::time_point t0) {
    if (!show_progress_) return;
    const double elapsed = std::chrono::duration<double>(Clock::now() - t0).count();
    const double frac = p.trial_budget ? double(p.trials) / double(p.trial_budget) : 0.0;
    // From the trials' pace; unrolling the policy has no measure of its own
    // length, so the ETA is unknown then.
    double eta = frac > 0 && !p.unrolling ? elapsed / frac - elapsed : NAN;
    const double per_world = frac > 0 ? elapsed / frac : NAN;
    eta += per_world * double(worlds_.size() - index - 1);
    constexpr int kBar = 20;
    const int filled = std::clamp(static_cast<int>(frac * kBar), 0, kBar);
    const std::string line = fmt::format(
        "{} ({}/{}) [{}{}] trials {}/{}  nodes {}  root [{:.1f}, {:.1f}]  workers {}/{} busy  "
        "sims {}  {}{} elapsed, ETA {}",
        name, index + 1, worlds_.size(), std::string(filled, '#'), std::string(kBar - filled, '-'),
        p.trials, p.trial_budget, p.nodes, p.lower, p.upper, simulator.busy(), simulator.workers(),
        p.results, p.unrolling ? "unrolling the policy  " : "", duration(elapsed), duration(eta));
    const auto now = Clock::now();
    if (tty_) {
      std::fprintf(stderr, "\r\033[K%s", line.c_str());
      std::fflush(stderr);
    } else if (now - last_line_ > std::chrono::seconds(10)) {
      std::fprintf(stderr, "%s\n", line.c_str());
      last_line_ = now;
    }
  }

  std::string library_, checkpoint_dir_, worker_program_, observation_json_, remote_service_;
  int particles_ = 5, workers_ = 2, remote_workers_ = 0, continuations_ = 0;
  double continuation_share_ = 1.0;
  double remote_timeout_s_ = 600;
  std::uint64_t seed_ = 1;
  bool show_progress_ = true, tty_ = false;
  GenerateOptions options_;
  jobs::RunnerSettings runner_;
  std::vector<WorldSpec> worlds_;
  Publisher<msg::PipelineDone> done_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  Clock::time_point last_line_{};
};

}  // namespace

PLR_PLUGIN(
    GeneratorNode, "strategy_generator", "1.0.0", PLR_KIND_GENERATOR,
    "Generates the strategy library L: POMHDP over simulated mass particles, in worker processes")
// Its local workers are processes fed over pipes (truck/worker_runner.hpp), not
// bus peers; its remote ones are called as sim/simulate (remote_service).
PLR_INTERFACE(plr::topic<plr::msg::PipelineDone>("pipeline/done"))
