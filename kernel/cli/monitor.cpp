#include "monitor.hpp"

#include "commands.hpp"
#include "dds_tool.hpp"

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <unistd.h>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstring>
#include <ctime>
#include <iostream>
#include <map>
#include <set>
#include <thread>

namespace plr::kernel {

namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;

std::atomic<bool> g_interrupted{false};

nlohmann::json parse_payload(const plr_dds_Envelope& e) {
  if (e.payload._length > kMaxJsonPayload) return nlohmann::json::value_t::discarded;
  return nlohmann::json::parse(e.payload._buffer, e.payload._buffer + e.payload._length, nullptr,
                               false);
}

// A field of an untrusted document, or a default when missing or of another type.
template <class T>
T field(const nlohmann::json& j, const char* key, T fallback) {
  if (!j.is_object() || !j.contains(key)) return fallback;
  const auto& v = j[key];
  if constexpr (std::is_same_v<T, std::string>) {
    return v.is_string() ? v.get<std::string>() : fallback;
  } else if constexpr (std::is_arithmetic_v<T>) {
    return v.is_number() ? v.get<T>() : fallback;
  } else {
    return v.is_structured() ? v : fallback;
  }
}

std::string render(const std::map<std::string, nlohmann::json>& kernels, int domain) {
  std::string out;
  const std::time_t now = std::time(nullptr);
  char clock[16];
  std::strftime(clock, sizeof clock, "%H:%M:%S", std::localtime(&now));
  out += fmt::format("PLR monitor   domain {}   {} kernel(s)   {}   (Ctrl-C quits)\n\n", domain,
                     kernels.size(), clock);
  // WAITS: how often this kernel's DDS writers had to wait for a peer's
  // acknowledgements (a slow or lossy peer shows here first).
  out += fmt::format("{:<40} {:<16} {:>7} {:>6} {:>10} {:>10} {:>8} {:>7}\n", "KERNEL", "HOSTNAME",
                     "PID", "NODES", "DDS OUT", "DDS IN", "INVALID", "WAITS");
  for (const auto& [id, k] : kernels) {
    const auto t = field(k, "telemetry", nlohmann::json::object());
    const auto dds = field(t, "dds", nlohmann::json::object());
    out += fmt::format(
        "{:<40} {:<16} {:>7} {:>6} {:>10} {:>10} {:>8} {:>7}\n", id,
        field<std::string>(k, "hostname", "?"), field<std::int64_t>(k, "pid", 0),
        field(t, "nodes", nlohmann::json::array()).size(), field<std::uint64_t>(dds, "sent", 0),
        field<std::uint64_t>(dds, "received", 0), field<std::uint64_t>(dds, "invalid", 0),
        field<std::uint64_t>(dds, "writer_waits", 0));
  }
  out += fmt::format("\n{:<40} {:<16} {:<22} {:<10} {:<10}\n", "KERNEL", "NODE", "PLUG-IN",
                     "VERSION", "STATE");
  for (const auto& [id, k] : kernels)
    for (const auto& n :
         field(field(k, "telemetry", nlohmann::json::object()), "nodes", nlohmann::json::array()))
      out += fmt::format("{:<40} {:<16} {:<22} {:<10} {:<10}\n", id,
                         field<std::string>(n, "name", "?"), field<std::string>(n, "plugin", "?"),
                         field<std::string>(n, "version", ""), field<std::string>(n, "state", "?"));
  out += fmt::format("\n{:<40} {:<22} {:>9} {:>11} {:>11} {:>7} {:>7}\n", "KERNEL", "TOPIC",
                     "RATE Hz", "LAT us avg", "LAT us max", "DROPS", "INVALID");
  for (const auto& [id, k] : kernels)
    for (const auto& t :
         field(field(k, "telemetry", nlohmann::json::object()), "topics", nlohmann::json::array()))
      out +=
          fmt::format("{:<40} {:<22} {:>9.1f} {:>11.1f} {:>11.1f} {:>7} {:>7}\n", id,
                      field<std::string>(t, "name", "?"), field<double>(t, "rate_hz", 0),
                      field<double>(t, "latency_mean_us", 0), field<double>(t, "latency_max_us", 0),
                      field<std::uint64_t>(t, "drops", 0), field<std::uint64_t>(t, "invalid", 0));
  return out;
}

}  // namespace

int monitor(const MonitorOptions& options) {
  DdsTool tool;
  if (auto s = tool.open(options.dds); !s) return fail(s.error().message);
  const auto telemetry = tool.reader(kDdsTelemetryTopic, 1, true);
  const auto announce = tool.reader(kDdsAnnounceTopic, 1, false);
  if (telemetry < 0 || announce < 0) return fail("dds: cannot create the monitor's readers");
  std::signal(SIGINT, [](int) { g_interrupted = true; });
  std::signal(SIGTERM, [](int) { g_interrupted = true; });

  std::map<std::string, nlohmann::json> kernels;
  std::map<std::string, Clock::time_point> seen;
  const auto start = Clock::now();
  auto next_draw = start + 1s;
  while (!g_interrupted) {
    std::set<std::string> gone;
    tool.take(
        announce, [&](const plr_dds_Envelope& e) { seen[e.kernel] = Clock::now(); }, &gone);
    tool.take(telemetry, [&](const plr_dds_Envelope& e) {
      auto doc = parse_payload(e);
      if (!doc.is_object() || field<std::string>(doc, "kernel", "") != e.kernel) {
        ++tool.invalid;
        return;
      }
      kernels[e.kernel] = std::move(doc);
      seen.try_emplace(e.kernel, Clock::now());
    });
    const auto now = Clock::now();
    for (auto it = seen.begin(); it != seen.end();) {
      if (gone.count(it->first) || now - it->second > 3 * kPeerTimeout) {
        kernels.erase(it->first);
        it = seen.erase(it);
      } else {
        ++it;
      }
    }
    if (options.once) {
      // Done when every kernel that announced itself has sent telemetry too,
      // after a moment for discovery; or at the deadline.
      bool complete = now - start > 2s;
      for (const auto& [id, t] : seen) complete = complete && kernels.count(id);
      if (complete || now - start > std::chrono::duration<double>(options.wait_s)) break;
    } else if (now >= next_draw) {
      next_draw += 1s;
      if (options.json) {
        nlohmann::json doc = {{"domain", options.dds.domain}, {"kernels", nlohmann::json::array()}};
        for (const auto& [id, k] : kernels) doc["kernels"].push_back(k);
        std::cout << doc.dump() << std::endl;
      } else {
        std::cout << "\033[H\033[2J" << render(kernels, options.dds.domain) << std::flush;
      }
    }
    std::this_thread::sleep_for(50ms);
  }
  if (options.once) {
    if (options.json) {
      nlohmann::json doc = {{"domain", options.dds.domain},
                            {"kernels", nlohmann::json::array()},
                            {"invalid", tool.invalid}};
      for (const auto& [id, k] : kernels) doc["kernels"].push_back(k);
      std::cout << doc.dump(2) << "\n";
    } else {
      std::cout << render(kernels, options.dds.domain);
    }
    if (kernels.empty())
      std::cerr << "plr: no kernel found on domain " << options.dds.domain << "\n";
  }
  return 0;
}

int remote_command(const RemoteCommandOptions& options) {
  DdsTool tool;
  if (auto s = tool.open(options.dds); !s) return fail(s.error().message);
  const auto announce = tool.reader(kDdsAnnounceTopic, 1, false);
  const auto results = tool.reader(kDdsResultTopic, 16, true);
  const auto commands = tool.writer(kDdsControlTopic, 0, false);
  if (announce < 0 || results < 0 || commands < 0)
    return fail("dds: cannot create the control endpoints");

  // Which kernel: wait for its announce (they come 4 times a second).
  std::set<std::string> found;
  const auto deadline = Clock::now() + 3s;
  while (Clock::now() < deadline) {
    tool.take(announce, [&](const plr_dds_Envelope& e) {
      if (names_kernel(e.kernel, options.kernel)) found.insert(e.kernel);
    });
    if (!found.empty() && Clock::now() > deadline - 2s) break;
    std::this_thread::sleep_for(50ms);
  }
  if (found.empty())
    return fail(fmt::format("no kernel '{}' on DDS domain {}", options.kernel, options.dds.domain));
  if (found.size() > 1)
    return fail(fmt::format("'{}' names several kernels ({}); give the full id", options.kernel,
                            fmt::join(found, ", ")));
  const std::string target = *found.begin();
  // The kernel must have seen our writer, or the command is lost; and we its
  // result writer (kept answers reach a late reader, but only a matched one).
  for (int i = 0; i < 200; ++i) {
    dds_publication_matched_status_t w{};
    dds_subscription_matched_status_t r{};
    dds_get_publication_matched_status(commands, &w);
    dds_get_subscription_matched_status(results, &r);
    if (w.current_count > 0 && r.current_count > 0) break;
    std::this_thread::sleep_for(10ms);
  }

  char host[256] = {};
  ::gethostname(host, sizeof host - 1);
  const std::string me = fmt::format("plr-cli@{}:{}", host, ::getpid());
  nlohmann::json command = {{"cmd", options.cmd}, {"node", options.node}};
  if (options.cmd == "swap") command["plugin"] = options.plugin;
  const auto payload = command.dump();
  plr_dds_Envelope e{};
  e.kernel = const_cast<char*>(me.c_str());
  e.target = const_cast<char*>(target.c_str());
  e.name = const_cast<char*>(options.cmd.c_str());
  e.kind = static_cast<std::uint8_t>(EnvelopeKind::kCommand);
  e.correlation_id = 1;
  e.payload._buffer = reinterpret_cast<std::uint8_t*>(const_cast<char*>(payload.data()));
  e.payload._length = e.payload._maximum = static_cast<std::uint32_t>(payload.size());
  if (auto rc = dds_write(commands, &e); rc < 0)
    return fail(fmt::format("dds: cannot send the command: {}", dds_strretcode(rc)));

  const auto wait_until = Clock::now() + 60s;
  while (Clock::now() < wait_until) {
    std::optional<std::pair<int, std::string>> answer;
    tool.take(results, [&](const plr_dds_Envelope& r) {
      if (r.kind == static_cast<std::uint8_t>(EnvelopeKind::kResult) && me == r.target &&
          target == r.kernel && r.correlation_id == 1)
        answer.emplace(r.status, std::string(reinterpret_cast<const char*>(r.payload._buffer),
                                             std::min<std::size_t>(r.payload._length, 4096)));
    });
    if (answer) {
      if (answer->first != PLR_OK) return fail(fmt::format("{}: {}", target, answer->second));
      if (options.cmd == "swap")
        std::cout << fmt::format("node '{}' of kernel '{}' now runs '{}'\n", options.node, target,
                                 options.plugin);
      else
        std::cout << fmt::format("node '{}' of kernel '{}' {}\n", options.node, target,
                                 options.cmd == "pause" ? "paused" : "resumed");
      return 0;
    }
    std::this_thread::sleep_for(10ms);
  }
  return fail(fmt::format("kernel '{}' did not answer within 60 s", target));
}

}  // namespace plr::kernel
