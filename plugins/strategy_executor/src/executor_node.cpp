// The strategy executor: runs the episode engine (plr/episode/engine.hpp)
// over the bus: the planner's `plan`, the simulator's (or robot driver's)
// `sim/observe` and `sim/execute`, strategies from the config and
// `strategy/next`. A simulator that dies is waited for and restored from the
// last checkpoint; the interrupted action is repeated. It watches the run
// for the progress line, the state topic, the log and the report. See
// docs/executor.md.
#include <unistd.h>

#include <plr/actions/action_model.hpp>
#include <plr/atomic_file.hpp>
#include <plr/episode/engine.hpp>
#include <plr/interface.hpp>
#include <plr/messages.hpp>
#include <plr/node.hpp>
#include <plr/plugin.hpp>
#include <plr/sim/library.hpp>
#include <plr/sim/observation.hpp>
#include <plr/sim/render.hpp>
#include <plr/sim/robot_model.hpp>
#include <plr/sim/strategy.hpp>
#include <plr/sim/world_io.hpp>

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdio>
#include <filesystem>
#include <mutex>
#include <optional>
#include <thread>

#include "bus_backend.hpp"
#include "report.hpp"

namespace plr::executor {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

// Unwinds the worker when the node is deactivated.
struct Stopped {};
// The simulator's host went away, or restarted.
struct SimulatorLost {
  std::string what;
};

// A trailer to unload: generated (`env`, `seed`) or read (`world_file`).
struct Trailer {
  std::string env;
  std::uint64_t seed = 1;
  std::string world_file;
  std::string name() const {
    return world_file.empty() ? fmt::format("{} seed {}", env, seed) : world_file;
  }
};

template <std::size_t N>
bool read_array(const Params& p, const char* key, std::array<double, N>& to, Status& error) {
  const auto v = p.get<std::vector<double>>(key, std::vector<double>(to.begin(), to.end()));
  if (v.size() != N) {
    error =
        make_error(PLR_ERR_INVALID, fmt::format("param '{}': expected {} joint values", key, N));
    return false;
  }
  std::copy(v.begin(), v.end(), to.begin());
  return true;
}

class ExecutorNode : public plr::Node, private episode::Observer {
 public:
  using Node::Node;

 protected:
  plr::Status on_configure() override {
    params().allow_only({"report_dir",
                         "env",
                         "seed",
                         "world_file",
                         "urdf",
                         "observation",
                         "plan_timeout_s",
                         "plan_expansions",
                         "plan_while_moving",
                         "plan_epsilons",
                         "execute_timeout_s",
                         "service_wait_s",
                         "retry_ms",
                         "max_idle_actions",
                         "max_actions",
                         "pick_candidates",
                         "grip_attempts",
                         "settle_s",
                         "nose_home",
                         "nose_down",
                         "nose_sweep",
                         "arm_clear",
                         "retreat_m",
                         "dropoff_backoff_m",
                         "carry_height_m",
                         "progress",
                         "strategy_file",
                         "strategy_library",
                         "strategy_entry",
                         "trailers",
                         "cycles"});
    report_dir_ = params().get<std::string>("report_dir", "report");
    env_ = params().get<std::string>("env", "");
    seed_ = params().get<std::uint64_t>("seed", 1);
    world_file_ = params().get<std::string>("world_file", "");
    if (auto ok = read_trailers(); !ok) return ok;
    // Open loop: the first strategy is a given one (a strategy file, or an
    // entry of a library L) instead of strategy/next's; once it ends, the
    // executor asks strategy/next as usual.
    first_strategy_.reset();
    const auto strategy_file = params().get<std::string>("strategy_file", "");
    const auto library = params().get<std::string>("strategy_library", "");
    if (!strategy_file.empty() && !library.empty())
      return make_error(PLR_ERR_INVALID,
                        "params 'strategy_file' and 'strategy_library': give one of them");
    if (!strategy_file.empty()) {
      auto s = sim::load_strategy(strategy_file);
      if (!s) return make_error(PLR_ERR_INVALID, "param 'strategy_file': " + s.error().message);
      first_strategy_ = std::move(*s);
    } else if (!library.empty()) {
      const auto entry = params().require<std::string>("strategy_entry");
      auto lib = sim::load_library(library);
      if (!lib)
        return make_error(PLR_ERR_INVALID, "param 'strategy_library': " + lib.error().message);
      for (auto& e : lib->entries) {
        if (e.name == entry) first_strategy_ = std::move(e.strategy);
      }
      if (!first_strategy_)
        return make_error(PLR_ERR_INVALID,
                          fmt::format("param 'strategy_entry': {}: no entry '{}'", library, entry));
    }
    actions::ActionOptions& o = options_;
    auto observation =
        sim::ObservationParams::from_json(params().json().value("observation", nlohmann::json()));
    if (!observation) return observation.error();
    o.observation = observation.value();
    o.plan_timeout_s = params().get<double>("plan_timeout_s", o.plan_timeout_s);
    o.plan_expansions = params().get<std::uint64_t>("plan_expansions", o.plan_expansions);
    o.plan_while_moving = params().get<bool>("plan_while_moving", o.plan_while_moving);
    o.plan_epsilons = params().get<std::vector<double>>("plan_epsilons", o.plan_epsilons);
    o.pick_candidates = params().get<std::uint64_t>("pick_candidates", o.pick_candidates);
    o.grip_attempts = static_cast<int>(
        params().get<std::uint64_t>("grip_attempts", static_cast<std::uint64_t>(o.grip_attempts)));
    o.settle_s = params().get<double>("settle_s", o.settle_s);
    o.retreat_m = params().get<double>("retreat_m", o.retreat_m);
    o.dropoff_backoff_m = params().get<double>("dropoff_backoff_m", o.dropoff_backoff_m);
    o.carry_height_m = params().get<double>("carry_height_m", o.carry_height_m);
    Status bad;
    if (!read_array(params(), "nose_home", o.nose_home, bad) ||
        !read_array(params(), "nose_down", o.nose_down, bad) ||
        !read_array(params(), "nose_sweep", o.nose_sweep, bad) ||
        !read_array(params(), "arm_clear", o.arm_clear, bad))
      return bad;
    if (auto ok = o.check(); !ok) return ok;
    bus_.plan_timeout_s = o.plan_timeout_s;
    bus_.execute_timeout_s = params().get<double>("execute_timeout_s", bus_.execute_timeout_s);
    bus_.service_wait_s = params().get<double>("service_wait_s", bus_.service_wait_s);
    bus_.retry = std::chrono::milliseconds(params().get<std::uint64_t>("retry_ms", 50));
    max_idle_ = params().get<std::uint64_t>("max_idle_actions", max_idle_);
    max_actions_ = params().get<std::uint64_t>("max_actions", 0);
    show_progress_ = params().get<bool>("progress", true);
    if (!(bus_.execute_timeout_s > 0) || !(bus_.service_wait_s >= 0))
      return make_error(PLR_ERR_INVALID,
                        "params 'execute_timeout_s' must be > 0, 'service_wait_s' >= 0");
    if (max_idle_ == 0)
      return make_error(PLR_ERR_INVALID, "param 'max_idle_actions': must be >= 1");
    auto robot = sim::load_robot(params().get<std::string>("urdf", ""));
    if (!robot) return make_error(PLR_ERR_INVALID, "param 'urdf': " + robot.error().message);
    robot_ = std::make_unique<sim::RobotModel>(std::move(*robot));
    model_ = std::make_unique<actions::ActionModel>(*robot_, options_);
    auto status = ctx().advertise<msg::Statistics>("executor/status");
    if (!status) return status.error();
    status_ = *status;
    auto state = ctx().advertise<msg::ExecutorState>("executor/state");
    if (!state) return state.error();
    state_pub_ = *state;
    auto done = ctx().advertise<msg::PipelineDone>("pipeline/done");
    if (!done) return done.error();
    done_ = *done;
    auto report = ctx().advertise<msg::NodeReport>("pipeline/report");
    if (!report) return report.error();
    report_pub_ = *report;
    tty_ = isatty(STDERR_FILENO) == 1;
    return {};
  }

  plr::Status on_cleanup() override {
    engine_.reset();
    model_.reset();
    robot_.reset();
    return {};
  }

  plr::Status on_activate() override {
    stop_ = false;
    stats_ = {};
    first_used_ = false;
    engine_.reset();
    backend_ = std::make_unique<BusBackend>(ctx(), bus_, [this](std::chrono::nanoseconds d) {
      std::unique_lock lock(m_);
      return !cv_.wait_for(lock, d, [this] { return stop_.load(); });
    });
    worker_ = std::thread([this] { run(); });
    return {};
  }

  plr::Status on_deactivate() override {
    {
      std::lock_guard lock(m_);
      stop_ = true;
    }
    cv_.notify_all();
    if (worker_.joinable()) worker_.join();
    return {};
  }

 private:
  // A backend error: stopping, a lost simulator, or the end of the job.
  [[noreturn]] void fail(const Error& e) const {
    if (e.code == PLR_ERR_CANCELLED) throw Stopped{};
    if (e.code == PLR_ERR_UNAVAILABLE || e.code == PLR_ERR_TIMEOUT) throw SimulatorLost{e.message};
    throw std::runtime_error(e.message);
  }

  // `trailers`: a list of {env, seed} or {world_file}, unloaded one after
  // the other `cycles` times (0: until the run is stopped).
  plr::Status read_trailers() {
    trailers_.clear();
    cycles_ = params().get<std::uint64_t>("cycles", 1);
    const auto list = params().json().value("trailers", nlohmann::json::array());
    if (!list.is_array()) return make_error(PLR_ERR_INVALID, "param 'trailers': expected a list");
    if (!list.empty() && (!env_.empty() || !world_file_.empty()))
      return make_error(PLR_ERR_INVALID,
                        "params 'trailers' and 'env'/'world_file': give one of them");
    for (std::size_t i = 0; i < list.size(); ++i) {
      const auto& e = list[i];
      const auto where = fmt::format("param 'trailers[{}]'", i);
      if (!e.is_object()) return make_error(PLR_ERR_INVALID, where + ": expected a map");
      Trailer t;
      for (const auto& [key, value] : e.items()) {
        if (key == "env" && value.is_string()) {
          t.env = value.get<std::string>();
        } else if (key == "seed" && value.is_number_unsigned()) {
          t.seed = value.get<std::uint64_t>();
        } else if (key == "world_file" && value.is_string()) {
          t.world_file = value.get<std::string>();
        } else {
          return make_error(PLR_ERR_INVALID, fmt::format("{}: bad key '{}'", where, key));
        }
      }
      if (t.env.empty() == t.world_file.empty())
        return make_error(PLR_ERR_INVALID, where + ": give 'env' (and 'seed') or 'world_file'");
      trailers_.push_back(std::move(t));
    }
    return {};
  }

  actions::Perceived observe() {
    auto w = backend_->observe();
    if (!w) fail(w.error());
    return std::move(*w);
  }

  // The run's strategies: the config's first (open loop), then strategy/next's.
  episode::StrategySource strategy_source() {
    return [this](const actions::Perceived&, const sim::SceneAnalysis& scene,
                  const episode::RunRules& rules) -> plr::Expected<episode::StrategyChoice> {
      if (first_strategy_ && !first_used_) {
        first_used_ = true;
        log().info("strategy '{}' from the config ({} nodes), open loop", first_strategy_->name,
                   first_strategy_->nodes.size());
        return episode::StrategyChoice{*first_strategy_, "config", {}};
      }
      return ask_strategy(*scene.observation, rules);
    };
  }

  // strategy/next's answer, with where it says the strategy came from
  // ("library:A1-1", "hardcoded"; the service's name if it does not say).
  plr::Expected<episode::StrategyChoice> ask_strategy(sim::Observation observation,
                                                      const episode::RunRules& rules) {
    const auto& world = backend_->last_world();
    const auto view = world->view();
    flatbuffers::FlatBufferBuilder fbb;
    const auto nested = plr::create_nested(fbb, view.data, view.size);
    const std::vector<std::uint8_t> excluded(rules.exclusions().begin(), rules.exclusions().end());
    fbb.Finish(msg::CreateNextStrategyRequest(
        fbb, nested, observation,
        fbb.CreateVector(reinterpret_cast<const msg::Action*>(excluded.data()), excluded.size())));
    auto r = backend_->call_retry<msg::NextStrategyRequest, msg::NextStrategyReply>("strategy/next",
                                                                                    fbb, 30.0);
    if (!r) {
      if (r.error().code == PLR_ERR_CANCELLED) return r.error();
      return make_error(PLR_ERR_INTERNAL, "strategy/next: " + r.error().message);
    }
    if (r.value()->strategy() == nullptr)
      return make_error(PLR_ERR_INTERNAL, "strategy/next: reply without a strategy");
    auto s = sim::from_message(*r.value()->strategy(), "strategy/next reply");
    if (!s) return make_error(PLR_ERR_INTERNAL, s.error().message);
    const auto* reason = r.value()->reason();
    const auto* from = r.value()->source();
    const std::string source = from && from->size() > 0 ? from->str() : "strategy/next";
    log().info("strategy '{}' from {}{} ({} nodes) for {}", s->name, source,
               reason && reason->size() > 0 ? " (" + reason->str() + ")" : std::string(),
               s->nodes.size(), sim::to_string(observation));
    return episode::StrategyChoice{std::move(*s), source, {}};
  }

  void run() {
    t0_ = Clock::now();
    try {
      job();
      finish(true);
    } catch (const Stopped&) {
      // Stopped before the job was done (Ctrl-C, SIGTERM, --duration, a lost
      // host): the figures so far are the report; the kernel adds why.
      stats_.stop_reason = "stopped";
      stats_.wall_time_s = seconds_since(t0_);
      save_report();
    } catch (const std::exception& e) {
      stats_.stop_reason = e.what();
      log().error("executor: {}", e.what());
      finish(false);
    } catch (const SimulatorLost& lost) {
      stats_.stop_reason = "simulator lost: " + lost.what;
      log().error("executor: {}", stats_.stop_reason);
      finish(false);
    }
  }

  void job() {
    if (trailers_.empty()) {
      // A simulator may hold no world before its first reset: reset first when
      // asked to (waiting for it to come up), observe only otherwise.
      if (!env_.empty() || !world_file_.empty()) reset({env_, seed_, world_file_});
      if (auto ran = unload(); !ran) fail(ran.error());
      return;
    }
    std::uint32_t unloaded = 0, total = 0;
    for (std::uint64_t cycle = 0; cycles_ == 0 || cycle < cycles_; ++cycle) {
      for (const Trailer& t : trailers_) {
        const auto t0 = Clock::now();
        unload_from_its_start(t);
        finish_trailer(t, seconds_since(t0));
        unloaded += stats_.trailers.back().boxes_unloaded;
        total += stats_.trailers.back().boxes_total;
      }
    }
    stats_.stop_reason = fmt::format("{} trailers done: {}/{} boxes unloaded",
                                     stats_.trailers.size(), unloaded, total);
  }

  // `sim/reset` to trailer `t`; returns the world it made.
  sim::World reset(const Trailer& t) {
    flatbuffers::FlatBufferBuilder fbb;
    fbb.Finish(msg::CreateResetRequestDirect(fbb, t.env.c_str(), t.seed, t.world_file.c_str()));
    auto r = backend_->call_retry<msg::ResetRequest, msg::WorldState>("sim/reset", fbb, 120.0);
    if (!r) {
      if (r.error().code == PLR_ERR_CANCELLED) throw Stopped{};
      throw std::runtime_error("sim/reset: " + r.error().message);
    }
    backend_->forget_clock();  // a reset starts the simulator's clock again
    return sim::world_from_message(*r.value());
  }

  // The next trailer, checkpointed at once: a simulator that restarts
  // resumes its last checkpoint, which until then is the trailer before
  // (unloaded). What it shows after the checkpoint is compared with what the
  // reset made; when they differ, it restarted in between and the reset is
  // made again (a first trailer's simulator restarts with no world at all).
  void reset_and_checkpoint(const Trailer& t) {
    constexpr int kAttempts = 10;  // restarts are bounded by the run's max_restarts anyway
    start_checkpoint_bytes_ = 0;
    for (int attempt = 1;; ++attempt) {
      const sim::World made = reset(t);
      backend_->expect_trailer(made);
      checkpoint_trailer(t);
      auto w = backend_->wait_for_simulator();
      if (w && w->unloaded == 0 && box_ids(w->world) == box_ids(made)) return;
      if (!w && w.error().code == PLR_ERR_CANCELLED) throw Stopped{};
      const std::string shows =
          w ? fmt::format("{} boxes, {} unloaded", w->world.boxes.size(), w->unloaded)
            : w.error().message;
      if (attempt == kAttempts)
        throw std::runtime_error(
            fmt::format("trailer {}: the simulator does not keep its reset "
                        "after {} attempts ({})",
                        t.name(), kAttempts, shows));
      log().warn("trailer {}: the simulator restarted after its reset ({}): resetting again",
                 t.name(), shows);
    }
  }

  // A trailer starts only from its own checkpoint: a simulator restarted
  // later would resume the trailer before, which the executor would take
  // for this one (bench_soak: a read-only disk refused it, then a kill).
  void checkpoint_trailer(const Trailer& t) {
    auto ok = backend_->checkpoint_until_written("trailer " + t.name());
    if (ok) start_checkpoint_bytes_ = *ok;
    if (ok || backend_->lost(ok.error())) return;  // a restart is seen next
    if (ok.error().code == PLR_ERR_CANCELLED) throw Stopped{};
    fail(ok.error());
  }

  static std::vector<std::uint32_t> box_ids(const sim::World& w) {
    std::vector<std::uint32_t> ids;
    for (const auto& b : w.boxes) ids.push_back(b.id);
    std::sort(ids.begin(), ids.end());
    return ids;
  }

  // The trailer's figures, with what the simulator holds at its end: a box
  // the executor counted that the simulator did not (or the reverse) shows.
  void finish_trailer(const Trailer& t, double wall_time_s) {
    auto w = backend_->wait_for_simulator();
    if (!w) fail(w.error());
    TrailerRecord r;
    r.name = t.name();
    r.boxes_total = stats_.boxes_total;
    r.boxes_unloaded = stats_.boxes_unloaded;
    r.sim_boxes_unloaded = w->unloaded;
    r.sim_boxes_left = static_cast<std::uint32_t>(w->world.boxes.size());
    r.recoveries = stats_.recoveries;
    r.plan_calls_unanswered = stats_.planner.unanswered;
    r.wall_time_s = wall_time_s;
    r.stop_reason = stats_.stop_reason;
    r.start_checkpoint_bytes = start_checkpoint_bytes_;
    log().info("trailer {} ({}): {}/{} boxes, {}", stats_.trailers.size() + 1, r.name,
               r.boxes_unloaded, r.boxes_total, r.stop_reason);
    stats_.trailers.push_back(std::move(r));
    save_report();
  }

  // Trailer `t` from its reset; started again when the simulator comes back
  // from a restart with another trailer's world (its checkpoint lost).
  void unload_from_its_start(const Trailer& t) {
    constexpr int kAttempts = 10;  // restarts are bounded by the run's max_restarts anyway
    for (int attempt = 1;; ++attempt) {
      reset_and_checkpoint(t);
      const auto ran = unload();
      if (ran) return;
      if (!backend_->another_world() || attempt == kAttempts) fail(ran.error());
      log().warn("trailer {}: {}: unloading it again from its start", t.name(),
                 ran.error().message);
    }
  }

  // One trailer, from what the simulator shows now. Fails (with the engine's
  // error) only when the simulator came back with another trailer's world.
  plr::Status unload() {
    auto w = backend_->wait_for_simulator();
    if (!w) fail(w.error());
    stats_.boxes_total = static_cast<std::uint32_t>(w->world.boxes.size()) + w->unloaded;
    log().info("{} boxes in the trailer", stats_.boxes_total);
    episode::EngineSettings settings;
    settings.limits = {max_actions_, max_idle_};
    settings.observers = {this};
    settings.recovery = backend_.get();
    engine_.emplace(*model_, *backend_, strategy_source(), std::move(settings));
    const auto ran = engine_->run();
    sync(engine_->episode());
    if (!ran && !backend_->another_world()) fail(ran.error());
    stats_.stop_reason = engine_->episode().stop_reason;
    return ran ? plr::Status{} : plr::Status{ran.error()};
  }

  // ---- The run as the engine goes (episode::Observer) ----------------------

  void starting(const episode::ActionStart& action, const episode::Episode& e) override {
    sync(e);
    strategy_ = action.strategy;
    node_ = action.node;
    action_name_ = fmt::format("#{} {}", action.number, sim::to_string(action.action));
    publish_state("starting");
  }

  void progress(const std::string& step) override { report_progress(step); }

  void note(const std::string& line) override { log().info("{}: {}", action_name_, line); }

  void recorded(const episode::EpisodeStep& step, const episode::Episode& e) override {
    sync(e);
    stats_.wall_time_s = seconds_since(t0_);
    report_progress(fmt::format("{}: +{} boxes", action_name_, step.outcome.boxes), true);
    publish_status();
    // After every action, so a run killed at any moment keeps its figures.
    stats_.stop_reason = "running";
    save_report();
  }

  void lost(const Error& why) override {
    log().warn("simulator lost ({}); waiting for it to restart", why.message);
    report_progress("waiting for the simulator");
  }

  void restored(const episode::Episode& e) override {
    sync(e);
    log().info("simulator back; restored 'checkpoint', repeating the interrupted action");
  }

  // The report's figures from the engine's (the total is the executor's own:
  // the boxes in the trailer and those unloaded before the run).
  void sync(const episode::Episode& e) {
    stats_.boxes_unloaded = e.boxes_unloaded;
    stats_.robot_time_s = e.robot_time_s;
    stats_.plan_wall_s = e.plan_wall_s;
    stats_.wasted_s = e.wasted_s;
    stats_.sim_time_s = e.sim_time_s;
    stats_.robot_trailer_collisions = e.robot_trailer_contacts;
    stats_.failed_grasps = e.failed_grasps;
    stats_.not_applicable = e.not_applicable;
    stats_.recoveries = e.recoveries;
    stats_.strategies_asked = e.strategies_asked;
    stats_.strategy_steps = e.strategy_steps;
    stats_.planner = e.planner;
    stats_.pick = e.pick;
    stats_.sweep = e.sweep;
    stats_.curve.clear();
    for (const auto& p : e.curve.points()) stats_.curve.push_back({p.robot_time_s, p.boxes});
    stats_.steps.clear();
    for (const auto& s : e.steps)
      stats_.steps.push_back({s.source, sim::to_string(s.action), sim::to_string(s.observation),
                              s.wall_height, s.pile_height, s.pile_depth, s.outcome.applicable,
                              s.outcome.boxes, s.outcome.robot_time_s});
    stats_.boxes_left.clear();
    for (const auto& b : e.left)
      stats_.boxes_left.push_back({b.id, episode::to_string(b.reason), b.detail});
  }

  // Why each box still in the trailer is there: known where the run stopped
  // by its rules; a stopped or failed run asks the simulator, if it can.
  void log_boxes_left() {
    if (stats_.boxes_left.empty() && stats_.boxes_unloaded < stats_.boxes_total && model_) {
      try {
        const actions::Perceived w = observe();
        const actions::Memory none;
        for (const auto& b :
             episode::boxes_left(w.world, w.q, engine_ ? engine_->memory() : none, *model_))
          stats_.boxes_left.push_back({b.id, episode::to_string(b.reason), b.detail});
      } catch (...) {  // the simulator is gone: the report says only what is known
      }
    }
    if (stats_.boxes_left.empty()) return;
    std::map<std::string, std::uint32_t> counts;
    for (const auto& b : stats_.boxes_left) ++counts[b.reason];
    std::string summary;
    for (const auto& [reason, n] : counts)
      summary += fmt::format("{}{}: {}", summary.empty() ? "" : ", ", reason, n);
    log().info("left in the trailer: {} box{} ({})", stats_.boxes_left.size(),
               stats_.boxes_left.size() == 1 ? "" : "es", summary);
    for (const auto& b : stats_.boxes_left)
      log().info("  box {}: {}{}", b.id, b.reason, b.detail.empty() ? "" : " (" + b.detail + ")");
  }

  void finish(bool ok) {
    stats_.wall_time_s = seconds_since(t0_);
    if (show_progress_ && tty_) std::fputs("\n", stderr);
    log().info("done: {} of {} boxes in {:.1f} s robot time ({:.1f} s wall): {}",
               stats_.boxes_unloaded, stats_.boxes_total, stats_.robot_time_s, stats_.wall_time_s,
               stats_.stop_reason);
    log_boxes_left();
    std::string report_error;
    try {
      write_report();
    } catch (const std::exception& e) {
      report_error = e.what();
      log().error("report: {}", report_error);
    }
    publish_status();
    flatbuffers::FlatBufferBuilder fbb;
    // Several trailers: the stop reason counts their boxes.
    const std::string reason = fmt::format(
        "{}{}{}", stats_.stop_reason,
        stats_.trailers.empty()
            ? fmt::format(": {}/{} boxes unloaded", stats_.boxes_unloaded, stats_.boxes_total)
            : "",
        report_error.empty() ? "" : "; report: " + report_error);
    fbb.Finish(msg::CreatePipelineDoneDirect(fbb, ok && report_error.empty(), reason.c_str()));
    (void)done_.publish(fbb);
  }

  // The figures and the curve only (no final scene: the simulator may be
  // gone or stopping); a failure is logged, the run goes on.
  void save_report() {
    try {
      write_report(false);
    } catch (const std::exception& e) {
      log().error("report: {}", e.what());
    }
  }

  // The figures go to `plr run`, which writes them into report.json; the
  // files beside it are the executor's.
  void write_report(bool final_scene = true) {
    auto check = [](const Status& written) {
      if (!written) throw std::runtime_error(written.error().message);
    };
    flatbuffers::FlatBufferBuilder report;
    report.Finish(
        msg::CreateNodeReportDirect(report, ctx().name().c_str(), to_json(stats_).dump().c_str()));
    check(report_pub_.publish(report));
    namespace fs = std::filesystem;
    const fs::path dir(report_dir_);
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) throw std::runtime_error(dir.string() + ": " + ec.message());
    auto write = [&](const std::string& name, const std::string& content) {
      check(write_file_atomically((dir / name).string(), content));
    };
    write("unloading.svg", curve_svg(stats_.curve, stats_.boxes_total,
                                     fmt::format("{}: {}/{} boxes unloaded", ctx().name(),
                                                 stats_.boxes_unloaded, stats_.boxes_total)));
    if (!final_scene) return;
    // The final scene, with the robot's links drawn over it.
    try {
      const actions::Perceived w = observe();
      sim::RenderOptions options;
      options.title = fmt::format("final scene: {} boxes left", w.world.boxes.size());
      std::vector<Eigen::Isometry3d> poses;
      robot_->forward_kinematics(w.q, poses);
      for (std::size_t i = 0; i < robot_->links().size(); ++i) {
        for (const auto& shape : robot_->links()[i].shapes) {
          sim::Overlay o;
          o.pose = poses[i] * shape.origin;
          switch (shape.type) {
            case sim::CollisionShape::Type::kBox:
              o.size = shape.size;
              break;
            case sim::CollisionShape::Type::kCylinder:
              o.size = {2 * shape.size.x(), 2 * shape.size.x(), shape.size.y()};
              break;
            case sim::CollisionShape::Type::kSphere:
              o.size = Eigen::Vector3d::Constant(2 * shape.size.x());
              break;
          }
          options.robot.push_back(o);
        }
      }
      check(sim::write_svg(dir / "scene_side.svg", w.world, sim::View::kSide, options));
      check(sim::write_svg(dir / "scene_top.svg", w.world, sim::View::kTop, options));
      // What is left, as a world file another run can start from.
      write("final_world.yaml", sim::format_world(w.world));
    } catch (const SimulatorLost& lost) {
      log().warn("no final scene: {}", lost.what);
    } catch (const Stopped&) {
      log().warn("no final scene: stopped");
    } catch (const std::runtime_error& e) {
      log().warn("no final scene: {}", e.what());
    }
  }

  // ---- Progress ------------------------------------------------------------

  void report_progress(const std::string& what, bool action_done = false) {
    publish_state(action_done ? "done" : what);
    if (!show_progress_) return;
    const auto line = progress_line(stats_.boxes_unloaded, stats_.boxes_total, stats_.robot_time_s,
                                    action_done ? what : action_name_ + ": " + what);
    if (tty_) {
      std::fprintf(stderr, "\r\033[K%s", line.c_str());
      std::fflush(stderr);
    } else if (action_done) {
      std::fprintf(stderr, "%s\n", line.c_str());
    }
  }

  void publish_status() {
    flatbuffers::FlatBufferBuilder fbb;
    std::vector<flatbuffers::Offset<msg::Stat>> s;
    auto add = [&](const char* key, double v) { s.push_back(msg::CreateStatDirect(fbb, key, v)); };
    add("boxes_unloaded", stats_.boxes_unloaded);
    add("boxes_total", stats_.boxes_total);
    add("actions", static_cast<double>(stats_.pick.executions + stats_.sweep.executions));
    add("robot_time_s", stats_.robot_time_s);
    add("boxes_per_s", stats_.robot_time_s > 0 ? stats_.boxes_unloaded / stats_.robot_time_s : 0.0);
    fbb.Finish(msg::CreateStatisticsDirect(fbb, ctx().name().c_str(), &s));
    (void)status_.publish(fbb);
  }

  // What a dashboard shows: the strategy and its node, the action and its
  // step, the curve and the planner's figures so far.
  void publish_state(const std::string& subaction) {
    static constexpr std::array<const char*, 7> kModes = {
        "", "M1 arm", "M2 arm+base", "M3 nose", "M4 arm line", "M5 base line", "M6 escape"};
    flatbuffers::FlatBufferBuilder fbb;
    const auto strategy =
        strategy_ ? sim::build(fbb, *strategy_) : flatbuffers::Offset<msg::Strategy>();
    std::vector<msg::CurveSample> curve;
    curve.reserve(stats_.curve.size());
    for (const auto& c : stats_.curve) curve.emplace_back(c.robot_time_s, c.boxes);
    std::vector<flatbuffers::Offset<msg::PlanModeStats>> modes;
    for (std::size_t m = 1; m < kModes.size(); ++m) {
      const auto& ms = stats_.planner.modes[m];
      modes.push_back(msg::CreatePlanModeStatsDirect(fbb, kModes[m], ms.queries, ms.failures,
                                                     ms.ms.mean, ms.expansions.mean));
    }
    fbb.Finish(msg::CreateExecutorStateDirect(
        fbb, action_name_.c_str(), subaction.c_str(), strategy,
        node_ ? static_cast<std::int32_t>(*node_) : -1, stats_.boxes_total, stats_.boxes_unloaded,
        stats_.robot_time_s, &curve, &modes));
    (void)state_pub_.publish(fbb);
  }

  // Parameters.
  std::string report_dir_, env_, world_file_;
  std::optional<sim::Strategy> first_strategy_;
  bool first_used_ = false;
  std::uint64_t seed_ = 1;
  std::vector<Trailer> trailers_;
  std::uint64_t cycles_ = 1;
  actions::ActionOptions options_;
  BusOptions bus_;
  std::uint64_t max_idle_ = 24, max_actions_ = 0;
  bool show_progress_ = true, tty_ = false;
  std::unique_ptr<sim::RobotModel> robot_;
  std::unique_ptr<actions::ActionModel> model_;
  Publisher<msg::Statistics> status_;
  Publisher<msg::ExecutorState> state_pub_;
  Publisher<msg::PipelineDone> done_;
  Publisher<msg::NodeReport> report_pub_;

  // Worker.
  std::thread worker_;
  std::mutex m_;
  std::condition_variable cv_;
  std::atomic<bool> stop_{false};

  // Run state (worker thread only).
  std::unique_ptr<BusBackend> backend_;
  std::optional<episode::Engine> engine_;
  Clock::time_point t0_;
  RunStats stats_;
  std::uint64_t start_checkpoint_bytes_ = 0;  // the trailer being unloaded's
  std::string action_name_;
  std::optional<sim::Strategy> strategy_;  // the one being walked (a copy: trees are small)
  std::optional<std::uint32_t> node_;
};

}  // namespace
}  // namespace plr::executor

PLR_PLUGIN(plr::executor::ExecutorNode, "strategy_executor", "2.0.0", PLR_KIND_EXECUTOR,
           "Walks strategies; runs each abstract action with the action model over the bus")
PLR_INTERFACE(plr::topic<plr::msg::Statistics>("executor/status"),
              plr::topic<plr::msg::ExecutorState>("executor/state"),
              plr::topic<plr::msg::PipelineDone>("pipeline/done"),
              plr::topic<plr::msg::NodeReport>("pipeline/report"))
