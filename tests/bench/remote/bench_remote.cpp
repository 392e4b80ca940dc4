// bench_remote: round trip of a service call between two kernels over Cyclone
// DDS (this process: bus + DDS bridge + caller; a child `bench_remote --serve`:
// bus + DDS bridge + echo provider), on loopback, beside Cyclone's ddsperf
// ping/pong between the same two places (two processes, same Cyclone config).
// Nothing is pinned: both sides float over the machine's cores alike.
// ddsperf prints half its round trip (its one-way latency estimate); its
// figures are doubled here, and the doubling is checked against its rate.
//   bench_remote [--quick] [--json]
#include "bare_kernel.hpp"
#include "bench_cli.hpp"

#include <plr/message.hpp>
#include <plr/spin_wait.hpp>

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <nlohmann/json.hpp>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>
#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <optional>
#include <regex>
#include <string>
#include <thread>
#include <vector>

namespace plr::kernel {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;
using remote_test::BareKernel;
using remote_test::kEchoType;
using testing::TestEndpoint;

// Two echo services: "echo" is quick (answered on the thread that took the
// request off the network), "echo_node" is answered on its node's thread.
constexpr const char* kServices[] = {"echo", "echo_node"};

// What is measured: a service, and whether the caller watches for the reply
// (as plr::Future::get() does) or sleeps at once, as ddsperf's two sides do.
struct Case {
  const char* key;
  const char* service;
  bool watch;
};
constexpr Case kCases[] = {
    {"echo", "echo", true}, {"echo_node", "echo_node", true}, {"echo_sleeping", "echo", false}};

int serve(int domain) {
  BareKernel k(domain, "bench_server", true, "echo*");
  if (const Status s = k.open(); !s) {
    std::cerr << s.error().message << "\n";
    return 1;
  }
  (void)k.provide_echo(k.add_node("echo"), "echo", PLR_SERVICE_QUICK);
  (void)k.provide_echo(k.add_node("echo_node"), "echo_node", 0);
  // Until the parent goes.
  while (::getppid() != 1) std::this_thread::sleep_for(100ms);
  return 0;
}

struct Figures {
  double median_us = 0, mean_us = 0, p99_us = 0;
  std::size_t count = 0;
};

Figures summarize(std::vector<double> v) {
  Figures f;
  if (v.empty()) return f;
  std::sort(v.begin(), v.end());
  f.count = v.size();
  f.median_us = v[v.size() / 2];
  f.p99_us = v[std::min(v.size() - 1, v.size() * 99 / 100)];
  double sum = 0;
  for (double x : v) sum += x;
  f.mean_us = sum / v.size();
  return f;
}

class Client {
 public:
  explicit Client(int domain)
      : kernel_(domain, "bench_client", false, "echo*"), caller_(kernel_.add_node("caller")) {}
  Status open() { return kernel_.open(); }
  struct RoundTrip {
    double resumed_us;   // until the calling thread runs again
    double callback_us;  // until the reply callback runs (Cyclone's receive thread)
  };
  // One round trip, or nothing when the call failed. A watching caller waits as
  // plr::Future::get() does: it watches for the reply for kCallSpin, then sleeps.
  std::optional<RoundTrip> call(const char* service, const std::vector<std::uint8_t>& payload,
                                bool watch = true) {
    plr_msg* request = msg_copy(payload.data(), payload.size(), kEchoType, 1, 0);
    done_.store(false);
    const auto t0 = Clock::now();
    auto s = kernel_.bus().call(&caller_, service, kEchoType, request, 2s, &Client::on_reply, this,
                                nullptr);
    if (!s) return std::nullopt;
    if (!watch || !spin_until(done_, kCallSpin)) done_.wait(false);
    const auto t1 = Clock::now();
    if (status_ != PLR_OK || reply_size_ != payload.size()) return std::nullopt;
    return RoundTrip{std::chrono::duration<double, std::micro>(t1 - t0).count(),
                     std::chrono::duration<double, std::micro>(reply_at_ - t0).count()};
  }

 private:
  static void on_reply(void* user, plr_status status, const plr_msg* reply, const char*) {
    auto* self = static_cast<Client*>(user);
    self->reply_at_ = Clock::now();
    self->status_ = status;
    self->reply_size_ = reply ? msg_view(reply).size : 0;
    self->done_.store(true, std::memory_order_release);
    self->done_.notify_one();
  }

  std::atomic<bool> done_{false};
  plr_status status_ = PLR_OK;
  Clock::time_point reply_at_;
  std::size_t reply_size_ = 0;
  BareKernel kernel_;  // last: stops before what its reply callbacks write
  TestEndpoint& caller_;
};

pid_t spawn(const std::vector<std::string>& argv, const std::string& uri, const char* out) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (!uri.empty()) ::setenv("CYCLONEDDS_URI", uri.c_str(), 1);
    if (out) std::freopen(out, "w", stdout);
    std::vector<char*> args;
    for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    ::execvp(args[0], args.data());
    ::_exit(127);
  }
  return pid;
}

void finish(pid_t pid) {
  ::kill(pid, SIGTERM);
  ::waitpid(pid, nullptr, 0);
}

// ddsperf's own round trip, from its "size N mean Xus min .. 50% Yus .. 99% Zus
// .. cnt K" lines, one per second. Its ping sends the next ping as the pong
// arrives, so K round trips fill each second, K * X = 0.5 s shows that X is
// half a round trip, and the last line's figures are doubled; the check keeps
// another ddsperf that printed whole round trips from being misread.
std::optional<Figures> ddsperf(int domain, const std::string& uri, std::size_t size, int seconds) {
  const pid_t pong = spawn({"ddsperf", "-i", std::to_string(domain), "pong"}, uri, "/dev/null");
  const std::string out_file = fmt::format("/tmp/bench_remote_ddsperf_{}.txt", ::getpid());
  const pid_t ping = spawn({"ddsperf", "-i", std::to_string(domain), "-D",
                            std::to_string(seconds + 2), "ping", "size", std::to_string(size)},
                           uri, out_file.c_str());
  ::waitpid(ping, nullptr, 0);
  finish(pong);
  FILE* f = std::fopen(out_file.c_str(), "r");
  if (!f) return std::nullopt;
  std::string text;
  char buf[4096];
  std::size_t n = 0;
  while ((n = std::fread(buf, 1, sizeof buf, f)) > 0) text.append(buf, n);
  std::fclose(f);
  std::remove(out_file.c_str());
  static const std::regex line(
      R"(size (\d+) mean ([0-9.]+)us min [0-9.]+us 50% ([0-9.]+)us 90% [0-9.]+us 99% ([0-9.]+)us max [0-9.]+us cnt (\d+))");
  std::optional<Figures> last;
  for (std::sregex_iterator it(text.begin(), text.end(), line), end; it != end; ++it) {
    Figures fig;
    fig.mean_us = std::stod((*it)[2]);
    fig.median_us = std::stod((*it)[3]);
    fig.p99_us = std::stod((*it)[4]);
    fig.count = std::stoul((*it)[5]);
    last = fig;
  }
  if (!last) return last;
  const double busy = static_cast<double>(last->count) * last->mean_us * 1e-6;  // s per s
  const double scale = busy > 0.4 && busy < 0.6 ? 2 : busy > 0.8 && busy < 1.2 ? 1 : 0;
  if (scale == 0) {
    std::cerr << fmt::format(
        "ddsperf at {} B: {} round trips at {} us fill {:.2f} s of a second; "
        "neither half nor whole round trips, left out\n",
        size, last->count, last->mean_us, busy);
    return std::nullopt;
  }
  last->mean_us *= scale;
  last->median_us *= scale;
  last->p99_us *= scale;
  return last;
}

int bench(bool quick, bool json) {
  const int domain = 100 + ::getpid() % 60;  // ddsperf uses domain + 60: both <= 232
  const int seconds = quick ? 1 : 3;
  const std::vector<std::size_t> sizes{64, 64 * 1024};
  DdsConfig dds;
  dds.domain = domain;
  auto xml = cyclone_config_xml(dds);
  if (!xml) {
    std::cerr << xml.error().message << "\n";
    return 1;
  }

  nlohmann::json results = nlohmann::json::array();
  const pid_t server = spawn({"/proc/self/exe", "--serve", std::to_string(domain)}, "", nullptr);
  {
    Client client(domain);
    if (const Status s = client.open(); !s) {
      std::cerr << s.error().message << "\n";
      finish(server);
      return 1;
    }
    // Discovery first: until both echo services answer.
    const auto ready_by = Clock::now() + 20s;
    for (const char* service : kServices)
      while (!client.call(service, std::vector<std::uint8_t>(64, 1)) && Clock::now() < ready_by)
        std::this_thread::sleep_for(50ms);
    for (auto size : sizes) {
      nlohmann::json row = {{"size", size}};
      std::vector<std::uint8_t> payload(size, 0x5a);
      for (const auto& c : kCases) {
        for (int i = 0; i < 200; ++i) (void)client.call(c.service, payload, c.watch);  // warm-up
        std::vector<double> rtt, at_callback;
        std::size_t failed = 0;
        const auto until = Clock::now() + std::chrono::seconds(seconds);
        while (Clock::now() < until) {
          if (auto rt = client.call(c.service, payload, c.watch)) {
            rtt.push_back(rt->resumed_us);
            at_callback.push_back(rt->callback_us);
          } else {
            ++failed;
          }
        }
        const auto f = summarize(rtt);
        row[c.key] = {{"service", c.service},
                      {"caller", c.watch ? "watches" : "sleeps"},
                      {"median_us", f.median_us},
                      {"mean_us", f.mean_us},
                      {"p99_us", f.p99_us},
                      {"count", f.count},
                      {"failed", failed},
                      {"reply_callback_median_us", summarize(at_callback).median_us}};
      }
      results.push_back(row);
    }
  }
  finish(server);

  for (auto& r : results) {
    const auto f = ddsperf(domain + 60, *xml, r["size"].get<std::size_t>(), seconds);
    r["ddsperf"] = nullptr;
    if (!f) continue;
    r["ddsperf"] = {{"median_us", f->median_us},
                    {"mean_us", f->mean_us},
                    {"p99_us", f->p99_us},
                    {"count", f->count}};
    for (const auto& c : kCases)
      r[c.key]["ratio_median"] = r[c.key]["median_us"].get<double>() / f->median_us;
  }

  if (json) {
    std::cout << nlohmann::json{{"bench", "remote"},
                                {"transport", "cyclone dds 0.10.2, loopback, 2 processes"},
                                {"pinning", "none"},
                                {"seconds_per_size", seconds},
                                {"results", results}}
                     .dump(2)
              << "\n";
    return 0;
  }
  std::cout << fmt::format(
      "Service round trip over Cyclone DDS, loopback, two processes, {} s per size and case,\n"
      "not pinned. plr = caller -> bus -> DDS bridge ~> DDS bridge -> bus -> echo and back, until\n"
      "the calling thread runs again; cb p50: until the reply callback runs. echo is a quick\n"
      "service (answered on the receiving thread), echo_node is answered on its node's thread.\n"
      "The caller watches {} us for the reply, then sleeps (as plr::Future::get()), except in\n"
      "echo_sleeping, where it sleeps at once. ddsperf = Cyclone's own ping/pong, same Cyclone\n"
      "config, whole round trips (it prints half of one).\n\n",
      seconds, kCallSpin.count());
  std::cout << fmt::format(
      "{:>8} {:>14} | {:>10} {:>10} {:>10} {:>10} | {:>10} {:>10} {:>10} | {:>8}\n", "size", "case",
      "plr p50", "plr mean", "plr p99", "cb p50", "dds p50", "dds mean", "dds p99", "p50 x");
  const auto us = [](const nlohmann::json& d, const char* key) {
    return d.is_null() ? std::string("-") : fmt::format("{:.1f}us", d[key].get<double>());
  };
  for (const auto& r : results) {
    const auto& d = r["ddsperf"];
    for (const auto& c : kCases) {
      const auto& p = r[c.key];
      std::cout << fmt::format(
          "{:>8} {:>14} | {:>10} {:>10} {:>10} {:>10} | {:>10} {:>10} {:>10} | {:>8}\n",
          r["size"].get<std::size_t>(), c.key, us(p, "median_us"), us(p, "mean_us"),
          us(p, "p99_us"), us(p, "reply_callback_median_us"), us(d, "median_us"), us(d, "mean_us"),
          us(d, "p99_us"),
          p.contains("ratio_median") ? fmt::format("{:.2f}", p["ratio_median"].get<double>())
                                     : "-");
    }
  }
  return 0;
}

}  // namespace
}  // namespace plr::kernel

int main(int argc, char** argv) {
  // The bridges' info lines would mix with the table or the JSON on stdout.
  spdlog::set_level(spdlog::level::warn);
  bool quick = false, json = false;
  std::optional<int> serve_domain;
  CLI::App app{
      "Round trip of a service call between two kernels over Cyclone DDS, beside "
      "ddsperf ping/pong"};
  plr::bench::add_quick_flag(app, quick, "1 s per size and case instead of 3");
  plr::bench::add_json_flag(app, json);
  app.add_option("--serve", serve_domain,
                 "Be the echo side on this DDS domain (the benchmark starts it itself)");
  plr::bench::parse_or_exit(app, argc, argv);
  if (serve_domain) {
    // The server shares the parent's stdout: its warnings would break the JSON.
    spdlog::set_level(spdlog::level::err);
    return plr::kernel::serve(*serve_domain);
  }
  return plr::kernel::bench(quick, json);
}
