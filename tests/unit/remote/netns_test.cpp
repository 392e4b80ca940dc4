// Kernels on "different machines": network namespaces A and B, each joined
// by a veth pair to a bridge in the root namespace (so a monitor there sees
// both). Shows a topic and a service crossing over Cyclone DDS, a service
// with providers on both sides losing one mid-run (its pending call fails at
// once, the rest go to the other), `plr monitor --once --json` seeing both
// kernels, and a remote swap refused without permission. Where namespaces
// are not permitted the same scenario runs on loopback, and says so.
#include <plr/expected.hpp>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fcntl.h>
#include <sched.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace {

using namespace std::chrono_literals;

const std::string kPlr = PLR_BINARY;

int sh(const std::string& command, std::string* out = nullptr) {
  FILE* p = ::popen((command + " 2>&1").c_str(), "r");
  if (!p) return -1;
  char buf[4096];
  std::size_t n = 0;
  std::string sink;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) (out ? out : &sink)->append(buf, n);
  const int status = ::pclose(p);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

std::string slurp(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// A process started as `argv` (in network namespace `ns` unless empty) with
// stdout and stderr to `log`. Joined here rather than by `ip netns exec`,
// which forks: the pid must be plr's own, to stop and kill it.
struct Proc {
  pid_t pid = -1;
  std::string log;
  Proc(const std::string& ns, const std::vector<std::string>& argv, std::string log_path)
      : log(std::move(log_path)) {
    pid = ::fork();
    if (pid == 0) {
      if (!ns.empty()) {
        const int nsfd = ::open(("/run/netns/" + ns).c_str(), O_RDONLY | O_CLOEXEC);
        if (nsfd < 0 || ::setns(nsfd, CLONE_NEWNET) != 0) ::_exit(126);
      }
      const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
      ::dup2(fd, 1);
      ::dup2(fd, 2);
      std::vector<char*> args;
      for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
      args.push_back(nullptr);
      ::execvp(args[0], args.data());
      ::_exit(127);
    }
  }
  // Exit code, or -1 when it did not end within `timeout`.
  int wait(std::chrono::milliseconds timeout) {
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (std::chrono::steady_clock::now() < end) {
      int status = 0;
      if (::waitpid(pid, &status, WNOHANG) == pid) {
        pid = -1;
        return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
      }
      std::this_thread::sleep_for(20ms);
    }
    return -1;
  }
  // A clean stop first, so the kernel removes its control socket.
  ~Proc() {
    if (pid <= 0) return;
    ::kill(pid, SIGTERM);
    ::kill(pid, SIGCONT);
    if (wait(5s) == -1) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, nullptr, 0);
    }
  }
};

// Namespaces A and B on a bridge; removed again at the end.
struct Net {
  bool isolated = false;
  std::string why_not;
  std::string ns_a, ns_b, bridge;
  std::string iface = "lo";       // the kernels' interface
  std::string root_iface = "lo";  // the monitor's

  Net() {
    const auto tag = std::to_string(::getpid() % 100000);
    ns_a = "plra" + tag;
    ns_b = "plrb" + tag;
    bridge = "plrbr" + tag;
    std::string out;
    if (sh("ip netns add " + ns_a, &out) != 0) {
      why_not = out;
      return;
    }
    const std::vector<std::string> steps = {
        "ip netns add " + ns_b,
        "ip link add " + bridge + " type bridge mcast_snooping 0",
        "ip addr add 10.77.0.254/24 dev " + bridge,
        "ip link set " + bridge + " up",
        setup(ns_a, "a" + tag, "10.77.0.1"),
        setup(ns_b, "b" + tag, "10.77.0.2"),
    };
    for (const auto& s : steps) {
      out.clear();
      if (sh(s, &out) != 0) {
        why_not = s + ": " + out;
        return;
      }
    }
    isolated = true;
    iface = "plr0";
    root_iface = bridge;
  }
  static std::string setup(const std::string& ns, const std::string& veth,
                           const std::string& addr) {
    return "ip link add " + veth + " type veth peer name plr0 netns " + ns + " && ip link set " +
           veth + " master plrbr" + ns.substr(4) + " up && ip -n " + ns + " addr add " + addr +
           "/24 dev plr0 && ip -n " + ns + " link set plr0 up && ip -n " + ns + " link set lo up";
  }
  ~Net() {
    sh("ip netns del " + ns_a);
    sh("ip netns del " + ns_b);
    sh("ip link del " + bridge);
  }
  std::string in(const std::string& ns) const { return isolated ? ns : ""; }
};

std::string write_config(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path) << text;
  return path;
}

std::string dds_block(int domain, const std::string& iface, const std::string& exp,
                      const std::string& imp) {
  return "remote:\n  dds: {domain: " + std::to_string(domain) + ", interfaces: [" + iface +
         "], export: [" + exp + "], import: [" + imp + "]}\n";
}

nlohmann::json monitor_once(const Net& net, int domain, std::string* raw) {
  raw->clear();
  sh(kPlr + " monitor --once --json --wait 6 --domain " + std::to_string(domain) + " --interface " +
         net.root_iface + " 2>/dev/null",
     raw);
  return nlohmann::json::parse(*raw, nullptr, false);
}

const nlohmann::json* kernel_of(const nlohmann::json& doc, const std::string& pipeline) {
  if (!doc.is_object() || !doc.contains("kernels")) return nullptr;
  for (const auto& k : doc["kernels"])
    if (k.value("kernel", "").rfind(pipeline + "@", 0) == 0) return &k;
  return nullptr;
}

std::uint64_t topic_messages(const nlohmann::json& kernel, const std::string& topic) {
  for (const auto& t : kernel["telemetry"]["topics"])
    if (t.value("name", "") == topic) return t.value("messages", 0ull);
  return 0;
}

TEST(RemoteNetns, TopicAndServiceCrossProviderLossMonitorAndRefusedSwap) {
  Net net;
  if (net.isolated) {
    std::cout << "remote_netns: kernels in network namespaces " << net.ns_a << " and " << net.ns_b
              << " (veth pairs to bridge " << net.bridge << "), monitor in the root namespace\n";
  } else {
    std::cout << "remote_netns: NOTE network namespaces are not permitted here (" << net.why_not
              << "); running the same scenario on loopback in ONE namespace instead\n";
  }
  const int domain = 100 + ::getpid() % 100;
  const auto a = write_config("remote_a.yaml",
                              "pipeline: remote_a\nnodes:\n  doubler: {plugin: demo_doubler}\n" +
                                  dds_block(domain, net.iface, "double", "count"));
  const auto b1 = write_config(
      "remote_b1.yaml", "pipeline: remote_b_provider\nnodes:\n  doubler: {plugin: demo_doubler}\n" +
                            dds_block(domain, net.iface, "double", ""));
  const auto b2 =
      write_config("remote_b2.yaml",
                   "pipeline: remote_b_caller\nnodes:\n  counter: {plugin: demo_counter, params: "
                   "{period_ms: 20, limit: 200}}\n" +
                       dds_block(domain, net.iface, "count", "double"));
  const auto dir = ::testing::TempDir();

  Proc kernel_a(net.in(net.ns_a), {kPlr, "run", a, "--report", dir + "ra"}, dir + "remote_a.log");
  Proc kernel_b1(net.in(net.ns_b), {kPlr, "run", b1, "--report", dir + "rb1"},
                 dir + "remote_b1.log");

  // The monitor, from the root namespace, sees both kernels.
  std::string raw;
  nlohmann::json doc;
  for (int i = 0; i < 5; ++i) {
    doc = monitor_once(net, domain, &raw);
    if (kernel_of(doc, "remote_a") && kernel_of(doc, "remote_b_provider")) break;
  }
  ASSERT_TRUE(kernel_of(doc, "remote_a")) << raw << slurp(kernel_a.log);
  ASSERT_TRUE(kernel_of(doc, "remote_b_provider")) << raw << slurp(kernel_b1.log);
  EXPECT_EQ((*kernel_of(doc, "remote_a"))["telemetry"]["nodes"][0].value("plugin", ""),
            "demo_doubler");

  // Remote control is off: the swap is refused, and the kernel logs it.
  std::string swap_out;
  EXPECT_EQ(sh(kPlr + " swap --remote remote_a doubler demo_doubler --domain " +
                   std::to_string(domain) + " --interface " + net.root_iface,
               &swap_out),
            1)
      << swap_out;
  EXPECT_NE(swap_out.find("refuses remote control"), std::string::npos) << swap_out;

  // The caller in B: its calls are spread over A and B's provider.
  Proc caller(net.in(net.ns_b), {kPlr, "run", b2, "--report", dir + "rb2"}, dir + "remote_b2.log");
  // The count topic reaches A (its bus counts what the bridge injected).
  std::uint64_t counts_at_a = 0;
  for (int i = 0; i < 5 && counts_at_a <= 10; ++i) {
    doc = monitor_once(net, domain, &raw);
    if (const auto* ka = kernel_of(doc, "remote_a")) counts_at_a = topic_messages(*ka, "count");
  }
  EXPECT_GT(counts_at_a, 10u) << "the count topic did not reach A: " << raw;

  // A freezes mid-run: the call waiting on it fails at once (heartbeat), not
  // by the caller's 2 s timeout; later calls go to B's provider.
  ::kill(kernel_a.pid, SIGSTOP);
  const int rc = caller.wait(60s);
  const auto log = slurp(caller.log);
  EXPECT_EQ(rc, 0) << log;
  EXPECT_NE(slurp(kernel_a.log).find("refused remote command"), std::string::npos);

  static const std::regex ok(R"((\d+) doubled is (\d+))");
  int good = 0, wrong = 0;
  std::size_t last_good = 0;
  for (std::sregex_iterator it(log.begin(), log.end(), ok), end; it != end; ++it) {
    (std::stoll((*it)[2]) == 2 * std::stoll((*it)[1]) ? good : wrong)++;
    last_good = static_cast<std::size_t>(it->position());
  }
  const auto gone = log.find("failed: kernel 'remote_a@");
  EXPECT_EQ(wrong, 0);
  EXPECT_GE(good, 150) << log;
  // Before discovery calls are refused (no provider yet); after the first
  // answer, only the call caught on the frozen kernel fails.
  std::size_t failures_after_start = 0;
  for (auto at = log.find("failed:", log.find("doubled is")); at != std::string::npos;
       at = log.find("failed:", at + 1))
    ++failures_after_start;
  EXPECT_EQ(failures_after_start, 1u) << log;
  ASSERT_NE(gone, std::string::npos) << "no call failed when A froze:\n" << log;
  EXPECT_NE(log.find("is gone (silent for"), std::string::npos) << log;
  EXPECT_EQ(log.find("timed out"), std::string::npos) << log;
  EXPECT_GT(last_good, gone) << "no answers after A was lost";
}

}  // namespace
