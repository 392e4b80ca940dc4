// Kernels on "different machines": network namespaces A and B, each joined
// by a veth pair to a bridge in the root namespace (so a monitor there sees
// both). Shows a topic and a service crossing over Cyclone DDS; a service
// with providers on both sides losing one mid-run, seen by two callers: one
// whose policy is to fail (its pending call fails at once, naming the lost
// kernel) and one that declares the service idempotent (its pending call is
// re-sent to the other provider and completes); `plr monitor --once --json`
// seeing both kernels; a remote swap and pause refused without permission.
// Where namespaces are not permitted the same scenario runs on loopback, and
// says so.
#include "remote_fixture.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <iostream>
#include <regex>

namespace {

using namespace plr::remote_test;

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
  return write_file(::testing::TempDir() + name, text);
}

std::string dds_block(int domain, const std::string& iface, const std::string& exp,
                      const std::string& imp, const std::string& extra = "") {
  return "remote:\n  dds: {domain: " + std::to_string(domain) + ", interfaces: [" + iface +
         "], export: [" + exp + "], import: [" + imp + "]" + extra + "}\n";
}

struct CallerLog {
  int good = 0, wrong = 0;
  std::size_t last_good = 0;  // where the last answer is
  std::size_t failures_after_start = 0;
};

// What a demo_counter's log says about its `double` calls. Before discovery
// calls are refused (no provider yet); failures count from the first answer.
CallerLog read_caller(const std::string& log) {
  static const std::regex ok(R"((\d+) doubled is (\d+))");
  CallerLog c;
  for (std::sregex_iterator it(log.begin(), log.end(), ok), end; it != end; ++it) {
    (std::stoll((*it)[2]) == 2 * std::stoll((*it)[1]) ? c.good : c.wrong)++;
    c.last_good = static_cast<std::size_t>(it->position());
  }
  for (auto at = log.find("failed:", log.find("doubled is")); at != std::string::npos;
       at = log.find("failed:", at + 1))
    ++c.failures_after_start;
  return c;
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

TEST(RemoteNetns, TopicAndServiceCrossProviderLossMonitorAndRefusedControl) {
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
  const auto counter =
      "nodes:\n  counter: {plugin: demo_counter, params: {period_ms: 20, limit: 250}}\n";
  const auto b2 =
      write_config("remote_b2.yaml", std::string("pipeline: remote_b_caller\n") + counter +
                                         dds_block(domain, net.iface, "count", "double"));
  const auto b3 = write_config(
      "remote_b3.yaml",
      std::string("pipeline: remote_b_resend\n") + counter +
          dds_block(domain, net.iface, "", "double", ", resend_on_provider_loss: [double]"));
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

  // Remote control is off: a swap and a pause are refused, and the kernel logs them.
  for (const std::string command :
       {"swap --remote remote_a doubler demo_doubler", "pause --remote remote_a doubler"}) {
    std::string out;
    EXPECT_EQ(sh(kPlr + " " + command + " --domain " + std::to_string(domain) + " --interface " +
                     net.root_iface,
                 &out),
              1)
        << command << ": " << out;
    EXPECT_NE(out.find("refuses remote control"), std::string::npos) << command << ": " << out;
  }

  // Two callers in B: their calls are spread over A and B's provider.
  Proc caller(net.in(net.ns_b), {kPlr, "run", b2, "--report", dir + "rb2"}, dir + "remote_b2.log");
  Proc resender(net.in(net.ns_b), {kPlr, "run", b3, "--report", dir + "rb3"},
                dir + "remote_b3.log");
  // The count topic reaches A (its bus counts what the bridge injected).
  std::uint64_t counts_at_a = 0;
  for (int i = 0; i < 5 && counts_at_a <= 10; ++i) {
    doc = monitor_once(net, domain, &raw);
    if (const auto* ka = kernel_of(doc, "remote_a")) counts_at_a = topic_messages(*ka, "count");
  }
  EXPECT_GT(counts_at_a, 10u) << "the count topic did not reach A: " << raw;

  // A freezes mid-run: the call waiting on it is lost at once (heartbeat),
  // not by the callers' 2 s timeout. The fail caller sees it fail; the
  // resend caller's goes to B's provider. Later calls go to B's provider.
  ::kill(kernel_a.pid, SIGSTOP);
  const int rc = caller.wait(60s);
  const int resend_rc = resender.wait(30s);
  const auto log = slurp(caller.log);
  const auto resend_log = slurp(resender.log);
  EXPECT_EQ(rc, 0) << log;
  EXPECT_EQ(resend_rc, 0) << resend_log;
  const auto a_log = slurp(kernel_a.log);
  EXPECT_NE(a_log.find(R"(refused remote command {"cmd":"swap")"), std::string::npos) << a_log;
  EXPECT_NE(a_log.find(R"(refused remote command {"cmd":"pause")"), std::string::npos) << a_log;

  const auto fails = read_caller(log);
  const auto gone = log.find("failed: kernel 'remote_a@");
  EXPECT_EQ(fails.wrong, 0);
  EXPECT_GE(fails.good, 150) << log;
  // Only the call caught on the frozen kernel fails.
  EXPECT_EQ(fails.failures_after_start, 1u) << log;
  ASSERT_NE(gone, std::string::npos) << "no call failed when A froze:\n" << log;
  EXPECT_NE(log.find("is gone (silent for"), std::string::npos) << log;
  EXPECT_NE(log.find("the request was not re-sent"), std::string::npos) << log;
  EXPECT_EQ(log.find("timed out"), std::string::npos) << log;
  EXPECT_GT(fails.last_good, gone) << "no answers after A was lost";

  // The idempotent service: nothing fails, the lost call was re-sent and answered.
  const auto resent = read_caller(resend_log);
  const auto resend_at = resend_log.find("re-sent after losing kernel 'remote_a@");
  EXPECT_EQ(resent.wrong, 0);
  EXPECT_GE(resent.good, 150) << resend_log;
  EXPECT_EQ(resent.failures_after_start, 0u) << resend_log;
  ASSERT_NE(resend_at, std::string::npos) << "no call was re-sent when A froze:\n" << resend_log;
  EXPECT_GT(resent.last_good, resend_at) << "no answers after A was lost";
}

}  // namespace

namespace {

// A kernel frozen mid-run (SIGSTOP) must not stall the calls between the
// others. Its DDS readers stop acknowledging, and reliable writers keep every
// sample it has not acknowledged until its DDS lease ends: with Cyclone's
// default lease (10 s) the request and reply histories filled after a few
// thousand calls and every call on the domain timed out until then.
TEST(RemoteNetns, AFrozenKernelDoesNotStallTheOthersCalls) {
  Net net;
  const int domain = 100 + (::getpid() + 50) % 100;
  const auto provider = [&](const std::string& name) {
    return write_config(name + ".yaml", "pipeline: " + name +
                                            "\nnodes:\n  doubler: {plugin: demo_doubler}\n" +
                                            dds_block(domain, net.iface, "double", ""));
  };
  const auto a = provider("frozen_a"), b = provider("frozen_b");
  const auto c = write_config(
      "frozen_c.yaml",
      "pipeline: frozen_c\nnodes:\n  counter: {plugin: demo_counter, params: {period_ms: 1, "
      "limit: 12000}}\n" +
          dds_block(domain, net.iface, "", "double"));
  const auto dir = ::testing::TempDir();
  Proc kernel_a(net.in(net.ns_a), {kPlr, "run", a, "--report", dir + "fa"}, dir + "frozen_a.log");
  Proc kernel_b(net.in(net.ns_b), {kPlr, "run", b, "--report", dir + "fb"}, dir + "frozen_b.log");
  Proc caller(net.in(net.ns_b), {kPlr, "run", c, "--report", dir + "fc"}, dir + "frozen_c.log");

  // Freeze A once calls flow to both providers.
  const auto deadline = std::chrono::steady_clock::now() + 30s;
  while (read_caller(slurp(caller.log)).good < 1000 && std::chrono::steady_clock::now() < deadline)
    std::this_thread::sleep_for(100ms);
  ASSERT_GE(read_caller(slurp(caller.log)).good, 1000) << slurp(caller.log);
  ::kill(kernel_a.pid, SIGSTOP);
  const int rc = caller.wait(120s);
  ::kill(kernel_a.pid, SIGCONT);
  const auto log = slurp(caller.log);
  const auto tail = log.substr(log.size() > 3000 ? log.size() - 3000 : 0);
  EXPECT_EQ(rc, 0) << tail;
  const auto calls = read_caller(log);
  EXPECT_EQ(calls.wrong, 0);
  EXPECT_GE(calls.good, 11000) << tail;
  // The call caught on A when it froze, and nothing after.
  EXPECT_LE(calls.failures_after_start, 1u) << tail;
  EXPECT_EQ(log.find("timed out"), std::string::npos) << tail;
}

}  // namespace
