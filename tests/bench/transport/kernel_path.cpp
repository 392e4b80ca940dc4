#include "kernel_path.hpp"

#include <sched.h>
#include <sys/mman.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstring>
#include <memory>
#include <thread>

#include "bus.hpp"
#include "links.hpp"
#include "message.hpp"
#include "pipeline_config.hpp"
#include "shm_bridge.hpp"

namespace plr::bench {
namespace {

using namespace std::chrono_literals;
using kernel::Bus;
using kernel::PipelineConfig;
using kernel::ShmBridge;

constexpr std::size_t kMaxSamples = 1000;
constexpr std::uint64_t kBlobType = 0x626c6f62;  // the bus does not interpret it

enum class Path { kLoan, kCopyIntoLoan, kHeap };
const char* name(Path p) {
  switch (p) {
    case Path::kLoan:
      return "loan";
    case Path::kCopyIntoLoan:
      return "copy-into-loan";
    case Path::kHeap:
      return "heap+bridge-copy";
  }
  return "?";
}

struct Received {
  std::atomic<std::uint64_t> count;
  std::uint64_t oneway_ns[kMaxSamples];
};

class Ep final : public kernel::Endpoint {
 public:
  explicit Ep(std::string n) : name_(std::move(n)), node_thread_(name_) {}
  kernel::NodeThread& node_thread() override { return node_thread_; }
  const std::string& endpoint_name() const override { return name_; }

 private:
  std::string name_;
  kernel::NodeThread node_thread_;
};

PipelineConfig make_config(std::size_t size) {
  auto c = kernel::parse_pipeline_config(
      "hosts:\n  b: {restart: never}\n"
      "nodes:\n  a: {plugin: none}\n  b: {plugin: none, host: b}\n"
      "topics:\n  blob: {policy: reliable, depth: 4, slot_size: " +
          std::to_string(size) + "}\n",
      "bench_kernel_path.yaml");
  if (!c) {
    std::fprintf(stderr, "bench config: %s\n", c.error().message.c_str());
    std::exit(1);
  }
  return *c;
}

// Host b: records receive time - stamp for each message, in its subscriber's callback.
int receive(const PipelineConfig& config, const std::string& run, std::size_t n, Received& out) {
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(1, &set);
  sched_setaffinity(0, sizeof set, &set);
  Bus bus([&](const std::string& t) { return config.topic(t); });
  auto bridge =
      std::make_unique<ShmBridge>(bus, config, "b", std::vector<std::string>{"main", "b"}, run);
  bus.attach(bridge.get());
  Ep ep("reader");
  bus.set_live(&ep, true);
  auto fn = [](void* user, const plr_msg* m) {
    const auto t = now_ns();
    auto* r = static_cast<Received*>(user);
    std::uint64_t stamp = 0;
    const auto v = kernel::msg_view(m);
    if (v.size >= 8) std::memcpy(&stamp, v.data, 8);
    const auto i = r->count.load(std::memory_order_relaxed);
    if (i < kMaxSamples) r->oneway_ns[i] = t - stamp;
    r->count.store(i + 1, std::memory_order_release);
  };
  if (!bus.subscribe(&ep, "blob", kBlobType, fn, &out)) return 2;
  const auto end = std::chrono::steady_clock::now() + 60s;
  while (out.count.load() < n && std::chrono::steady_clock::now() < end)
    std::this_thread::sleep_for(1ms);
  bus.remove_endpoint(&ep);
  ep.node_thread().drain();
  bus.detach(bridge.get());
  return out.count.load() >= n ? 0 : 3;
}

double percentile(std::vector<std::uint64_t> v, std::size_t pct) {
  if (v.empty()) return 0;
  std::sort(v.begin(), v.end());
  return static_cast<double>(v[std::min(v.size() - 1, v.size() * pct / 100)]) / 1e3;
}

KernelRow run_case(Path path, std::size_t size, std::size_t n, const std::string& run,
                   Received* shared) {
  KernelRow row;
  row.path = name(path);
  row.size = size;
  row.messages = n;
  const PipelineConfig config = make_config(size);
  shared->count.store(0);
  const pid_t child = ::fork();
  if (child == 0) ::_exit(receive(config, run, n, *shared));

  Bus bus([&](const std::string& t) { return config.topic(t); });
  auto bridge =
      std::make_unique<ShmBridge>(bus, config, "main", std::vector<std::string>{"main", "b"}, run);
  bus.attach(bridge.get());
  Ep ep("publisher");
  auto pub = bus.advertise(&ep, "blob", kBlobType, 1);
  // Wait until host b reads the topic: then a loan is a slot of its segment.
  bool attached = false;
  for (int i = 0; i < 3000 && pub && !attached; ++i) {
    std::uint8_t* d = nullptr;
    plr_msg* m = bus.loan(*pub, 8, &d);
    attached = m != nullptr && m->loan != nullptr;
    if (m) kernel::msg_release(m);
    if (!attached) std::this_thread::sleep_for(10ms);
  }
  std::vector<std::uint64_t> cost;
  if (attached) {
    // The message "built elsewhere" (a finished FlatBufferBuilder, say).
    std::vector<std::uint8_t> built(size, 0x5a);
    for (std::size_t i = 0; i < n; ++i) {
      const std::uint64_t t0 = now_ns();
      std::uint8_t* d = nullptr;
      plr_msg* m = path == Path::kHeap ? kernel::msg_alloc(size, &d) : bus.loan(*pub, size, &d);
      if (path == Path::kLoan) {
        std::memcpy(d, &t0, 8);  // built in place: only the stamp is written
      } else {
        std::memcpy(built.data(), &t0, 8);
        std::memcpy(d, built.data(), size);
      }
      m->offset = 0;
      m->size = size;
      (void)bus.publish(*pub, m);
      cost.push_back(now_ns() - t0);
      // Paced so that neither side queues: the figures are per message.
      std::this_thread::sleep_for(size > (1u << 20) ? 5ms : 1ms);
    }
  }
  int status = 0;
  ::waitpid(child, &status, 0);
  const auto stats = bridge->stats();
  row.sent_in_place = stats["sent_in_place"];
  row.sent_copied = stats["sent_copied"];
  bus.remove_endpoint(&ep);
  bus.detach(bridge.get());
  if (!attached || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    row.error = attached ? "receiver failed" : "host b never attached";
    return row;
  }
  const std::vector<std::uint64_t> oneway(shared->oneway_ns,
                                          shared->oneway_ns + std::min(n, kMaxSamples));
  row.publish_p50_us = percentile(cost, 50);
  row.publish_p99_us = percentile(cost, 99);
  row.oneway_p50_us = percentile(oneway, 50);
  row.oneway_p99_us = percentile(oneway, 99);
  row.ok = true;
  return row;
}

}  // namespace

const char* kernel_path_description() {
  return "Bus + ShmBridge per process (host main on CPU 0, host b on CPU 1, all their threads "
         "too), reliable topic, futex wait, messages paced 1 ms (4 MiB: 5 ms). publish = "
         "publishing thread from loan/alloc to publish() returned; one-way = to the "
         "subscriber callback on host b. loan: built in the slot (0 copies); copy-into-loan: "
         "built elsewhere, copied into the loaned slot (SDK publish(fbb), 1 copy); "
         "heap+bridge-copy: heap buffer, the bridge copies it into a slot (2 copies, the "
         "path before loans).";
}

std::vector<KernelRow> run_kernel_path(bool quick, const std::string& run_id) {
  void* mem =
      ::mmap(nullptr, sizeof(Received), PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0);
  std::vector<KernelRow> rows;
  if (mem == MAP_FAILED) return rows;
  auto* shared = new (mem) Received{};
  const std::size_t n = quick ? 50 : 200;
  int i = 0;
  for (std::size_t size : {std::size_t{64} << 10, std::size_t{4} << 20})
    for (Path p : {Path::kLoan, Path::kCopyIntoLoan, Path::kHeap})
      rows.push_back(run_case(p, size, size > (1u << 20) ? n / 2 : n,
                              run_id + "x" + std::to_string(i++), shared));
  ::munmap(mem, sizeof(Received));
  return rows;
}

void print(const KernelRow& r) {
  const std::string size = r.size >= (1u << 20) ? std::to_string(r.size >> 20) + " MiB"
                                                : std::to_string(r.size >> 10) + " KiB";
  if (!r.ok) {
    std::printf("%-8s %-17s FAILED: %s\n", size.c_str(), r.path.c_str(), r.error.c_str());
    return;
  }
  std::printf(
      "%-8s %-17s publish p50 %8.2f us p99 %8.2f us  one-way p50 %8.2f us p99 %8.2f us  "
      "(in place %llu, copied %llu)\n",
      size.c_str(), r.path.c_str(), r.publish_p50_us, r.publish_p99_us, r.oneway_p50_us,
      r.oneway_p99_us, static_cast<unsigned long long>(r.sent_in_place),
      static_cast<unsigned long long>(r.sent_copied));
  std::fflush(stdout);
}

nlohmann::json to_json(const KernelRow& r) {
  nlohmann::json o{
      {"path", r.path}, {"size_bytes", r.size}, {"ok", r.ok}, {"messages", r.messages}};
  if (!r.ok) {
    o["error"] = r.error;
    return o;
  }
  o["publish_p50_us"] = r.publish_p50_us;
  o["publish_p99_us"] = r.publish_p99_us;
  o["oneway_p50_us"] = r.oneway_p50_us;
  o["oneway_p99_us"] = r.oneway_p99_us;
  o["sent_in_place"] = r.sent_in_place;
  o["sent_copied"] = r.sent_copied;
  return o;
}

}  // namespace plr::bench
