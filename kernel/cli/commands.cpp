#include "commands.hpp"

#include "control.hpp"
#include "kernel.hpp"
#include "log_file.hpp"
#include "plugin_loader.hpp"
#include "run.hpp"
#include "shm_need.hpp"

#include <plr/plugin_abi.h>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <nlohmann/json.hpp>

#include <dirent.h>
#include <csignal>
#include <ctime>
#include <iostream>

namespace plr::kernel {

int fail(const std::string& message, int code) {
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

namespace {

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

}  // namespace

int fail(const Error& error) {
  return fail(error.message, exit_code(error.code));
}

Expected<PipelineConfig> load_config(const std::string& file,
                                     const std::vector<std::string>& overrides) {
  std::vector<Override> parsed;
  for (const auto& o : overrides) {
    auto p = parse_override(o);
    if (!p) return p.error();
    parsed.push_back(*p);
  }
  return load_pipeline_config(file, parsed);
}

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

int run_pipeline(const RunOptions& options) {
  spdlog::set_level(options.verbose ? spdlog::level::debug : spdlog::level::info);
  // A vanished peer shows up as EPIPE where we write, not as a process kill.
  std::signal(SIGPIPE, SIG_IGN);
  // Signals are taken synchronously by this thread only; every thread the
  // run starts inherits the mask.
  sigset_t signals;
  sigemptyset(&signals);
  for (int s : {SIGINT, SIGTERM, SIGHUP}) sigaddset(&signals, s);
  pthread_sigmask(SIG_BLOCK, &signals, nullptr);

  // Before anything is said, after the mask (its thread inherits it); the
  // hosts inherit its pipe. Destroyed last: the run's last lines are in it.
  std::unique_ptr<LogFile> log;
  if (!options.log_file.empty() && options.host == "main") {
    auto opened = LogFile::open({options.log_file, options.log_max_bytes, options.log_keep});
    if (!opened) return fail(opened.error());
    log = std::move(*opened);
  }
  Run run(options);
  if (auto s = run.prepare(); !s) return run.not_started(s.error());
  if (auto s = run.start(); !s) return run.not_started(s.error());
  for (;;) {
    timespec tick{0, 50'000'000};
    const int sig = sigtimedwait(&signals, nullptr, &tick);
    if (sig == SIGHUP && run.main_host()) {
      run.reload();
      continue;
    }
    if (sig > 0) return run.finish(ended_by_signal(sig));
    if (auto end = run.poll()) return run.finish(*end);
  }
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
  auto config = load_config(file, overrides);
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
    auto config = load_config(options.config, {});
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
  for (const auto& e : errors) fail(e, 1);
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
