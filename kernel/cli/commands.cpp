#include "commands.hpp"

#include "control.hpp"
#include "kernel.hpp"
#include "pipeline_config.hpp"
#include "plugin_loader.hpp"
#include "supervisor.hpp"
#include "variables.hpp"

#include <plr/shm/segments.hpp>
#include <plr/shm/wake_latency.hpp>

#include <plr/plugin_abi.h>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <nlohmann/json.hpp>

#include <dirent.h>
#include <unistd.h>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <ctime>
#include <filesystem>
#include <iostream>
#include <optional>

namespace plr::kernel {

namespace {

int fail(const std::string& message, int code = 1) {
  std::cerr << "plr: " << message << "\n";
  return code;
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

}  // namespace

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
  if (!config) return fail(config.error().message, 2);
  const std::string run_id = options.run_id.empty() ? new_run_id() : options.run_id;
  namespace fs = std::filesystem;
  const auto report_dir = fs::absolute(options.report_dir.empty() ? "report" : options.report_dir);
  if (auto s = substitute_variables(*config,
                                    {{"report_dir", report_dir.string()},
                                     {"config_dir", fs::path(config->file).parent_path().string()},
                                     {"run_id", run_id}});
      !s)
    return fail(s.error().message, 2);

  // Signals are taken synchronously by this thread only; every thread started
  // from here on inherits the mask.
  sigset_t signals;
  sigemptyset(&signals);
  for (int s : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&signals, s);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  // Host processes: started and watched from the main one.
  std::unique_ptr<Supervisor> supervisor;
  std::vector<HostConfig> children;
  for (const auto& h : hosts_with_nodes(*config))
    if (h != "main") children.push_back(*config->host(h));
  // The request is machine-wide: the main host holds it for every host.
  std::optional<shm::WakeLatencyRequest> wake_latency;
  if (main_host) {
    if (const auto n = shm::reclaim_stale_segments(); n > 0)
      spdlog::info("removed {} shared-memory segments of dead runs", n);
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
      return fail(s.error().message);

  std::atomic<bool> stop_requested{false};
  std::unique_ptr<ControlServer> control;
  if (options.host == "main") {
    auto path = control_socket_path(config->pipeline);
    if (!path) return fail(path.error().message);
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
            if (!s) return {{"ok", false}, {"error", s.error().message}};
            return {{"ok", true}};
          }
          return {{"ok", false}, {"error", "unknown command '" + cmd + "'"}};
        });
    if (auto s = control->start(); !s) return fail(s.error().message);
  }

  // Hosts first: their services must be there when the main nodes start.
  if (supervisor) {
    if (auto s = supervisor->start(std::chrono::seconds(60)); !s) {
      supervisor.reset();
      (void)shm::remove_run_segments(run_id);
      return fail(s.error().message);
    }
  }
  if (auto s = kernel.start(); !s) {
    supervisor.reset();
    if (main_host) (void)shm::remove_run_segments(run_id);
    return fail(s.error().message);
  }
  kernel.sync_transports();
  if (!main_host) report_ready();
  spdlog::info("pipeline '{}' running ({} nodes); Ctrl-C stops it", config->pipeline,
               kernel.nodes().size());

  const auto started = std::chrono::steady_clock::now();
  int exit_code = 0;
  for (;;) {
    timespec tick{0, 50'000'000};
    const int sig = sigtimedwait(&signals, nullptr, &tick);
    if (sig == SIGHUP && main_host) {
      reload(kernel, options);
      continue;
    }
    if (sig > 0) {
      spdlog::info("signal {}: stopping", sig);
      break;
    }
    if (finished) {
      std::lock_guard lock(reason_mutex);
      spdlog::info("pipeline done: {}", finish_reason);
      exit_code = finished_ok ? 0 : 1;
      break;
    }
    if (stop_requested) break;
    if (supervisor) {
      if (auto s = supervisor->poll(); !s) {
        spdlog::error("{}", s.error().message);
        exit_code = 1;
        break;
      }
    }
    if (options.duration_s > 0 && std::chrono::steady_clock::now() - started >
                                      std::chrono::duration<double>(options.duration_s))
      break;
  }
  kernel.stop();
  control.reset();
  // Hosts stop after the main nodes, so nothing waits on a vanished service.
  supervisor.reset();
  // The main host clears the run's shared memory; a host whose supervisor
  // died (kill -9) does it instead.
  if (main_host || !parent.alive()) (void)shm::remove_run_segments(run_id);
  return exit_code;
}

int validate(const std::string& file, const std::vector<std::string>& overrides) {
  auto config = load(file, overrides);
  if (!config) return fail(config.error().message, 2);
  PluginLoader loader(plugin_search_paths(*config));
  int bad = 0;
  for (const auto& n : config->nodes) {
    auto lib = loader.load(n.plugin);
    if (!lib) {
      std::cerr << "plr: " << n.where.str() << ": nodes." << n.name
                << ".plugin: " << lib.error().message << "\n";
      ++bad;
    }
  }
  if (bad) return 2;
  std::cout << fmt::format("{}: ok ({} nodes, {} hosts)\n", file, config->nodes.size(),
                           config->hosts.size());
  return 0;
}

int list_plugins(const PluginsOptions& options) {
  std::vector<std::string> paths{default_plugin_path()};
  if (!options.config.empty()) {
    auto config = load(options.config, {});
    if (!config) return fail(config.error().message, 2);
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
  for (const auto& e : errors) std::cerr << "plr: " << e << "\n";
  return 0;
}

int swap_plugin(const SwapOptions& options) {
  auto path = find_socket(options.pipeline);
  if (!path) return fail(path.error().message);
  auto reply = control_request(
      *path, {{"cmd", "swap"}, {"node", options.node}, {"plugin", options.plugin}}, 60000);
  if (!reply) return fail(reply.error().message);
  if (!reply->value("ok", false)) return fail(reply->value("error", "swap failed"));
  std::cout << fmt::format("node '{}' now runs '{}'\n", options.node, options.plugin);
  return 0;
}

int pause_resume(const std::string& cmd, const std::string& node, const std::string& pipeline) {
  auto path = find_socket(pipeline);
  if (!path) return fail(path.error().message);
  auto reply = control_request(*path, {{"cmd", cmd}, {"node", node}}, 60000);
  if (!reply) return fail(reply.error().message);
  if (!reply->value("ok", false)) return fail(reply->value("error", cmd + " failed"));
  std::cout << fmt::format("node '{}' {}\n", node, cmd == "pause" ? "paused" : "resumed");
  return 0;
}

int status(const std::string& pipeline) {
  auto path = find_socket(pipeline);
  if (!path) return fail(path.error().message);
  auto reply = control_request(*path, {{"cmd", "status"}}, 5000);
  if (!reply) return fail(reply.error().message);
  std::cout << (*reply)["telemetry"].dump(2) << "\n";
  return 0;
}

int print_version() {
  std::cout << fmt::format("plr {} (plug-in ABI {}.{})\n", PLR_VERSION, PLR_ABI_MAJOR,
                           PLR_ABI_MINOR);
  return 0;
}

}  // namespace plr::kernel
