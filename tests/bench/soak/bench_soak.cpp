// Hours, not minutes (issue 50): ONE `plr run` of the robot pipeline
// (simulator host, ARA* planner, strategy H, the executor unloading trailer
// after trailer of mixed families, the web monitor with a page client and a
// Foxglove client coming and going, a recorder, DDS on loopback) for a wall
// time, with faults on a seeded schedule:
//   kill_sim   kill -9 of the simulator's host
//   swap       `plr swap planner` between ARA* and RRTConnect
//   sighup     the config rewritten with the other planner, then SIGHUP (reload)
//   dds_monitor `plr monitor --once`: a DDS participant attaches and leaves
//   shm_full   /dev/shm filled to the brim, then the simulator's host killed:
//              its restart's segments are refused (posix_fallocate: ENOSPC)
//              until the filler goes, once the refusal is in the log
//   read_only  the report folder (report.json, the checkpoint) remounted
//              read-only for a while
// Every fourth fault event is two kinds at once. A fault is survived when
// the pipeline is still running and the executor has moved on since
// (messages on executor/state, from `plr status`).
//
// The bench runs in a mount namespace of its own (it needs root): /dev/shm
// there is a tmpfs of its own, sized to the run's need (from `plr validate`)
// plus 64 MiB, which makes the full /dev/shm real without touching the
// machine's, and the report folder is a bind mount that can be made
// read-only (root ignores file modes, not a read-only mount).
//
// Measured every 5 s (a table row every 10 min, every 2 min with --quick):
// RSS and descriptors of every process of the run (/proc), bytes of the
// run's /dev/shm segments (pages held), DDS entities (participants, writers
// and readers alive on the domain, from Cyclone's built-in topics, without
// the bench's own participant), checkpoint bytes, log bytes (stderr, the
// recording, the report folder). Growth: the least-squares slope per hour of
// the samples after the first trailer, over their mean; the checkpoint's
// from each trailer's start checkpoint against the same world's first.
//
// Then the same trailers once more without faults, clients or DDS (a second
// `plr run`, the trailers the soak finished, each once): boxes_without_faults.
//
//   bench_soak [--minutes M] [--quick] [--json] [--seed S] [--depth D] [--keep DIR]
#include <dds/dds.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/mount.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <optional>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "bench_cli.hpp"
#include "dds_domain.hpp"
#include "plr/sim/generators.hpp"
#include "plr/sim/world_io.hpp"
#include "web_client.hpp"

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;
using json = nlohmann::json;
using plr::sim::EnvFamily;

double since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

std::string read_file(const fs::path& p) {
  std::ifstream in(p);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

void write_file(const fs::path& p, const std::string& text) {
  const fs::path tmp = p.string() + ".tmp";
  std::ofstream(tmp) << text;
  fs::rename(tmp, p);
}

// Runs `argv`, stdout into `out` (if given), stderr to /dev/null; the exit code.
int run_tool(const std::vector<std::string>& argv, std::string* out = nullptr) {
  int pipefd[2] = {-1, -1};
  if (out && ::pipe(pipefd) != 0) return -1;
  const pid_t pid = ::fork();
  if (pid == 0) {
    const int null = ::open("/dev/null", O_RDWR);
    ::dup2(out ? pipefd[1] : null, 1);
    ::dup2(null, 2);
    if (out) ::close(pipefd[0]);
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    ::execv(args[0], args.data());
    ::_exit(127);
  }
  if (out) {
    ::close(pipefd[1]);
    char buf[4096];
    for (ssize_t n; (n = ::read(pipefd[0], buf, sizeof buf)) > 0;) out->append(buf, n);
    ::close(pipefd[0]);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

// ---- Processes of the run --------------------------------------------------

struct Proc {
  pid_t pid = 0;
  std::string label;  // main, host:NAME, watchdog
  double rss_mib = 0;
  double anon_mib = 0;  // of it, the process's own memory (heap, stacks): not code, not /dev/shm
  int fds = 0;
};

std::vector<std::string> cmdline(pid_t pid) {
  const std::string raw = read_file(fmt::format("/proc/{}/cmdline", pid));
  std::vector<std::string> args;
  std::string cur;
  for (char c : raw) {
    if (c == '\0') {
      args.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  return args;
}

pid_t parent_of(pid_t pid) {
  const std::string stat = read_file(fmt::format("/proc/{}/stat", pid));
  const auto close = stat.rfind(')');
  if (close == std::string::npos) return 0;
  std::istringstream in(stat.substr(close + 2));
  char state = 0;
  pid_t ppid = 0;
  in >> state >> ppid;
  return ppid;
}

// `root` and its descendants, labelled.
std::vector<Proc> processes(pid_t root) {
  std::map<pid_t, pid_t> parent;
  for (const auto& e : fs::directory_iterator("/proc")) {
    const std::string name = e.path().filename();
    if (name.empty() || !std::isdigit(static_cast<unsigned char>(name[0]))) continue;
    const pid_t pid = std::stoi(name);
    parent[pid] = parent_of(pid);
  }
  std::vector<Proc> out;
  std::set<pid_t> tree{root};
  for (bool grew = true; grew;) {
    grew = false;
    for (const auto& [pid, pp] : parent)
      if (tree.count(pp) && !tree.count(pid)) grew = tree.insert(pid).second || grew;
  }
  for (pid_t pid : tree) {
    Proc p;
    p.pid = pid;
    const auto args = cmdline(pid);
    if (args.empty()) continue;  // gone, or a zombie
    p.label = pid == root ? "main" : "watchdog";
    for (std::size_t i = 0; i + 1 < args.size(); ++i)
      if (args[i] == "--host") p.label = "host:" + args[i + 1];
    std::istringstream status(read_file(fmt::format("/proc/{}/status", pid)));
    for (std::string line; std::getline(status, line);)
      if (line.rfind("VmRSS:", 0) == 0)
        p.rss_mib = std::stod(line.substr(6)) / 1024.0;
      else if (line.rfind("RssAnon:", 0) == 0)
        p.anon_mib = std::stod(line.substr(8)) / 1024.0;
    std::error_code ec;
    for (auto it = fs::directory_iterator(fmt::format("/proc/{}/fd", pid), ec);
         !ec && it != fs::directory_iterator(); it.increment(ec))
      ++p.fds;
    out.push_back(p);
  }
  return out;
}

std::optional<pid_t> host_pid(pid_t root, const std::string& host) {
  for (const auto& p : processes(root))
    if (p.label == "host:" + host) return p.pid;
  return std::nullopt;
}

// Bytes a folder's files hold (pages, for /dev/shm), skipping `skip`.
std::uint64_t folder_bytes(const fs::path& dir, const std::string& skip = {}) {
  std::uint64_t n = 0;
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(dir, ec);
       !ec && it != fs::recursive_directory_iterator(); it.increment(ec)) {
    struct stat st {};
    if (it->path().filename() == skip || ::lstat(it->path().c_str(), &st) != 0) continue;
    if (S_ISREG(st.st_mode)) n += static_cast<std::uint64_t>(st.st_blocks) * 512;
  }
  return n;
}

std::uint64_t file_bytes(const fs::path& f) {
  std::error_code ec;
  const auto n = fs::file_size(f, ec);
  return ec ? 0 : n;
}

// `plr run --log FILE`'s files: FILE and its rotated FILE.1, FILE.2, ...
std::uint64_t log_bytes(const fs::path& f) {
  std::uint64_t n = file_bytes(f);
  for (int k = 1; fs::exists(f.string() + "." + std::to_string(k)); ++k)
    n += file_bytes(f.string() + "." + std::to_string(k));
  return n;
}

// `plr run --record FILE`'s parts: FILE (or FILE.part while it is written)
// and the earlier STEM.1.EXT, STEM.2.EXT, ...
std::uint64_t record_bytes(const fs::path& f) {
  std::uint64_t n = file_bytes(f) + file_bytes(f.string() + ".part");
  for (int k = 1;; ++k) {
    const fs::path part =
        f.parent_path() / (f.stem().string() + "." + std::to_string(k) + f.extension().string());
    if (!fs::exists(part)) return n;
    n += file_bytes(part);
  }
}

// ---- DDS entities, as a participant on the domain sees them ------------------

class DdsCount {
 public:
  explicit DdsCount(int domain) {
    plr::kernel::DdsConfig c;
    c.enabled = true;
    c.domain = domain;
    auto p = plr::kernel::open_participant(c);
    if (!p) throw std::runtime_error("DDS: " + p.error().message);
    participant_ = *p;
    dds_get_guid(participant_, &own_);
    participants_ =
        dds_create_reader(participant_, DDS_BUILTIN_TOPIC_DCPSPARTICIPANT, nullptr, nullptr);
    writers_ = dds_create_reader(participant_, DDS_BUILTIN_TOPIC_DCPSPUBLICATION, nullptr, nullptr);
    readers_ =
        dds_create_reader(participant_, DDS_BUILTIN_TOPIC_DCPSSUBSCRIPTION, nullptr, nullptr);
  }
  ~DdsCount() { dds_delete(participant_); }

  // Participants, writers and readers alive now (not the bench's own).
  int count() {
    return alive(participants_, true) + alive(writers_, false) + alive(readers_, false);
  }

 private:
  int alive(dds_entity_t reader, bool is_participant) {
    constexpr int kMax = 4096;
    std::vector<void*> samples(kMax, nullptr);
    std::vector<dds_sample_info_t> infos(kMax);
    const int n =
        dds_read_mask(reader, samples.data(), infos.data(), kMax, kMax,
                      DDS_ANY_SAMPLE_STATE | DDS_ANY_VIEW_STATE | DDS_ALIVE_INSTANCE_STATE);
    int count = 0;
    for (int i = 0; i < n; ++i) {
      if (!infos[i].valid_data) continue;
      const dds_guid_t& key =
          is_participant ? static_cast<dds_builtintopic_participant_t*>(samples[i])->key
                         : static_cast<dds_builtintopic_endpoint_t*>(samples[i])->participant_key;
      if (std::equal(std::begin(key.v), std::end(key.v), std::begin(own_.v))) continue;
      ++count;
    }
    if (n > 0) dds_return_loan(reader, samples.data(), n);
    return count;
  }

  dds_entity_t participant_ = 0, participants_ = 0, writers_ = 0, readers_ = 0;
  dds_guid_t own_{};
};

// ---- The pipeline -----------------------------------------------------------

struct Setup {
  fs::path dir, report, config, log, record;
  std::string pipeline;
  int domain = 0;
  std::uint16_t port = 0;
  std::vector<fs::path> worlds;
  std::vector<std::string> names;
};

std::uint16_t free_port() {
  namespace net = boost::asio;
  net::io_context ioc;
  net::ip::tcp::acceptor a(ioc, {net::ip::make_address("127.0.0.1"), 0});
  return a.local_endpoint().port();
}

// The pipeline: `planner` its planner's plug-in; `soak`: DDS, the monitor,
// trailers without end; otherwise the first `trailers` once.
std::string config_text(const Setup& s, const std::string& planner, bool soak,
                        std::size_t trailers) {
  std::string list;
  for (std::size_t i = 0; i < trailers; ++i)
    list += fmt::format("{}{{world_file: \"{}\"}}", i ? ", " : "", s.worlds[i].string());
  std::string text =
      fmt::format(R"(pipeline: {}
hosts:
  sim: {{restart: on-failure}}
nodes:
  simulator:
    plugin: simulator_simbody
    host: sim
    params: {{checkpoint_dir: "${{report_dir}}/checkpoint"}}
  planner:
    plugin: {}
  strategy:
    plugin: strategy_hardcoded
  executor:
    plugin: strategy_executor
    params:
      trailers: [{}]
      cycles: {}
      report_dir: ${{report_dir}}
      progress: false
)",
                  s.pipeline + (soak ? "" : "_baseline"), planner, list, soak ? 0 : 1);
  if (soak)
    text += fmt::format(R"(  monitor:
    plugin: monitor_web
    params: {{port: {}}}
remote:
  dds: {{domain: {}, interfaces: [lo], export: ["executor/status", "progress"]}}
)",
                        s.port, s.domain);
  return text;
}

pid_t start_run(const Setup& s, const fs::path& config, const fs::path& log, bool record) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    ::prctl(PR_SET_PDEATHSIG, SIGTERM);  // a bench that dies stops its run
    // What plr says before its --log is open (a refused option) lands here.
    const fs::path early = log.string() + ".early";
    const int fd = ::open(early.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    ::dup2(fd, 2);
    ::dup2(fd, 1);
    std::vector<std::string> argv = {PLR_BIN,           "run",   config.string(), "--report",
                                     s.report.string(), "--log", log.string()};
    if (record) {
      argv.insert(argv.end(), {"--record", s.record.string(), "--record-topics",
                               "executor/status,progress,pipeline/*"});
    }
    std::vector<char*> args;
    for (auto& a : argv) args.push_back(a.data());
    args.push_back(nullptr);
    ::execv(PLR_BIN, args.data());
    ::_exit(127);
  }
  return pid;
}

// Messages on executor/state so far (one per step the executor starts);
// -1 when the pipeline does not answer.
long executor_steps(const std::string& pipeline) {
  std::string out;
  if (run_tool({PLR_BIN, "status", "--pipeline", pipeline}, &out) != 0) return -1;
  const auto status = json::parse(out, nullptr, false);
  if (!status.is_object()) return -1;
  for (const auto& t : status.value("topics", json::array()))
    if (t.value("name", "") == "executor/state") return t.value("messages", -1L);
  return -1;
}

json read_report(const fs::path& report) {
  const auto j = json::parse(read_file(report / "report.json"), nullptr, false);
  return j.is_object() ? j : json::object();
}

// ---- Faults -----------------------------------------------------------------

enum class Kind { kKillSim, kSwap, kSighup, kDdsMonitor, kShmFull, kReadOnly };
constexpr Kind kKinds[] = {Kind::kKillSim,    Kind::kSwap,    Kind::kSighup,
                           Kind::kDdsMonitor, Kind::kShmFull, Kind::kReadOnly};

const char* name(Kind k) {
  switch (k) {
    case Kind::kKillSim:
      return "kill_sim";
    case Kind::kSwap:
      return "swap";
    case Kind::kSighup:
      return "sighup";
    case Kind::kDdsMonitor:
      return "dds_monitor";
    case Kind::kShmFull:
      return "shm_full";
    case Kind::kReadOnly:
      return "read_only";
  }
  return "?";
}

struct FaultRecord {
  double at_s = 0;
  Kind kind{};
  bool injected = false;
  std::optional<bool> survived;  // decided once the executor moved on, or not
  std::string detail;
  long steps_before = 0;
  std::optional<pid_t> old_sim;
};

// Remounts the bind mount `dir` read-only or writable; a file open for
// writing on it makes the kernel refuse (EBUSY): tried again a while.
bool remount(const fs::path& dir, bool read_only) {
  for (int i = 0; i < 500; ++i) {
    if (::mount(nullptr, dir.c_str(), nullptr, MS_REMOUNT | MS_BIND | (read_only ? MS_RDONLY : 0),
                nullptr) == 0)
      return true;
    if (errno != EBUSY) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return false;
}

std::size_t count_in(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// ---- The clients of the web monitor -------------------------------------------

struct Clients {
  std::atomic<int> page_ok{0}, page_failed{0}, fox_ok{0}, fox_failed{0};
  std::atomic<bool> stop{false};

  void page(std::uint16_t port) {
    const auto r = plr::monitor_web::testing::http_get(port, "/state.json");
    (r.status == 200 && json::accept(r.body) ? page_ok : page_failed)++;
  }

  // Connects, subscribes to every channel it is told of, reads a few
  // messages, leaves.
  void foxglove(std::uint16_t port) {
    try {
      plr::monitor_web::testing::WsClient ws("127.0.0.1", port, "/", "foxglove.websocket.v1");
      int subscribed = 0, data = 0;
      for (int i = 0; i < 40 && data < 5; ++i) {
        const auto f = ws.read();
        if (!f) break;
        if (f->binary) {
          ++data;
          continue;
        }
        const auto m = json::parse(f->data, nullptr, false);
        if (!m.is_object() || m.value("op", "") != "advertise") continue;
        json subs = json::array();
        for (const auto& c : m.value("channels", json::array()))
          subs.push_back({{"id", ++subscribed}, {"channelId", c.value("id", 0)}});
        ws.send_text(json{{"op", "subscribe"}, {"subscriptions", subs}}.dump());
      }
      (subscribed > 0 ? fox_ok : fox_failed)++;
    } catch (const std::exception&) {
      fox_failed++;
    }
  }
};

// ---- Samples and growth -------------------------------------------------------

struct Sample {
  double t_s = 0;
  std::vector<Proc> procs;
  double rss_mib = 0;
  double anon_mib = 0;
  int fds = 0;
  double shm_mib = 0;
  int dds = 0;
  double checkpoint_kib = 0;
  double log_kib = 0;
  int trailers = 0;
  long boxes = 0;
  int faults = 0, survived = 0;
};

// Least-squares slope per hour of `value` over the samples from `from_s`
// on, as a fraction of their mean; null with fewer than 3.
json growth(const std::vector<Sample>& samples, double from_s, double (*value)(const Sample&)) {
  std::vector<std::pair<double, double>> xy;
  for (const auto& s : samples)
    if (s.t_s >= from_s) xy.push_back({s.t_s / 3600.0, value(s)});
  if (xy.size() < 3) return nullptr;
  double mx = 0, my = 0;
  for (auto [x, y] : xy) mx += x, my += y;
  mx /= xy.size(), my /= xy.size();
  double sxy = 0, sxx = 0;
  for (auto [x, y] : xy) sxy += (x - mx) * (y - my), sxx += (x - mx) * (x - mx);
  if (sxx <= 0 || my == 0) return 0.0;
  return sxy / sxx / my;
}

// The checkpoint's growth, from same-state sizes: each trailer's start
// checkpoint (as the simulator reported the folder's bytes once written)
// over the same world's first start, fitted against the time the trailer
// finished. A sampled folder size follows the boxes left at the moment and
// says nothing about growth. Null with fewer than 3 trailers after the first.
json checkpoint_growth(const json& trailers, const std::vector<double>& finished_s) {
  std::map<std::string, double> first;
  std::vector<Sample> points;
  for (std::size_t i = 0; i < trailers.size() && i < finished_s.size(); ++i) {
    const double bytes = trailers[i].value("start_checkpoint_bytes", 0.0);
    if (bytes <= 0) continue;
    const double same_start = first.emplace(trailers[i].value("name", ""), bytes).first->second;
    if (i == 0) continue;
    Sample p;
    p.t_s = finished_s[i];
    p.checkpoint_kib = bytes / same_start;
    points.push_back(p);
  }
  return growth(points, 0, [](const Sample& x) { return x.checkpoint_kib; });
}

std::string procs_text(const std::vector<Proc>& procs) {
  std::map<std::string, std::pair<double, int>> by;
  for (const auto& p : procs) {
    by[p.label].first += p.rss_mib;
    by[p.label].second += p.fds;
  }
  std::string out;
  for (const auto& [label, v] : by)
    out += fmt::format("{}{} {:.0f}M/{}", out.empty() ? "" : ", ", label, v.first, v.second);
  return out;
}

double load_average() {
  double l = 0;
  std::ifstream("/proc/loadavg") >> l;
  return l;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"A soak of the robot pipeline under faults (issue 50)"};
  double minutes = 120;
  bool quick = false, json_out = false;
  std::uint64_t seed = 1;
  double depth = 4.0;
  std::string keep;
  double fault_min_s = 30, fault_max_s = 90;
  app.add_option("--minutes", minutes, "Wall time of the soak")->capture_default_str();
  plr::bench::add_quick_flag(app, quick, "10 minutes, a table row every 2 minutes");
  plr::bench::add_json_flag(app, json_out);
  app.add_option("--seed", seed, "Seed of the fault schedule and the trailers")
      ->capture_default_str();
  app.add_option("--depth", depth, "Depth of the trailers, m")->capture_default_str();
  app.add_option("--fault-min", fault_min_s, "Shortest time between faults, s")
      ->capture_default_str();
  app.add_option("--fault-max", fault_max_s, "Longest time between faults, s")
      ->capture_default_str();
  app.add_option("--keep", keep, "Keep the run's folder here (log, report, recording)");
  plr::bench::parse_or_exit(app, argc, argv);
  if (quick) minutes = 10;
  const double row_every_s = minutes < 20 ? (minutes <= 10 ? 120 : 300) / (quick ? 1 : 2) : 600;

  if (::geteuid() != 0) {
    std::fprintf(stderr,
                 "bench_soak: needs root (a mount namespace of its own for /dev/shm "
                 "and the read-only report folder)\n");
    return 2;
  }
  if (::unshare(CLONE_NEWNS) != 0 ||
      ::mount(nullptr, "/", nullptr, MS_REC | MS_PRIVATE, nullptr) != 0) {
    std::perror("bench_soak: mount namespace");
    return 2;
  }

  Setup s;
  {
    std::string pattern = (fs::temp_directory_path() / "plr_soak_XXXXXX").string();
    s.dir = ::mkdtemp(pattern.data());
  }
  s.report = s.dir / "report";
  s.config = s.dir / "soak.yaml";
  s.log = s.dir / "plr_run.log";
  s.record = s.dir / "run.mcap";
  s.pipeline = fmt::format("plr_soak_{}", ::getpid());
  s.domain = 150 + static_cast<int>(::getpid() % 80);
  s.port = free_port();
  fs::create_directories(s.report);

  // Mixed families, small trailers: one of each family the generator can
  // fit in `depth`, with seeds from --seed.
  {
    plr::sim::Trailer trailer;
    trailer.depth = depth;
    std::uint64_t k = 0;
    for (EnvFamily f : {EnvFamily::kB1, EnvFamily::kD1, EnvFamily::kA2, EnvFamily::kB2,
                        EnvFamily::kC, EnvFamily::kA1}) {
      const std::uint64_t world_seed = seed * 100 + ++k;
      try {
        const auto w = plr::sim::generate_world(f, world_seed, trailer);
        const std::string n = fmt::format("{}_{}", plr::sim::to_string(f), world_seed);
        const fs::path file = s.dir / (n + ".yaml");
        if (auto ok = plr::sim::save_world(w, file); !ok)
          throw std::runtime_error(ok.error().message);
        s.worlds.push_back(file);
        s.names.push_back(fmt::format("{} ({} boxes)", n, w.boxes.size()));
      } catch (const std::invalid_argument& e) {
        std::fprintf(stderr, "bench_soak: no %s trailer %.1f m deep: %s\n",
                     std::string(plr::sim::to_string(f)).c_str(), depth, e.what());
      }
    }
  }
  if (s.worlds.empty()) return 2;

  std::string planner = "planner_arastar";
  write_file(s.config, config_text(s, planner, true, s.worlds.size()));

  // /dev/shm of our own: the run's need and 64 MiB.
  std::uint64_t need = 0;
  {
    std::string out;
    run_tool({PLR_BIN, "validate", s.config.string()}, &out);
    const auto at = out.find("MiB (");
    if (at != std::string::npos) need = std::stoull(out.substr(at + 5));
    if (need == 0) {
      std::fprintf(stderr, "bench_soak: plr validate printed no /dev/shm need:\n%s", out.c_str());
      return 2;
    }
    const std::string opts = fmt::format("size={},mode=1777", need + (64ull << 20));
    if (::mount("tmpfs", "/dev/shm", "tmpfs", MS_NOSUID | MS_NODEV, opts.c_str()) != 0 ||
        ::mount(s.report.c_str(), s.report.c_str(), nullptr, MS_BIND, nullptr) != 0) {
      std::perror("bench_soak: mounts");
      return 2;
    }
  }

  std::mt19937_64 rng(seed);
  DdsCount dds(s.domain);
  std::fprintf(stderr, "bench_soak: %s, %.0f min, trailers:", s.dir.c_str(), minutes);
  for (const auto& n : s.names) std::fprintf(stderr, " %s", n.c_str());
  std::fprintf(stderr, "\n");

  const auto t0 = Clock::now();
  const pid_t run = start_run(s, s.config, s.log, true);
  Clients clients;
  std::thread client_thread([&] {
    std::this_thread::sleep_for(std::chrono::seconds(10));  // the monitor starts listening
    for (int i = 0; !clients.stop; ++i) {
      std::this_thread::sleep_for(std::chrono::seconds(5));
      if (clients.stop) break;
      if (i % 2 == 0)
        clients.page(s.port);
      else
        clients.foxglove(s.port);
    }
  });

  std::vector<Sample> samples;
  std::vector<FaultRecord> faults;
  std::vector<Kind> round;
  double next_fault_s = std::uniform_real_distribution<double>(fault_min_s, fault_max_s)(rng);
  int events = 0;
  double first_trailer_s = -1;
  std::vector<double> finished_s;  // when each trailer was first seen in the report
  double next_row_s = 0;
  int run_status = -1;
  std::string ended;
  long steps = 0;

  const auto take_sample = [&] {
    Sample x;
    x.t_s = since(t0);
    x.procs = processes(run);
    for (const auto& p : x.procs) x.rss_mib += p.rss_mib, x.anon_mib += p.anon_mib, x.fds += p.fds;
    x.shm_mib = folder_bytes("/dev/shm", "plr_soak_filler") / 1048576.0;
    x.dds = dds.count();
    x.checkpoint_kib = folder_bytes(s.report / "checkpoint") / 1024.0;
    x.log_kib = (log_bytes(s.log) + record_bytes(s.record) + folder_bytes(s.report)) / 1024.0;
    const json r = read_report(s.report);
    for (const auto& t : r.value("trailers", json::array())) {
      ++x.trailers;
      x.boxes += t.value("boxes_unloaded", 0);
    }
    while (finished_s.size() < static_cast<std::size_t>(x.trailers)) finished_s.push_back(x.t_s);
    for (const auto& f : faults) x.faults += f.injected, x.survived += f.survived.value_or(false);
    if (x.trailers > 0 && first_trailer_s < 0) first_trailer_s = x.t_s;
    samples.push_back(x);
    if (x.t_s >= next_row_s) {
      next_row_s += row_every_s;
      std::fprintf(
          stderr,
          "%6.1f min  trailers %d  boxes %ld  faults %d/%d  rss %.0f MiB  fds %d  shm %.1f "
          "MiB  dds %d  ckpt %.0f KiB  logs %.0f KiB  [%s]  load %.1f\n",
          x.t_s / 60, x.trailers, x.boxes, x.survived, x.faults, x.rss_mib, x.fds, x.shm_mib, x.dds,
          x.checkpoint_kib, x.log_kib, procs_text(x.procs).c_str(), load_average());
    }
  };

  const auto alive = [&] {
    if (run_status >= 0) return false;
    int st = 0;
    if (::waitpid(run, &st, WNOHANG) == run) {
      run_status = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
      ended = fmt::format("plr run ended by itself at {:.0f} s, exit {}", since(t0), run_status);
      return false;
    }
    return true;
  };

  const auto inject = [&](Kind k) {
    FaultRecord f;
    f.at_s = since(t0);
    f.kind = k;
    f.steps_before = steps;
    f.old_sim = host_pid(run, "sim");
    const std::string other = planner == "planner_arastar" ? "planner_ompl" : "planner_arastar";
    switch (k) {
      case Kind::kKillSim:
        f.injected = f.old_sim && ::kill(*f.old_sim, SIGKILL) == 0;
        f.detail = f.injected ? fmt::format("killed pid {}", *f.old_sim) : "no simulator host";
        break;
      case Kind::kSwap: {
        const int rc = run_tool({PLR_BIN, "swap", "planner", other, "--pipeline", s.pipeline});
        f.injected = true;
        if (rc == 0) planner = other;
        f.detail = fmt::format("to {}: exit {}", other, rc);
        if (rc != 0) f.survived = false;
        break;
      }
      case Kind::kSighup:
        write_file(s.config, config_text(s, other, true, s.worlds.size()));
        f.injected = ::kill(run, SIGHUP) == 0;
        planner = other;
        f.detail = "reload to " + other;
        break;
      case Kind::kDdsMonitor: {
        std::string out;
        const int rc = run_tool({PLR_BIN, "monitor", "--domain", std::to_string(s.domain), "--once",
                                 "--json", "--wait", "30"},
                                &out);
        f.injected = true;
        const auto m = json::parse(out, nullptr, false);
        int ours = 0;
        if (m.is_object())
          for (const auto& kernel : m.value("kernels", json::array()))
            ours += kernel.dump().find(s.pipeline) != std::string::npos;
        f.detail = fmt::format("exit {}, saw our kernel {} time(s)", rc, ours);
        if (rc != 0 || ours == 0) f.survived = false;
        break;
      }
      case Kind::kShmFull: {
        // Fill what is left, then take the simulator's host down; free the
        // room as soon as its restart was refused (the log says so), before
        // the supervisor's window of crashes runs out.
        const int fd = ::open("/dev/shm/plr_soak_filler", O_RDWR | O_CREAT | O_TRUNC, 0600);
        struct statvfs v {};
        ::statvfs("/dev/shm", &v);
        off_t size = static_cast<off_t>(v.f_bavail) * static_cast<off_t>(v.f_frsize);
        ::posix_fallocate(fd, 0, size);
        ::close(fd);
        ::statvfs("/dev/shm", &v);
        const std::size_t before = count_in(read_file(s.log), "no room in /dev/shm");
        f.injected = f.old_sim && ::kill(*f.old_sim, SIGKILL) == 0;
        bool refused = false;
        const auto until = Clock::now() + std::chrono::seconds(60);
        while (f.injected && Clock::now() < until && alive()) {
          if (count_in(read_file(s.log), "no room in /dev/shm") > before) {
            refused = true;
            break;
          }
          const auto now_sim = host_pid(run, "sim");
          if (now_sim && now_sim != f.old_sim && since(t0) - f.at_s > 20) break;
          std::this_thread::sleep_for(std::chrono::milliseconds(20));
        }
        ::unlink("/dev/shm/plr_soak_filler");
        f.detail =
            fmt::format("{} B left free, restart {}", v.f_bavail * v.f_frsize,
                        refused ? "refused (no room in /dev/shm), room given back" : "not refused");
        if (!refused) f.injected = false;
        break;
      }
      case Kind::kReadOnly: {
        const double hold_s = quick ? 15 : 30;
        f.injected = remount(s.report, true);
        if (f.injected) {
          std::this_thread::sleep_for(std::chrono::duration<double>(hold_s));
          if (!remount(s.report, false)) f.detail = "could not make it writable again!";
        }
        f.detail += fmt::format("read-only for {:.0f} s{}", hold_s, f.injected ? "" : ": refused");
        break;
      }
    }
    faults.push_back(f);
  };

  while (since(t0) < minutes * 60 && alive()) {
    take_sample();
    if (const long n = executor_steps(s.pipeline); n >= 0) steps = n;
    // Decide the faults whose fate is open.
    const auto sim_now = host_pid(run, "sim");
    for (auto& f : faults) {
      if (f.survived || !f.injected) continue;
      const bool back = !(f.kind == Kind::kKillSim || f.kind == Kind::kShmFull) ||
                        (sim_now && sim_now != f.old_sim);
      if (back && steps > f.steps_before) f.survived = true;
    }
    const bool open = std::any_of(faults.begin(), faults.end(), [&](const FaultRecord& f) {
      return f.injected && !f.survived && since(t0) - f.at_s < 300;
    });
    // None in the last minute: its fate would be left open.
    if (since(t0) >= next_fault_s && since(t0) < minutes * 60 - 60 && !open) {
      if (round.empty()) {
        round.assign(std::begin(kKinds), std::end(kKinds));
        std::shuffle(round.begin(), round.end(), rng);
      }
      const Kind k = round.back();
      round.pop_back();
      inject(k);
      // Every fourth event: two faults at once.
      if (++events % 4 == 0) {
        if (round.empty()) {
          round.assign(std::begin(kKinds), std::end(kKinds));
          std::shuffle(round.begin(), round.end(), rng);
        }
        inject(round.back());
        round.pop_back();
      }
      next_fault_s =
          since(t0) + std::uniform_real_distribution<double>(fault_min_s, fault_max_s)(rng);
    }
    std::this_thread::sleep_for(std::chrono::seconds(5));
  }
  // A fault still open at the end: not survived if the run ended by
  // itself; undecided if it still ran but had not moved on since.
  if (run_status >= 0)
    for (auto& f : faults)
      if (f.injected && !f.survived) f.survived = false;
  clients.stop = true;
  client_thread.join();
  take_sample();
  remount(s.report, false);
  if (run_status < 0) {
    ::kill(run, SIGTERM);
    int st = 0;
    ::waitpid(run, &st, 0);
    run_status = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
    ended =
        fmt::format("stopped with SIGTERM after {:.1f} min, exit {}", since(t0) / 60, run_status);
  }
  const json report = read_report(s.report);
  const json trailers = report.value("trailers", json::array());

  // The same trailers without faults: each the soak finished, once.
  const std::size_t distinct = std::min(trailers.size(), s.worlds.size());
  std::vector<int> baseline;
  if (distinct > 0) {
    std::fprintf(stderr, "bench_soak: the same %zu trailers without faults...\n", distinct);
    const fs::path config = s.dir / "baseline.yaml", log = s.dir / "baseline.log";
    write_file(config, config_text(s, "planner_arastar", false, distinct));
    fs::remove_all(s.report / "checkpoint");
    const pid_t b = start_run(s, config, log, false);
    int st = 0;
    ::waitpid(b, &st, 0);
    const json r = read_report(s.report);
    for (const auto& t : r.value("trailers", json::array()))
      baseline.push_back(t.value("boxes_unloaded", 0));
    if (baseline.size() != distinct)
      std::fprintf(stderr, "bench_soak: the baseline run finished %zu of %zu trailers (exit %d)\n",
                   baseline.size(), distinct, WIFEXITED(st) ? WEXITSTATUS(st) : -1);
  }

  // Lost: plan queries no planner answered, boxes the simulator unloaded
  // that the executor did not count, boxes that vanished. Doubled: boxes
  // the executor counted that the simulator did not unload.
  long boxes = 0, without = 0, lost = 0, doubled = 0;
  json per_trailer = json::array();
  for (std::size_t i = 0; i < trailers.size(); ++i) {
    const auto& t = trailers[i];
    const long total = t.value("boxes_total", 0), counted = t.value("boxes_unloaded", 0),
               sim_out = t.value("sim_boxes_unloaded", 0), left = t.value("sim_boxes_left", 0);
    boxes += counted;
    const long base = i % s.worlds.size() < baseline.size() ? baseline[i % s.worlds.size()] : -1;
    if (base >= 0) without += base;
    lost += t.value("plan_calls_unanswered", 0L) + std::max(0L, sim_out - counted) +
            std::max(0L, total - sim_out - left);
    doubled += std::max(0L, counted - sim_out) + std::max(0L, sim_out + left - total);
    per_trailer.push_back({{"name", t.value("name", "")},
                           {"boxes_total", total},
                           {"boxes_unloaded", counted},
                           {"without_faults", base},
                           {"sim_boxes_unloaded", sim_out},
                           {"sim_boxes_left", left},
                           {"recoveries", t.value("recoveries", 0)},
                           {"stop_reason", t.value("stop_reason", "")}});
  }
  int injected = 0, survived = 0, undecided = 0;
  json fault_list = json::array();
  std::map<std::string, std::pair<int, int>> by_kind;
  for (const auto& f : faults) {
    injected += f.injected;
    survived += f.injected && f.survived.value_or(false);
    undecided += f.injected && !f.survived;
    if (f.injected) {
      by_kind[name(f.kind)].first++;
      by_kind[name(f.kind)].second += f.survived.value_or(false);
    }
    fault_list.push_back({{"at_s", std::round(f.at_s)},
                          {"kind", name(f.kind)},
                          {"injected", f.injected},
                          {"survived", f.survived ? json(*f.survived) : json()},
                          {"detail", f.detail}});
  }
  const double from = first_trailer_s >= 0 ? first_trailer_s : 1e18;
  json grow = {
      {"rss", growth(samples, from, [](const Sample& x) { return x.rss_mib; })},
      {"rss_anon", growth(samples, from, [](const Sample& x) { return x.anon_mib; })},
      {"fds", growth(samples, from, [](const Sample& x) { return double(x.fds); })},
      {"shm", growth(samples, from, [](const Sample& x) { return x.shm_mib; })},
      {"dds_entities", growth(samples, from, [](const Sample& x) { return double(x.dds); })},
      {"checkpoint", checkpoint_growth(trailers, finished_s)},
      {"log", growth(samples, from, [](const Sample& x) { return x.log_kib; })}};
  // Logs grow with the run (the stderr log, the recording, the report):
  // their rate, KiB per hour, after the first trailer.
  json log_rate = nullptr;
  {
    const Sample* a = nullptr;
    for (const auto& x : samples)
      if (x.t_s >= from && !a) a = &x;
    const Sample& b = samples.back();
    if (a && b.t_s > a->t_s) log_rate = (b.log_kib - a->log_kib) / (b.t_s - a->t_s) * 3600;
  }
  json rows = json::array();
  double next = 0;
  for (const auto& x : samples) {
    if (x.t_s < next && &x != &samples.back()) continue;
    next += row_every_s;
    json procs = json::array();
    for (const auto& p : x.procs)
      procs.push_back(
          {{"label", p.label}, {"rss_mib", p.rss_mib}, {"anon_mib", p.anon_mib}, {"fds", p.fds}});
    rows.push_back({{"min", x.t_s / 60},
                    {"trailers", x.trailers},
                    {"boxes", x.boxes},
                    {"faults", x.faults},
                    {"rss_mib", x.rss_mib},
                    {"rss_anon_mib", x.anon_mib},
                    {"fds", x.fds},
                    {"shm_mib", x.shm_mib},
                    {"dds_entities", x.dds},
                    {"checkpoint_kib", x.checkpoint_kib},
                    {"log_kib", x.log_kib},
                    {"processes", procs}});
  }
  const json out = {
      {"minutes", minutes},
      {"seed", seed},
      {"trailers", trailers.size()},
      {"boxes", boxes},
      {"boxes_without_faults", without},
      {"lost", lost},
      {"doubled", doubled},
      {"faults_injected", injected},
      {"faults_survived", survived},
      {"faults_undecided", undecided},
      {"log_kib_per_hour", log_rate},
      {"growth_per_hour", grow},
      {"ended", ended},
      {"exit", run_status},
      {"clients",
       {{"page", {{"ok", clients.page_ok.load()}, {"failed", clients.page_failed.load()}}},
        {"foxglove", {{"ok", clients.fox_ok.load()}, {"failed", clients.fox_failed.load()}}}}},
      {"load_average", load_average()},
      {"per_trailer", per_trailer},
      {"faults", fault_list},
      {"rows", rows}};
  if (json_out) {
    std::printf("%s\n", out.dump().c_str());
  } else {
    std::printf("Soak: %.0f min (seed %llu), %s\n", minutes, static_cast<unsigned long long>(seed),
                ended.c_str());
    std::printf(
        "\n| min | trailers | boxes | faults | RSS MiB (anon) | fds | /dev/shm MiB | DDS entities "
        "| "
        "checkpoint KiB | logs KiB | per process (RSS/fds) "
        "|\n|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (const auto& r : rows) {
      std::vector<Proc> procs;
      for (const auto& p : r["processes"])
        procs.push_back({0, p["label"].get<std::string>(), p["rss_mib"].get<double>(),
                         p["anon_mib"].get<double>(), p["fds"].get<int>()});
      std::printf("| %.1f | %d | %ld | %d | %.0f (%.0f) | %d | %.1f | %d | %.0f | %.0f | %s |\n",
                  r["min"].get<double>(), r["trailers"].get<int>(), r["boxes"].get<long>(),
                  r["faults"].get<int>(), r["rss_mib"].get<double>(),
                  r["rss_anon_mib"].get<double>(), r["fds"].get<int>(), r["shm_mib"].get<double>(),
                  r["dds_entities"].get<int>(), r["checkpoint_kib"].get<double>(),
                  r["log_kib"].get<double>(), procs_text(procs).c_str());
    }
    std::printf(
        "\n| trailer | boxes | without faults | simulator: out / left | recoveries |\n"
        "|---|---|---|---|---|\n");
    for (const auto& t : per_trailer)
      std::printf("| %s | %ld/%ld | %ld | %ld / %ld | %d |\n", t["name"].get<std::string>().c_str(),
                  t["boxes_unloaded"].get<long>(), t["boxes_total"].get<long>(),
                  t["without_faults"].get<long>(), t["sim_boxes_unloaded"].get<long>(),
                  t["sim_boxes_left"].get<long>(), t["recoveries"].get<int>());
    std::printf("\nfaults survived / injected: %d / %d, %d undecided at the end (", survived,
                injected, undecided);
    bool first = true;
    for (const auto& [k, v] : by_kind) {
      std::printf("%s%s %d/%d", first ? "" : ", ", k.c_str(), v.second, v.first);
      first = false;
    }
    std::printf(")\ntrailers %zu, boxes %ld, without faults %ld, lost %ld, doubled %ld\n",
                trailers.size(), boxes, without, lost, doubled);
    std::printf("page client %d ok / %d failed, Foxglove client %d ok / %d failed\n",
                clients.page_ok.load(), clients.page_failed.load(), clients.fox_ok.load(),
                clients.fox_failed.load());
    std::printf("growth per hour after the first trailer:");
    for (const auto& [k, v] : grow.items())
      std::printf(" %s %s", k.c_str(),
                  v.is_null() ? "n/a" : fmt::format("{:+.2f} %", 100 * v.get<double>()).c_str());
    std::printf("\nlogs (stderr, recording, report): %s KiB per hour\n",
                log_rate.is_null() ? "n/a" : fmt::format("{:.0f}", log_rate.get<double>()).c_str());
    std::printf("load average at the end: %.1f (2 cores)\n", load_average());
    for (const auto& f : fault_list)
      std::printf("  %5.0f s %-11s %s%s\n", f["at_s"].get<double>(),
                  f["kind"].get<std::string>().c_str(),
                  !f["injected"].get<bool>()  ? "not injected: "
                  : f["survived"].is_null()   ? "undecided: "
                  : f["survived"].get<bool>() ? "survived: "
                                              : "NOT survived: ",
                  f["detail"].get<std::string>().c_str());
  }
  ::umount(s.report.c_str());
  if (!keep.empty()) {
    fs::create_directories(keep);
    fs::copy(s.dir, keep, fs::copy_options::recursive | fs::copy_options::overwrite_existing);
  }
  fs::remove_all(s.dir);
  return 0;
}
