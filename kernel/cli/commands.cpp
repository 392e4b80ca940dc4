#include "commands.hpp"

#include "control.hpp"
#include "kernel.hpp"
#include "pipeline_config.hpp"
#include "plugin_loader.hpp"
#include "recorder.hpp"
#include "replayer.hpp"
#include "shm_need.hpp"
#include "supervisor.hpp"
#include "variables.hpp"

#include <plr/shm/segments.hpp>
#include <plr/shm/wake_latency.hpp>

#include <plr/plugin_abi.h>
#include <plr/atomic_file.hpp>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <nlohmann/json.hpp>

#include <dirent.h>
#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>

namespace plr::kernel {

namespace {

int fail(const std::string& message, int code = 1) {
  // Messages quote config text, names from requests and file names: never
  // let their control bytes reach the terminal.
  // A config's error lists one problem a line.
  std::string shown;
  for (std::size_t start = 0; start <= message.size();) {
    const auto end = std::min(message.find('\n', start), message.size());
    shown +=
        (start == 0 ? "" : "\n") + printable(std::string_view(message).substr(start, end - start));
    start = end + 1;
  }
  std::cerr << "plr: " << shown << "\n";
  return code;
}

int fail(const Error& e) {
  return fail(e.message, exit_code(e.code));
}

// Where POSIX shared memory lives (shm_open), whose room a run needs.
constexpr const char* kShmDir = "/dev/shm";

// How a run ended, as report.json's `run.ended` says it.
enum class Ending {
  Finished,
  Failed,
  Interrupted,
  Terminated,
  Duration,
  Stopped,
  HostLost,
  NotStarted
};

const char* to_string(Ending e) {
  switch (e) {
    case Ending::Finished:
      return "finished";
    case Ending::Failed:
      return "failed";
    case Ending::Interrupted:
      return "interrupted";
    case Ending::Terminated:
      return "terminated";
    case Ending::Duration:
      return "duration";
    case Ending::Stopped:
      return "stopped";
    case Ending::HostLost:
      return "host_lost";
    case Ending::NotStarted:
      return "not_started";
  }
  return "?";
}

struct RunEnd {
  Ending ending = Ending::Finished;
  std::string reason;
  int exit_code = 0;
};

// report.json in the report folder says how the run ended, whatever ended
// it: nodes that write their figures there (the executor) wrote them while
// they stopped, and this adds `run`; a file older than the run is a previous
// run's and is replaced.
void write_run_report(const std::filesystem::path& dir, const RunEnd& end,
                      const PipelineConfig& config, const std::string& run_id,
                      std::filesystem::file_time_type started, double wall_s, int restarts,
                      const std::vector<TopicStatsSnapshot>& topics = {}) {
  namespace fs = std::filesystem;
  std::error_code ec;
  fs::create_directories(dir, ec);
  const fs::path file = dir / "report.json";
  nlohmann::json report = nlohmann::json::object();
  if (fs::exists(file, ec) && fs::last_write_time(file, ec) >= started && !ec) {
    std::ifstream in(file);
    auto parsed = nlohmann::json::parse(in, nullptr, false);
    if (parsed.is_object()) report = std::move(parsed);
  }
  report["run"] = {{"pipeline", config.pipeline},    {"run_id", run_id},
                   {"ended", to_string(end.ending)}, {"reason", end.reason},
                   {"exit_code", end.exit_code},     {"wall_s", wall_s},
                   {"host_restarts", restarts}};
  // Messages each topic carried on the main host's bus (what a recording of it should hold).
  for (const auto& t : topics) report["run"]["topic_messages"][t.name] = t.messages;
  if (auto s = write_file_atomically(file.string(), report.dump(2) + "\n"); !s)
    spdlog::error("report: {}", s.error().message);
  else
    spdlog::info("report: {} (run {})", file.string(), to_string(end.ending));
}

Expected<PipelineConfig> load(const std::string& file, const std::vector<std::string>& overrides) {
  std::vector<Override> parsed;
  for (const auto& o : overrides) {
    auto p = parse_override(o);
    if (!p) return p.error();
    parsed.push_back(*p);
  }
  return load_pipeline_config(file, parsed);
}

// A request the running pipeline refused: its reason, and the exit code of
// its kind of error.
int refused(const nlohmann::json& reply, const std::string& fallback) {
  const auto code = reply.contains("code") && reply["code"].is_number_integer()
                        ? static_cast<plr_status>(reply["code"].get<int>())
                        : PLR_ERR_INTERNAL;
  const auto& e = reply.contains("error") ? reply["error"] : nlohmann::json();
  return fail(e.is_string() ? e.get<std::string>() : fallback, exit_code(code));
}

// The pipeline to talk to: the named one, or the only one running.
Expected<std::string> find_socket(const std::string& pipeline) {
  if (!pipeline.empty()) return control_socket_path(pipeline);
  auto dir = control_dir();
  if (!dir) return dir.error();
  std::vector<std::string> found;
  if (DIR* d = ::opendir(dir->c_str())) {
    while (auto* e = ::readdir(d)) {
      std::string name = e->d_name;
      if (name.size() > 5 && name.ends_with(".sock")) found.push_back(*dir + "/" + name);
    }
    ::closedir(d);
  }
  std::vector<std::string> live;
  for (const auto& f : found)
    if (control_request(f, {{"cmd", "ping"}}, 500)) live.push_back(f);
  if (live.size() == 1) return live.front();
  if (live.empty()) return make_error(PLR_ERR_UNAVAILABLE, "no pipeline is running");
  return make_error(PLR_ERR_INVALID, "several pipelines are running; name one with --pipeline");
}

// A process of its own that removes the run's shared memory when the main
// process dies, whatever kills it (kill -9 of main and hosts together left
// every segment behind until the next run). It waits on a pipe only main
// writes to: a byte means main cleaned up itself, end-of-file that it died.
// Forked while main has one thread, so the child may run ordinary code.
class SegmentWatchdog {
 public:
  explicit SegmentWatchdog(const std::string& run_id) {
    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0) return;
    const pid_t pid = ::fork();
    if (pid == 0) {
      ::close(fds[1]);
      // Not the terminal's nor a caller's pipe: whoever reads main's output
      // sees its end when main ends.
      if (const int null = ::open("/dev/null", O_RDWR); null >= 0)
        for (int fd : {0, 1, 2}) ::dup2(null, fd);
      ::setsid();  // Ctrl-C of the terminal is for main, not for this
      for (int s : {SIGINT, SIGTERM, SIGHUP, SIGPIPE}) std::signal(s, SIG_IGN);
      char c = 0;
      ssize_t n = 0;
      while ((n = ::read(fds[0], &c, 1)) < 0 && errno == EINTR) {
      }
      if (n == 0) {
        // Hosts die with main (PR_SET_PDEATHSIG); one may still be making a segment.
        (void)shm::remove_run_segments(run_id);
        ::sleep(1);
        (void)shm::remove_run_segments(run_id);
      }
      ::_exit(0);
    }
    ::close(fds[0]);
    if (pid < 0) {
      ::close(fds[1]);
      return;
    }
    fd_ = fds[1];
    pid_ = pid;
  }
  // Main removed the segments: the watchdog ends at once.
  ~SegmentWatchdog() {
    if (fd_ < 0) return;
    const char done = 1;
    (void)!::write(fd_, &done, 1);
    ::close(fd_);
    ::waitpid(pid_, nullptr, 0);
  }
  SegmentWatchdog(const SegmentWatchdog&) = delete;
  SegmentWatchdog& operator=(const SegmentWatchdog&) = delete;

 private:
  int fd_ = -1;
  pid_t pid_ = -1;
};

}  // namespace

int exit_code(plr_status code) {
  switch (code) {
    case PLR_OK:
      return 0;
    case PLR_ERR_INVALID:
      return 2;
    case PLR_ERR_TIMEOUT:
      return 3;
    case PLR_ERR_UNAVAILABLE:
      return 4;
    case PLR_ERR_CANCELLED:
      return 5;
    case PLR_ERR_STATE:
      return 6;
    case PLR_ERR_INTERNAL:
      return 1;
  }
  return 1;
}

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

// SIGHUP: read the config again and swap every node whose plug-in changed.
void reload(Kernel& kernel, const RunOptions& options) {
  auto fresh = load(options.config, options.overrides);
  if (!fresh) {
    spdlog::error("reload refused, the pipeline keeps running: {}", fresh.error().message);
    return;
  }
  for (const auto& node : fresh->nodes) {
    const auto* running = kernel.config().node(node.name);
    if (running == nullptr || node.host != "main") continue;
    for (const auto& status : kernel.nodes()) {
      if (status.name != node.name || status.plugin == node.plugin) continue;
      if (auto s = kernel.swap(node.name, node.plugin); !s)
        spdlog::error("reload: {}", s.error().message);
    }
  }
}

int run_pipeline(const RunOptions& options) {
  spdlog::set_level(options.verbose ? spdlog::level::debug : spdlog::level::info);
  const bool main_host = options.host == "main";
  // A host's parent is its supervisor. When it is killed, the host may hear
  // of it (PR_SET_PDEATHSIG) while the dying supervisor's other threads still
  // hold it as parent, and an orphan goes to init or to a subreaper: so ask
  // whether that process is still alive (a zombie is not), not who the parent is.
  const auto parent = shm::ProcessStamp::of(::getppid());
  // A vanished peer shows up as EPIPE where we write, not as a process kill.
  std::signal(SIGPIPE, SIG_IGN);
  if (!main_host) spdlog::set_pattern(fmt::format("[%H:%M:%S.%e] [%l] [host {}] %v", options.host));
  auto config = load(options.config, options.overrides);
  if (!config) return fail(config.error());
  // It names the run's segments.
  if (!options.run_id.empty() && !shm::valid_run_id(options.run_id))
    return fail(fmt::format("--run-id: '{}' is not a run id: 1 to 48 letters, digits, '_' and '-'",
                            options.run_id),
                2);
  const std::string run_id = options.run_id.empty() ? new_run_id() : options.run_id;
  namespace fs = std::filesystem;
  const auto report_dir = fs::absolute(options.report_dir.empty() ? "report" : options.report_dir);
  if (auto s = substitute_variables(*config,
                                    {{"report_dir", report_dir.string()},
                                     {"config_dir", fs::path(config->file).parent_path().string()},
                                     {"run_id", run_id}});
      !s)
    return fail(s.error());

  // Signals are taken synchronously by this thread only; every thread started
  // from here on inherits the mask.
  sigset_t signals;
  sigemptyset(&signals);
  for (int s : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&signals, s);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  const auto started = std::chrono::steady_clock::now();
  // Files written from here on are this run's (report.json, see write_run_report).
  const auto started_file_time = fs::file_time_type::clock::now() - std::chrono::seconds(1);
  std::unique_ptr<Supervisor> supervisor;
  // The main host writes report.json however the run ends; the others leave it to it.
  const auto end_run = [&](RunEnd end) {
    if (main_host)
      write_run_report(
          report_dir, end, *config, run_id, started_file_time,
          std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count(),
          supervisor ? supervisor->restarts() : 0);
    return end.exit_code;
  };
  const auto not_started = [&](const Error& e) {
    fail(e.message);
    return end_run({Ending::NotStarted, e.message, exit_code(e.code)});
  };

  // Host processes: started and watched from the main one.
  std::vector<HostConfig> children;
  for (const auto& h : hosts_with_nodes(*config))
    if (h != "main") children.push_back(*config->host(h));
  // Before any thread starts (see SegmentWatchdog); only runs across hosts
  // have segments. Destroyed after the segments are removed below.
  std::optional<SegmentWatchdog> watchdog;
  if (main_host && !children.empty()) watchdog.emplace(run_id);
  // The request is machine-wide: the main host holds it for every host.
  std::optional<shm::WakeLatencyRequest> wake_latency;
  if (main_host) {
    if (const auto n = shm::reclaim_stale_segments(); n > 0)
      spdlog::info("removed {} shared-memory segments of dead runs", n);
    // Refused here, before any host starts, rather than by a host that
    // cannot make its segment (which still says so, for what is not counted).
    if (!children.empty()) {
      PluginLoader loader(plugin_search_paths(*config));
      auto need = shm_need(*config, loader);
      if (!need) return not_started(need.error());
      auto room = free_bytes(kShmDir);
      if (room && *room < need->total)
        return not_started(make_error(
            PLR_ERR_UNAVAILABLE,
            fmt::format("{}: the run needs {} ({} B) of {} and {} ({} B) is free: give {} more "
                        "room (docker run --shm-size) or lower topics' depth or slot_size",
                        config->file, format_bytes(need->total), need->total, kShmDir,
                        format_bytes(*room), *room, kShmDir)));
      if (!room) spdlog::warn("cannot check the room in {}: {}", kShmDir, room.error().message);
      spdlog::info("{} of {} for {} segments", format_bytes(need->total), kShmDir,
                   need->segments.size());
    }
    if (const auto us = config->cpu_wake_latency_us) {
      auto r = shm::WakeLatencyRequest::hold(*us);
      if (r) {
        wake_latency.emplace(std::move(*r));
        spdlog::info("idle CPUs wake within {} us while the run lasts", *us);
      } else {
        spdlog::warn(
            "{}: cpu_wake_latency_us: /dev/cpu_dma_latency: {}; idle wake-ups keep the "
            "machine's setting",
            config->file, shm::to_string(r.error()));
      }
    }
    if (!children.empty()) {
      std::vector<std::string> command{fs::read_symlink("/proc/self/exe").string(), "run",
                                       config->file, "--report", report_dir.string()};
      for (const auto& o : options.overrides) {
        command.push_back("--set");
        command.push_back(o);
      }
      if (options.verbose) command.push_back("--verbose");
      supervisor = std::make_unique<Supervisor>(command, children, run_id);
    }
  }

  Kernel kernel(*config, options.host, run_id);
  // Attached before the nodes start, so it hears of every topic they advertise.
  std::unique_ptr<Recorder> recorder;
  if (main_host && !options.record_file.empty()) {
    auto r = Recorder::create(kernel.bus(), options.record_file, options.record_topics);
    if (!r) return not_started(r.error());
    recorder = std::move(*r);
  }
  std::unique_ptr<Replayer> replayer;
  if (main_host && !options.replay_file.empty()) {
    auto r = Replayer::create(kernel.bus(), options.replay_file, options.replay_speed);
    if (!r) return not_started(r.error());
    replayer = std::move(*r);
  }
  std::atomic<bool> finished{false};
  std::atomic<bool> finished_ok{true};
  std::string finish_reason;
  std::mutex reason_mutex;
  // Only the main host ends the run; the others wait for the supervisor.
  if (main_host)
    if (auto s = kernel.on_pipeline_done([&](bool ok, std::string reason) {
          {
            std::lock_guard lock(reason_mutex);
            finish_reason = std::move(reason);
          }
          finished_ok = ok;
          finished = true;
        });
        !s)
      return not_started(s.error());

  std::atomic<bool> stop_requested{false};
  std::unique_ptr<ControlServer> control;
  if (options.host == "main") {
    auto path = control_socket_path(config->pipeline);
    if (!path) return not_started(path.error());
    control =
        std::make_unique<ControlServer>(*path, [&](const nlohmann::json& req) -> nlohmann::json {
          const auto cmd = req.value("cmd", "");
          if (cmd == "ping") return {{"ok", true}, {"pipeline", config->pipeline}};
          if (cmd == "status")
            return {{"ok", true}, {"telemetry", nlohmann::json::parse(kernel.telemetry_json())}};
          if (cmd == "stop") {
            stop_requested = true;
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
    if (auto s = control->start(); !s) return not_started(s.error());
  }

  // Hosts first: their services must be there when the main nodes start.
  if (supervisor) {
    if (auto s = supervisor->start(std::chrono::seconds(60)); !s) {
      supervisor.reset();
      (void)shm::remove_run_segments(run_id);
      return not_started(s.error());
    }
  }
  if (auto s = kernel.start(); !s) {
    supervisor.reset();
    if (main_host) (void)shm::remove_run_segments(run_id);
    return not_started(s.error());
  }
  if (auto s = kernel.sync_transports(); !s) {
    kernel.stop();
    supervisor.reset();
    if (main_host) (void)shm::remove_run_segments(run_id);
    return not_started(s.error());
  }
  if (!main_host) report_ready();
  spdlog::info("pipeline '{}' running ({} nodes); Ctrl-C stops it", config->pipeline,
               kernel.nodes().size());
  std::optional<std::chrono::steady_clock::time_point> replayed_at;
  if (replayer) {
    spdlog::info("replaying {} messages of {}", replayer->size(), options.replay_file);
    replayer->start();
  }

  RunEnd end;
  for (;;) {
    timespec tick{0, 50'000'000};
    const int sig = sigtimedwait(&signals, nullptr, &tick);
    if (sig == SIGHUP && main_host) {
      reload(kernel, options);
      continue;
    }
    if (sig > 0) {
      spdlog::info("signal {}: stopping", sig);
      // 128 + signal, as a shell reports a process the signal ended.
      end = {sig == SIGINT ? Ending::Interrupted : Ending::Terminated,
             fmt::format("signal {} ({})", sig, sigabbrev_np(sig)), 128 + sig};
      break;
    }
    // A replayed pipeline/done is the recorded run's end, not this one's.
    if (finished && !replayer) {
      std::lock_guard lock(reason_mutex);
      spdlog::info("pipeline done: {}", finish_reason);
      end = {finished_ok ? Ending::Finished : Ending::Failed, finish_reason, finished_ok ? 0 : 1};
      break;
    }
    if (stop_requested) {
      end = {Ending::Stopped, "stop requested on the control socket", exit_code(PLR_ERR_CANCELLED)};
      break;
    }
    if (replayer && replayer->done()) {
      const auto now = std::chrono::steady_clock::now();
      if (!replayed_at) {
        replayed_at = now;
        spdlog::info("replay done: {} messages published", replayer->published());
      }
      if (now - *replayed_at > std::chrono::duration<double>(options.replay_linger_s)) {
        end = {Ending::Finished, "replay done", 0};
        break;
      }
    }
    if (supervisor) {
      if (auto s = supervisor->poll(); !s) {
        spdlog::error("{}", s.error().message);
        end = {Ending::HostLost, s.error().message, exit_code(s.error().code)};
        break;
      }
    }
    if (options.duration_s > 0 && std::chrono::steady_clock::now() - started >
                                      std::chrono::duration<double>(options.duration_s)) {
      spdlog::info("--duration {} s reached: stopping", options.duration_s);
      end = {Ending::Duration, fmt::format("--duration {} s reached", options.duration_s),
             exit_code(PLR_ERR_TIMEOUT)};
      break;
    }
  }
  kernel.stop();
  control.reset();
  // Hosts stop after the main nodes, so nothing waits on a vanished service.
  const int restarts = supervisor ? supervisor->restarts() : 0;
  supervisor.reset();
  // After every host stopped: what they sent is on the bus and recorded.
  if (recorder) {
    if (auto s = recorder->finish(); !s)
      spdlog::error("record: {}", s.error().message);
    else
      spdlog::info("recorded {} messages to {}", recorder->messages(), recorder->path());
  }
  // The main host clears the run's shared memory; a host whose supervisor
  // died (kill -9) does it instead.
  if (main_host || !parent.alive()) (void)shm::remove_run_segments(run_id);
  // The supervisor stops a host with SIGTERM: that is its normal end.
  if (!main_host) return 0;
  write_run_report(
      report_dir, end, *config, run_id, started_file_time,
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count(), restarts,
      kernel.bus().topic_stats());
  return end.exit_code;
}

namespace {

// "/dev/shm: 80.1 MiB (83976192 B) in 16 segments" and, verbose, one line per segment.
void print_shm_need(const ShmNeed& need, bool verbose) {
  if (need.segments.empty() && need.undeclared.empty()) {
    std::cout << "/dev/shm: none (one host: its nodes share the bus in memory)\n";
    return;
  }
  std::cout << fmt::format("/dev/shm: {} ({} B) in {} segments\n", format_bytes(need.total),
                           need.total, need.segments.size());
  if (verbose)
    for (const auto& s : need.segments)
      std::cout << fmt::format("  {:<8} {:<7} {:<24} {:>5} x {:>9} B  {:>10}\n", s.host,
                               s.service ? "service" : "topic", s.name, s.slots, s.slot_size,
                               format_bytes(s.bytes));
  for (const auto& n : need.undeclared)
    std::cout << fmt::format(
        "  node '{}': its plug-in declares no topics or services (plr/interface.hpp): not "
        "counted\n",
        n);
}

}  // namespace

int validate(const std::string& file, const std::vector<std::string>& overrides, bool verbose) {
  auto config = load(file, overrides);
  if (!config) return fail(config.error());
  PluginLoader loader(plugin_search_paths(*config));
  int code = 0;
  for (const auto& n : config->nodes) {
    auto lib = loader.load(n.plugin);
    if (!lib) {
      const int c =
          fail(fmt::format("{}: nodes.{}.plugin: {}", n.where.str(), n.name, lib.error().message),
               exit_code(lib.error().code));
      if (code == 0) code = c;
    }
  }
  if (code != 0) return code;
  auto need = shm_need(*config, loader);
  if (!need) return fail(need.error());
  std::cout << fmt::format("{}: ok ({} nodes, {} hosts)\n", file, config->nodes.size(),
                           config->hosts.size());
  print_shm_need(*need, verbose);
  return 0;
}

int list_plugins(const PluginsOptions& options) {
  std::vector<std::string> paths{default_plugin_path()};
  if (!options.config.empty()) {
    auto config = load(options.config, {});
    if (!config) return fail(config.error());
    paths = plugin_search_paths(*config);
  }
  PluginLoader loader(paths);
  std::vector<std::string> errors;
  const auto infos = loader.list(&errors);
  if (options.json) {
    nlohmann::json out = nlohmann::json::array();
    for (const auto& p : infos)
      out.push_back({{"name", p.name},
                     {"version", p.version},
                     {"kind", p.kind},
                     {"description", p.description},
                     {"path", p.path},
                     {"abi", fmt::format("{}.{}", p.abi_major, p.abi_minor)}});
    std::cout << out.dump(2) << "\n";
  } else {
    std::cout << fmt::format("{:<22} {:<10} {:<10} {}\n", "NAME", "VERSION", "KIND", "DESCRIPTION");
    for (const auto& p : infos)
      std::cout << fmt::format("{:<22} {:<10} {:<10} {}\n", p.name, p.version, p.kind,
                               p.description);
  }
  for (const auto& e : errors) fail(e);
  return 0;
}

int swap_plugin(const SwapOptions& options) {
  auto path = find_socket(options.pipeline);
  if (!path) return fail(path.error());
  auto reply = control_request(
      *path, {{"cmd", "swap"}, {"node", options.node}, {"plugin", options.plugin}}, 60000);
  if (!reply) return fail(reply.error());
  if (!reply->value("ok", false)) return refused(*reply, "swap failed");
  std::cout << fmt::format("node '{}' now runs '{}'\n", options.node, options.plugin);
  return 0;
}

int pause_resume(const std::string& cmd, const std::string& node, const std::string& pipeline) {
  auto path = find_socket(pipeline);
  if (!path) return fail(path.error());
  auto reply = control_request(*path, {{"cmd", cmd}, {"node", node}}, 60000);
  if (!reply) return fail(reply.error());
  if (!reply->value("ok", false)) return refused(*reply, cmd + " failed");
  std::cout << fmt::format("node '{}' {}\n", node, cmd == "pause" ? "paused" : "resumed");
  return 0;
}

int status(const std::string& pipeline) {
  auto path = find_socket(pipeline);
  if (!path) return fail(path.error());
  auto reply = control_request(*path, {{"cmd", "status"}}, 5000);
  if (!reply) return fail(reply.error());
  std::cout << (*reply)["telemetry"].dump(2) << "\n";
  return 0;
}

int print_version() {
  std::cout << fmt::format("plr {} (plug-in ABI {}.{})\n", PLR_VERSION, PLR_ABI_MAJOR,
                           PLR_ABI_MINOR);
  return 0;
}

}  // namespace plr::kernel
