#include "run.hpp"

#include "control.hpp"
#include "kernel.hpp"
#include "pipeline_config.hpp"
#include "plugin_loader.hpp"
#include "recorder.hpp"
#include "replayer.hpp"
#include "segment_watchdog.hpp"
#include "shm_need.hpp"
#include "supervisor.hpp"
#include "variables.hpp"

#include <plr/shm/segments.hpp>
#include <plr/shm/wake_latency.hpp>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <unistd.h>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstring>
#include <mutex>

namespace plr::kernel {

namespace {

using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

// Where POSIX shared memory lives (shm_open), whose room a run needs.
constexpr const char* kShmDir = "/dev/shm";

std::string new_run_id() {
  return fmt::format("{}-{:x}", ::getpid(), static_cast<std::uint32_t>(wall_now_ns() / 1000));
}

// Tells the supervisor that this host's nodes are up.
void report_ready() {
  const char* fd = std::getenv("PLR_READY_FD");
  if (fd == nullptr) return;
  const int n = std::atoi(fd);
  const char one = 1;
  (void)!::write(n, &one, 1);
  ::close(n);
  ::unsetenv("PLR_READY_FD");
}

}  // namespace

// Declared in the order they are made; destroyed in reverse, so the control
// socket, replayer and recorder go before the kernel whose bus they use, and
// the report outlives the kernel's listeners.
struct Run::Parts {
  // A host's parent is its supervisor. When it is killed, the host may hear
  // of it (PR_SET_PDEATHSIG) while the dying supervisor's other threads still
  // hold it as parent, and an orphan goes to init or to a subreaper: so ask
  // whether that process is still alive (a zombie is not), not who the parent is.
  shm::ProcessStamp parent = shm::ProcessStamp::of(::getppid());
  Clock::time_point started = Clock::now();
  std::optional<PipelineConfig> config;
  std::unique_ptr<RunReport> report;  // main host only
  // Host processes: started and watched from the main one.
  std::vector<HostConfig> children;
  std::optional<SegmentWatchdog> watchdog;
  // The request is machine-wide: the main host holds it for every host.
  std::optional<shm::WakeLatencyRequest> wake_latency;
  std::unique_ptr<Supervisor> supervisor;
  std::unique_ptr<Kernel> kernel;
  std::unique_ptr<Recorder> recorder;
  std::unique_ptr<Replayer> replayer;
  std::unique_ptr<ControlServer> control;

  std::atomic<bool> done{false};
  std::atomic<bool> done_ok{true};
  std::mutex reason_mutex;
  std::string done_reason;
  std::atomic<bool> stop_requested{false};
  std::optional<Clock::time_point> replayed_at;
};

Run::Run(RunOptions options)
    : options_(std::move(options)),
      main_host_(options_.host == "main"),
      parts_(std::make_unique<Parts>()) {}

Run::~Run() = default;

fs::path Run::report_file() const {
  return parts_->report ? parts_->report->file() : fs::path();
}

double Run::wall_s() const {
  return std::chrono::duration<double>(Clock::now() - parts_->started).count();
}

Status Run::prepare() {
  auto& p = *parts_;
  if (!main_host_)
    spdlog::set_pattern(fmt::format("[%H:%M:%S.%e] [%l] [host {}] %v", options_.host));
  auto config = load_config(options_.config, options_.overrides);
  if (!config) return config.error();
  // It names the run's segments.
  if (!options_.run_id.empty() && !shm::valid_run_id(options_.run_id))
    return make_error(
        PLR_ERR_INVALID,
        fmt::format("--run-id: '{}' is not a run id: 1 to 48 letters, digits, '_' and '-'",
                    options_.run_id));
  run_id_ = options_.run_id.empty() ? new_run_id() : options_.run_id;
  const auto report_dir =
      fs::absolute(options_.report_dir.empty() ? "report" : options_.report_dir);
  if (auto s = substitute_variables(*config,
                                    {{"report_dir", report_dir.string()},
                                     {"config_dir", fs::path(config->file).parent_path().string()},
                                     {"run_id", run_id_}});
      !s)
    return s.error();
  p.config = std::move(*config);
  p.started = Clock::now();
  // The main host writes report.json however the run ends; the others leave it to it.
  if (main_host_) p.report = std::make_unique<RunReport>(report_dir, p.config->pipeline, run_id_);

  for (const auto& h : hosts_with_nodes(*p.config))
    if (h != "main") p.children.push_back(*p.config->host(h));
  if (main_host_)
    if (auto s = prepare_main_host(); !s) return s;

  p.kernel = std::make_unique<Kernel>(*p.config, options_.host, run_id_);
  // Attached before the nodes start, so it hears of every topic they advertise.
  if (main_host_ && !options_.record_file.empty()) {
    auto r = Recorder::create(p.kernel->bus(), options_.record_file, options_.record_topics,
                              {options_.record_max_bytes, options_.record_keep});
    if (!r) return r.error();
    p.recorder = std::move(*r);
  }
  if (main_host_ && !options_.replay_file.empty()) {
    auto r = Replayer::create(p.kernel->bus(), options_.replay_file, options_.replay_speed);
    if (!r) return r.error();
    p.replayer = std::move(*r);
  }
  // Only the main host ends the run and reports; the others wait for the supervisor.
  if (main_host_)
    if (auto s = listen(); !s) return s;
  return {};
}

Status Run::prepare_main_host() {
  auto& p = *parts_;
  const auto& config = *p.config;
  // Before any thread starts (see SegmentWatchdog); only runs across hosts
  // have segments. Destroyed after the segments are removed.
  if (!p.children.empty()) p.watchdog.emplace(run_id_);
  if (const auto n = shm::reclaim_stale_segments(); n > 0)
    spdlog::info("removed {} shared-memory segments of dead runs", n);
  // Refused here, before any host starts, rather than by a host that
  // cannot make its segment (which still says so, for what is not counted).
  if (!p.children.empty()) {
    PluginLoader loader(plugin_search_paths(config));
    auto need = shm_need(config, loader);
    if (!need) return need.error();
    auto room = free_bytes(kShmDir);
    if (room && *room < need->total)
      return make_error(
          PLR_ERR_UNAVAILABLE,
          fmt::format("{}: the run needs {} ({} B) of {} and {} ({} B) is free: give {} more "
                      "room (docker run --shm-size) or lower topics' depth or slot_size",
                      config.file, format_bytes(need->total), need->total, kShmDir,
                      format_bytes(*room), *room, kShmDir));
    if (!room) spdlog::warn("cannot check the room in {}: {}", kShmDir, room.error().message);
    spdlog::info("{} of {} for {} segments", format_bytes(need->total), kShmDir,
                 need->segments.size());
  }
  if (const auto us = config.cpu_wake_latency_us) {
    auto r = shm::WakeLatencyRequest::hold(*us);
    if (r) {
      p.wake_latency.emplace(std::move(*r));
      spdlog::info("idle CPUs wake within {} us while the run lasts", *us);
    } else {
      spdlog::warn(
          "{}: cpu_wake_latency_us: /dev/cpu_dma_latency: {}; idle wake-ups keep the "
          "machine's setting",
          config.file, shm::to_string(r.error()));
    }
  }
  if (!p.children.empty()) {
    std::vector<std::string> command{fs::read_symlink("/proc/self/exe").string(), "run",
                                     config.file, "--report",
                                     p.report->file().parent_path().string()};
    for (const auto& o : options_.overrides) {
      command.push_back("--set");
      command.push_back(o);
    }
    if (options_.verbose) command.push_back("--verbose");
    p.supervisor = std::make_unique<Supervisor>(command, p.children, run_id_);
  }
  return {};
}

// The kernel's listeners and the control socket: what ends the run, and the
// figures nodes report.
Status Run::listen() {
  auto& p = *parts_;
  Kernel& kernel = *p.kernel;
  if (auto s = kernel.on_pipeline_done([&p](bool ok, std::string reason) {
        {
          std::lock_guard lock(p.reason_mutex);
          p.done_reason = std::move(reason);
        }
        p.done_ok = ok;
        p.done = true;
      });
      !s)
    return s;
  if (auto s = kernel.on_node_report([&p](const std::string& node, const std::string& figures) {
        if (auto added = p.report->add_figures(node, figures); !added)
          spdlog::warn("{}", added.error().message);
      });
      !s)
    return s;
  auto path = control_socket_path(p.config->pipeline);
  if (!path) return path.error();
  p.control = std::make_unique<ControlServer>(
      *path,
      [this, &kernel, pipeline = p.config->pipeline](const nlohmann::json& req) -> nlohmann::json {
        const auto cmd = req.value("cmd", "");
        if (cmd == "ping") return {{"ok", true}, {"pipeline", pipeline}};
        if (cmd == "status")
          return {{"ok", true}, {"telemetry", nlohmann::json::parse(kernel.telemetry_json())}};
        if (cmd == "stop") {
          request_stop();
          return {{"ok", true}};
        }
        if (cmd == "swap" || cmd == "pause" || cmd == "resume") {
          const auto node = req.value("node", "");
          auto s = cmd == "swap"    ? kernel.swap(node, req.value("plugin", ""))
                   : cmd == "pause" ? kernel.pause(node)
                                    : kernel.resume(node);
          if (!s) return {{"ok", false}, {"error", s.error().message}, {"code", s.error().code}};
          return {{"ok", true}};
        }
        return {{"ok", false},
                {"error", "unknown command '" + printable(cmd) + "'"},
                {"code", PLR_ERR_INVALID}};
      });
  return p.control->start();
}

Status Run::start() {
  auto& p = *parts_;
  // Hosts first: their services must be there when the main nodes start.
  if (p.supervisor)
    if (auto s = p.supervisor->start(std::chrono::seconds(60)); !s) return s;
  if (auto s = p.kernel->start(); !s) return s;
  if (auto s = p.kernel->sync_transports(); !s) return s;
  if (!main_host_) report_ready();
  spdlog::info("pipeline '{}' running ({} nodes); Ctrl-C stops it", p.config->pipeline,
               p.kernel->nodes().size());
  if (p.replayer) {
    spdlog::info("replaying {} messages of {}", p.replayer->size(), options_.replay_file);
    p.replayer->start();
  }
  return {};
}

std::optional<RunEnd> Run::poll() {
  auto& p = *parts_;
  // A replayed pipeline/done is the recorded run's end, not this one's.
  if (p.done && !p.replayer) {
    std::lock_guard lock(p.reason_mutex);
    spdlog::info("pipeline done: {}", p.done_reason);
    return RunEnd{p.done_ok ? Ending::Finished : Ending::Failed, p.done_reason, p.done_ok ? 0 : 1};
  }
  if (p.stop_requested)
    return RunEnd{Ending::Stopped, "stop requested on the control socket",
                  exit_code(PLR_ERR_CANCELLED)};
  if (p.replayer && p.replayer->done()) {
    const auto now = Clock::now();
    if (!p.replayed_at) {
      p.replayed_at = now;
      spdlog::info("replay done: {} messages published", p.replayer->published());
    }
    if (now - *p.replayed_at > std::chrono::duration<double>(options_.replay_linger_s))
      return RunEnd{Ending::Finished, "replay done", 0};
  }
  if (p.supervisor) {
    if (auto s = p.supervisor->poll(); !s) {
      spdlog::error("{}", s.error().message);
      return RunEnd{Ending::HostLost, s.error().message, exit_code(s.error().code)};
    }
  }
  if (options_.duration_s > 0 &&
      Clock::now() - p.started > std::chrono::duration<double>(options_.duration_s)) {
    spdlog::info("--duration {} s reached: stopping", options_.duration_s);
    return RunEnd{Ending::Duration, fmt::format("--duration {} s reached", options_.duration_s),
                  exit_code(PLR_ERR_TIMEOUT)};
  }
  return std::nullopt;
}

void Run::reload() {
  auto& p = *parts_;
  auto fresh = load_config(options_.config, options_.overrides);
  if (!fresh) {
    spdlog::error("reload refused, the pipeline keeps running: {}", fresh.error().message);
    return;
  }
  for (const auto& node : fresh->nodes) {
    const auto* running = p.kernel->config().node(node.name);
    if (running == nullptr || node.host != "main") continue;
    for (const auto& status : p.kernel->nodes()) {
      if (status.name != node.name || status.plugin == node.plugin) continue;
      if (auto s = p.kernel->swap(node.name, node.plugin); !s)
        spdlog::error("reload: {}", s.error().message);
    }
  }
}

void Run::request_stop() {
  parts_->stop_requested = true;
}

int Run::finish(const RunEnd& end) {
  auto& p = *parts_;
  p.kernel->stop();
  p.control.reset();
  // Hosts stop after the main nodes, so nothing waits on a vanished service.
  const int restarts = p.supervisor ? p.supervisor->restarts() : 0;
  p.supervisor.reset();
  // What the nodes reported while they stopped is in the report.
  p.kernel->drain_listeners();
  // After every host stopped: what they sent is on the bus and recorded.
  if (p.recorder) {
    if (auto s = p.recorder->finish(); !s)
      spdlog::error("record: {}", s.error().message);
    else
      spdlog::info("recorded {} messages to {}", p.recorder->messages(), p.recorder->path());
  }
  // The main host clears the run's shared memory; a host whose supervisor
  // died (kill -9) does it instead.
  if (main_host_ || !p.parent.alive()) (void)shm::remove_run_segments(run_id_);
  // The supervisor stops a host with SIGTERM: that is its normal end.
  if (!main_host_) return 0;
  p.report->end(end, wall_s(), restarts, p.kernel->bus().topic_stats());
  return end.exit_code;
}

int Run::not_started(const Error& error) {
  auto& p = *parts_;
  const int code = fail(error);
  if (p.kernel) p.kernel->stop();
  p.supervisor.reset();
  if (main_host_ && p.config) (void)shm::remove_run_segments(run_id_);
  if (p.report) p.report->end({Ending::NotStarted, error.message, code}, wall_s(), 0);
  return code;
}

RunEnd ended_by_signal(int signal) {
  spdlog::info("signal {}: stopping", signal);
  return {signal == SIGINT ? Ending::Interrupted : Ending::Terminated,
          fmt::format("signal {} ({})", signal, sigabbrev_np(signal)), 128 + signal};
}

}  // namespace plr::kernel
