// bench_transport: cross-process one-way latency and throughput of our
// shared-memory transport (busy-polling, futex, spin-then-futex) against a
// Unix domain socket and Cyclone DDS on loopback. Sender on CPU 0, receiver
// (a forked process) on CPU 1; one futex row with both on CPU 0. The
// transports that sleep run again with a PM QoS request that idle CPUs wake
// within 0 µs (rows marked "wake0"; needs root), as a deployment can ask with
// `cpu_wake_latency_us: 0`. Then the kernel's publish path (kernel_path.cpp):
// loaned slot vs copies.
//
// Latency: ping-pong; the sender stamps CLOCK_MONOTONIC before sending (for
// shm: before loan()), the receiver reads the clock as soon as the message is
// in hand (shm: take() returned; UDS: the whole payload read; DDS: dds_take()
// returned) and acks; one-way = receive time - stamp. Shm never copies the
// payload: the sender writes a 16-byte stamp into the loaned slot, the
// receiver reads it in place. UDS and DDS carry (copy) every payload byte.
// Throughput: back-to-back sends, reliable, until the receiver got them all.
#include <sched.h>
#include <sys/mman.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "bench_cli.hpp"
#include "kernel_path.hpp"
#include "links.hpp"
#include "plr/shm/shm.hpp"

namespace plr::bench {
namespace {

using namespace std::chrono_literals;

constexpr int kSenderCpu = 0;
constexpr int kReceiverCpu = 1;
constexpr std::size_t kMaxLatencySamples = 200'000;

// kShmSpin: blocking topic with spin_us = kSpinUs (spin, then futex).
// kShmBlockSameCore: blocking, receiver pinned to the sender's CPU.
enum class Kind { kShmPoll, kShmBlock, kShmSpin, kShmBlockSameCore, kUds, kDds };
constexpr std::uint32_t kSpinUs = 50;
bool is_shm(Kind k) {
  return k != Kind::kUds && k != Kind::kDds;
}
const char* name(Kind k) {
  switch (k) {
    case Kind::kShmPoll:
      return "shm-poll";
    case Kind::kShmBlock:
      return "shm-futex";
    case Kind::kShmSpin:
      return "shm-spin50";
    case Kind::kShmBlockSameCore:
      return "shm-futex-1cpu";
    case Kind::kUds:
      return "uds";
    case Kind::kDds:
      return "cyclonedds";
  }
  return "?";
}

// Results the receiver hands back (shared anonymous mapping: measurements
// only, never message data).
struct Shared {
  std::uint64_t last_receive_ns;
  std::uint64_t latency_count;
  std::uint64_t latency_ns[kMaxLatencySamples];
};

// --rt: SCHED_FIFO, so that on a busy machine the figures show the
// transport's cost rather than the wait for a core. Needs CAP_SYS_NICE.
bool g_realtime = false;

bool pin(int cpu) {
  cpu_set_t set;
  CPU_ZERO(&set);
  CPU_SET(cpu, &set);
  if (g_realtime) {
    sched_param sp{};
    sp.sched_priority = 10;
    if (sched_setscheduler(0, SCHED_FIFO, &sp) != 0) return false;
  }
  return sched_setaffinity(0, sizeof set, &set) == 0;
}

struct Pipe {
  int fd[2] = {-1, -1};
  Pipe() { (void)!::pipe(fd); }
  ~Pipe() {
    for (int f : fd) ::close(f);
  }
  void signal() const {
    char c = 'x';
    (void)!::write(fd[1], &c, 1);
  }
  bool wait() const {
    char c = 0;
    return ::read(fd[0], &c, 1) == 1;
  }
};

// ------------------------------------------------------------- shm link

class ShmLink final : public Link {
 public:
  // The sender publishes "data", the receiver publishes "ack"; each side
  // subscribes to the other's once the peer says it exists.
  static Link* make(bool sender, const std::string& run, std::size_t size, shm::WaitMode mode,
                    std::uint32_t spin_us, const Pipe& to_peer, const Pipe& from_peer,
                    std::string& error) {
    auto l = std::make_unique<ShmLink>();
    shm::TopicConfig c;
    c.policy = shm::Policy::kReliable;
    c.wait_mode = mode;
    c.spin_us = spin_us;
    c.slot_count = 8;
    c.slot_size = static_cast<std::uint32_t>(sender ? size : 64);
    auto pub =
        shm::PublisherBuilder().run_id(run).topic(sender ? "data" : "ack").config(c).create();
    if (!pub) return fail(error, "publisher", pub.error());
    l->pub_ = std::make_unique<shm::Publisher>(std::move(*pub));
    if (sender) {
      to_peer.signal();
      if (!from_peer.wait()) return fail(error, "peer", shm::Error::kPeerDead);
    } else {
      if (!from_peer.wait()) return fail(error, "peer", shm::Error::kPeerDead);
    }
    auto sub = shm::SubscriberBuilder().run_id(run).topic(sender ? "ack" : "data").create();
    if (!sub) return fail(error, "subscriber", sub.error());
    l->sub_ = std::make_unique<shm::Subscriber>(std::move(*sub));
    if (!sender) to_peer.signal();
    return l.release();
  }

  bool send(std::size_t size, std::uint64_t stamp, std::uint64_t seq) override {
    auto l = pub_->loan(size, 10s);
    if (!l) return false;
    std::memcpy(l->data(), &stamp, 8);
    std::memcpy(l->data() + 8, &seq, 8);
    return pub_->publish(std::move(*l), shm::MessageType{1, 1}, 0, size).has_value();
  }
  bool wait_ack(std::uint64_t& seq) override {
    std::uint64_t stamp = 0;
    return receive(stamp, seq);
  }
  bool receive(std::uint64_t& stamp, std::uint64_t& seq) override {
    auto m = sub_->take(10s);
    if (!m) return false;
    std::memcpy(&stamp, m->data().data(), 8);
    std::memcpy(&seq, m->data().data() + 8, 8);
    return true;
  }
  bool ack(std::uint64_t seq) override { return send(64, 0, seq); }

 private:
  static Link* fail(std::string& error, const char* what, shm::Error e) {
    error = std::string("shm ") + what + ": " + shm::to_string(e);
    return nullptr;
  }
  std::unique_ptr<shm::Publisher> pub_;
  std::unique_ptr<shm::Subscriber> sub_;
};

// ------------------------------------------------------------- UDS link

class UdsLink final : public Link {
 public:
  UdsLink(int fd, std::size_t max_size) : fd_(fd), buf_(std::max<std::size_t>(max_size, 64)) {
    const int bytes = 8 << 20;
    setsockopt(fd_, SOL_SOCKET, SO_SNDBUF, &bytes, sizeof bytes);
    setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &bytes, sizeof bytes);
  }
  bool send(std::size_t size, std::uint64_t stamp, std::uint64_t seq) override {
    std::memcpy(buf_.data(), &stamp, 8);
    std::memcpy(buf_.data() + 8, &seq, 8);
    return write_all(size);
  }
  bool wait_ack(std::uint64_t& seq) override {
    std::uint64_t stamp = 0;
    return read_msg(64, stamp, seq);
  }
  bool receive(std::uint64_t& stamp, std::uint64_t& seq) override {
    return read_msg(size_, stamp, seq);
  }
  bool ack(std::uint64_t seq) override { return send(64, 0, seq); }
  void set_size(std::size_t s) { size_ = s; }

 private:
  bool write_all(std::size_t size) {
    std::size_t done = 0;
    while (done < size) {
      const ssize_t n = ::send(fd_, buf_.data() + done, size - done, MSG_NOSIGNAL);
      if (n <= 0) return false;
      done += static_cast<std::size_t>(n);
    }
    return true;
  }
  bool read_msg(std::size_t size, std::uint64_t& stamp, std::uint64_t& seq) {
    std::size_t done = 0;
    while (done < size) {
      const ssize_t n = ::recv(fd_, buf_.data() + done, size - done, MSG_WAITALL);
      if (n <= 0) return false;
      done += static_cast<std::size_t>(n);
    }
    std::memcpy(&stamp, buf_.data(), 8);
    std::memcpy(&seq, buf_.data() + 8, 8);
    return true;
  }
  int fd_;
  std::size_t size_ = 0;
  std::vector<std::byte> buf_;
};

// ------------------------------------------------------------- harness

struct Case {
  Kind kind;
  bool wake0;  // a PM QoS request of 0 µs held during the case
  std::size_t size;
  std::size_t latency_iters;
  std::size_t throughput_iters;
};

struct Row {
  Kind kind = Kind::kShmPoll;
  bool wake0 = false;
  std::size_t size = 0;
  bool ok = false;
  std::string error;
  double p50_us = 0, p99_us = 0;
  double msgs_per_s = 0, mib_per_s = 0;
  std::size_t latency_iters = 0, throughput_iters = 0;
};

// Runs warm-up + latency ping-pong, then the throughput burst. Both roles.
bool run_sender(Link& l, const Case& c, std::size_t warm, std::uint64_t& first_send) {
  std::uint64_t seq = 0;
  for (std::size_t i = 0; i < warm + c.latency_iters; ++i) {
    if (!l.send(c.size, now_ns(), i) || !l.wait_ack(seq) || seq != i) return false;
  }
  first_send = now_ns();
  for (std::size_t i = 0; i < c.throughput_iters; ++i) {
    if (!l.send(c.size, 0, i)) return false;
  }
  return l.wait_ack(seq) && seq == c.throughput_iters;
}

int run_receiver(Link& l, const Case& c, std::size_t warm, Shared& out) {
  std::uint64_t stamp = 0, seq = 0;
  for (std::size_t i = 0; i < warm + c.latency_iters; ++i) {
    if (!l.receive(stamp, seq)) return 3;
    const std::uint64_t t = now_ns();
    if (i >= warm) out.latency_ns[out.latency_count++] = t - stamp;
    if (!l.ack(seq)) return 4;
  }
  for (std::size_t i = 0; i < c.throughput_iters; ++i) {
    if (!l.receive(stamp, seq) || seq != i) return 5;
  }
  out.last_receive_ns = now_ns();
  return l.ack(c.throughput_iters) ? 0 : 6;
}

Row run_case(const Case& c, Shared* shared, const std::string& run) {
  Row row;
  row.kind = c.kind;
  row.wake0 = c.wake0;
  row.size = c.size;
  row.latency_iters = c.latency_iters;
  row.throughput_iters = c.throughput_iters;
  const std::size_t warm = std::max<std::size_t>(50, c.latency_iters / 10);
  shared->latency_count = 0;
  shared->last_receive_ns = 0;
  Pipe to_child, to_parent;
  int sv[2] = {-1, -1};
  if (c.kind == Kind::kUds && ::socketpair(AF_UNIX, SOCK_STREAM, 0, sv) != 0) {
    row.error = "socketpair failed";
    return row;
  }
  const shm::WaitMode mode =
      c.kind == Kind::kShmPoll ? shm::WaitMode::kPolling : shm::WaitMode::kBlocking;
  const std::uint32_t spin_us = c.kind == Kind::kShmSpin ? kSpinUs : 0;
  std::optional<shm::WakeLatencyRequest> wake;
  if (c.wake0) {
    auto w = shm::WakeLatencyRequest::hold(0);
    if (!w) {
      row.error = std::string("/dev/cpu_dma_latency: ") + shm::to_string(w.error());
      return row;
    }
    wake.emplace(std::move(*w));
  }
  const pid_t pid = ::fork();
  if (pid == 0) {
    pin(c.kind == Kind::kShmBlockSameCore ? kSenderCpu : kReceiverCpu);
    std::string err;
    Link* l = nullptr;
    if (c.kind == Kind::kUds) {
      auto* u = new UdsLink(sv[1], c.size);
      u->set_size(c.size);
      l = u;
    } else if (c.kind == Kind::kDds) {
      l = make_dds_link(false, c.size, err);
    } else {
      l = ShmLink::make(false, run, c.size, mode, spin_us, to_parent, to_child, err);
    }
    if (l == nullptr) {
      std::fprintf(stderr, "receiver: %s\n", err.c_str());
      ::_exit(2);
    }
    const int rc = run_receiver(*l, c, warm, *shared);
    delete l;
    ::_exit(rc);
  }
  pin(kSenderCpu);
  std::string err;
  std::unique_ptr<Link> l;
  if (c.kind == Kind::kUds) {
    l = std::make_unique<UdsLink>(sv[0], c.size);
  } else if (c.kind == Kind::kDds) {
    l.reset(make_dds_link(true, c.size, err));
  } else {
    l.reset(ShmLink::make(true, run, c.size, mode, spin_us, to_child, to_parent, err));
  }
  std::uint64_t first_send = 0;
  const bool sent = l != nullptr && run_sender(*l, c, warm, first_send);
  if (!sent && err.empty()) err = "sender failed";
  if (!sent) ::kill(pid, SIGKILL);
  int status = 0;
  ::waitpid(pid, &status, 0);
  l.reset();
  if (sv[0] >= 0) {
    ::close(sv[0]);
    ::close(sv[1]);
  }
  if (!sent || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    row.error = err + " (receiver status " + std::to_string(WEXITSTATUS(status)) + ")";
    return row;
  }
  std::vector<std::uint64_t> lat(shared->latency_ns, shared->latency_ns + shared->latency_count);
  std::sort(lat.begin(), lat.end());
  row.p50_us = static_cast<double>(lat[lat.size() / 2]) / 1e3;
  row.p99_us = static_cast<double>(lat[lat.size() * 99 / 100]) / 1e3;
  const double secs = static_cast<double>(shared->last_receive_ns - first_send) / 1e9;
  row.msgs_per_s = static_cast<double>(c.throughput_iters) / secs;
  row.mib_per_s = row.msgs_per_s * static_cast<double>(c.size) / (1024.0 * 1024.0);
  row.ok = true;
  return row;
}

std::string row_label(const Row& r) {
  return std::string(name(r.kind)) + (r.wake0 ? " wake0" : "");
}

std::string size_label(std::size_t s) {
  if (s >= (1u << 20)) return std::to_string(s >> 20) + " MiB";
  if (s >= 1024) return std::to_string(s >> 10) + " KiB";
  return std::to_string(s) + " B";
}

// Cyclone DDS on loopback only (no multicast, the one peer 127.0.0.1), with
// 64 KB datagrams: what a kernel uses with `interfaces: [lo]`.
std::string write_dds_config() {
  char path[] = "/tmp/plr_bench_ddsXXXXXX";
  const int fd = ::mkstemp(path);
  if (fd < 0) return {};
  const char* xml =
      "<CycloneDDS xmlns=\"https://cdds.io/config\"><Domain Id=\"any\">"
      "<General><Interfaces><NetworkInterface name=\"lo\" multicast=\"false\"/></Interfaces>"
      "<AllowMulticast>false</AllowMulticast><MaxMessageSize>65500B</MaxMessageSize></General>"
      "<Discovery><ParticipantIndex>auto</ParticipantIndex>"
      "<MaxAutoParticipantIndex>20</MaxAutoParticipantIndex>"
      "<Peers><Peer Address=\"127.0.0.1\"/></Peers></Discovery>"
      "</Domain></CycloneDDS>";
  const bool ok = ::write(fd, xml, std::strlen(xml)) == static_cast<ssize_t>(std::strlen(xml));
  ::close(fd);
  return ok ? std::string(path) : std::string();
}

}  // namespace
}  // namespace plr::bench

int main(int argc, char** argv) {
  using namespace plr::bench;
  bool quick = false, json = false;
  CLI::App app{
      "Cross-process one-way latency and throughput: shared memory (polling, futex, "
      "spin-then-futex) against a Unix socket and Cyclone DDS, then the kernel's "
      "publish path"};
  add_quick_flag(app, quick, "a tenth of the messages");
  add_json_flag(app, json);
  app.add_flag("--rt", g_realtime, "SCHED_FIFO for sender and receiver (needs CAP_SYS_NICE)");
  parse_or_exit(app, argc, argv);
  if (!pin(kSenderCpu)) {
    std::perror("sched_setaffinity/sched_setscheduler");
    return 1;
  }
  const std::string dds_config = write_dds_config();
  if (dds_config.empty()) {
    std::fprintf(stderr, "cannot write the DDS config\n");
    return 1;
  }
  ::setenv("CYCLONEDDS_URI", ("file://" + dds_config).c_str(), 1);
  void* mem =
      ::mmap(nullptr, sizeof(Shared), PROT_READ | PROT_WRITE, MAP_SHARED | MAP_ANONYMOUS, -1, 0);
  if (mem == MAP_FAILED) return 1;
  auto* shared = static_cast<Shared*>(mem);
  const std::string run = "bench" + std::to_string(::getpid());

  // Iterations per size: latency round trips; throughput messages for the
  // copying transports. Shm's cost does not depend on the size, so it sends
  // the same count at every size (a short burst would dodge the preemptions
  // a longer one suffers on a busy machine and look better than it is).
  const std::size_t div = quick ? 10 : 1;
  struct SizePlan {
    std::size_t size, lat, thr;
  };
  const SizePlan plans[] = {
      {64, 20000, 200000}, {4096, 20000, 100000}, {64 * 1024, 5000, 20000}, {4 << 20, 500, 200}};
  constexpr std::size_t kShmThroughput = 200000;
  // Only transports whose reader sleeps feel the idle state's exit.
  const bool can_wake0 = plr::shm::WakeLatencyRequest::hold(0).has_value();
  struct Variant {
    Kind kind;
    bool wake0;
  };
  std::vector<Variant> variants{{Kind::kShmPoll, false}, {Kind::kShmBlock, false},
                                {Kind::kShmSpin, false}, {Kind::kShmBlockSameCore, false},
                                {Kind::kUds, false},     {Kind::kDds, false}};
  if (can_wake0) {
    for (Kind k : {Kind::kShmBlock, Kind::kUds, Kind::kDds}) variants.push_back({k, true});
  } else if (!json) {
    std::printf("(no wake0 rows: /dev/cpu_dma_latency is not writable; run as root)\n");
  }
  std::vector<Row> rows;
  for (const SizePlan& p : plans) {
    for (const Variant& v : variants) {
      const bool shm = is_shm(v.kind);
      const std::size_t lat = p.lat / div, thr = (shm ? kShmThroughput : p.thr) / div;
      rows.push_back(run_case(Case{v.kind, v.wake0, p.size, std::max<std::size_t>(lat, 50),
                                   std::max<std::size_t>(thr, 20)},
                              shared, run));
      if (!json) {
        const Row& r = rows.back();
        if (r.ok) {
          std::printf("%-8s %-16s p50 %9.2f us  p99 %9.2f us  %12.0f msg/s  %10.1f MiB/s\n",
                      size_label(r.size).c_str(), row_label(r).c_str(), r.p50_us, r.p99_us,
                      r.msgs_per_s, r.mib_per_s);
        } else {
          std::printf("%-8s %-16s FAILED: %s\n", size_label(r.size).c_str(), row_label(r).c_str(),
                      r.error.c_str());
        }
        std::fflush(stdout);
      }
    }
  }
  std::vector<KernelRow> kernel_rows = run_kernel_path(quick, run + "k");
  nlohmann::json kernel_json = nlohmann::json::array();
  if (!json) std::printf("\nkernel publish path, %s\n", kernel_path_description());
  for (const KernelRow& r : kernel_rows) {
    if (!json) print(r);
    kernel_json.push_back(to_json(r));
  }
  (void)plr::shm::remove_run_segments(run);
  (void)plr::shm::remove_run_segments(run + "k");
  ::unlink(dds_config.c_str());

  auto find = [&](Kind k, std::size_t s, bool wake0 = false) -> const Row* {
    for (const Row& r : rows) {
      if (r.kind == k && r.size == s && r.wake0 == wake0 && r.ok) return &r;
    }
    return nullptr;
  };
  const Row* dds64 = find(Kind::kDds, 64);
  const Row* poll64 = find(Kind::kShmPoll, 64);
  const Row* block64 = find(Kind::kShmBlock, 64);
  const Row* spin64 = find(Kind::kShmSpin, 64);
  const Row* same64 = find(Kind::kShmBlockSameCore, 64);
  const Row* dds64w = find(Kind::kDds, 64, true);
  const Row* block64w = find(Kind::kShmBlock, 64, true);
  const char* timed =
      "one-way latency = receiver clock when the message is in hand - sender clock before "
      "send (shm: before loan(); shm payload is not copied or rewritten, a 16-byte stamp is "
      "written into the loaned slot and read in place; UDS and DDS copy every byte). "
      "Throughput: back-to-back reliable sends until the receiver has all of them.";
  if (json) {
    nlohmann::json j;
    j["pinning"] = {{"sender_cpu", kSenderCpu},
                    {"receiver_cpu", kReceiverCpu},
                    {"receiver_cpu_shm_futex_1cpu", kSenderCpu},
                    {"shm_spin50_spin_us", kSpinUs},
                    {"sched", g_realtime ? "SCHED_FIFO 10" : "SCHED_OTHER"}};
    j["quick"] = quick;
    j["timed"] = timed;
    j["results"] = nlohmann::json::array();
    for (const Row& r : rows) {
      nlohmann::json o{{"transport", name(r.kind)},
                       {"wake0", r.wake0},
                       {"size_bytes", r.size},
                       {"ok", r.ok},
                       {"latency_iterations", r.latency_iters},
                       {"throughput_messages", r.throughput_iters}};
      if (r.ok) {
        o["latency_p50_us"] = r.p50_us;
        o["latency_p99_us"] = r.p99_us;
        o["throughput_msgs_per_s"] = r.msgs_per_s;
        o["throughput_mib_per_s"] = r.mib_per_s;
      } else {
        o["error"] = r.error;
      }
      j["results"].push_back(o);
    }
    if (dds64 && poll64) j["dds_over_shm_poll_64B_p50"] = dds64->p50_us / poll64->p50_us;
    if (dds64 && block64) j["dds_over_shm_futex_64B_p50"] = dds64->p50_us / block64->p50_us;
    if (dds64 && spin64) j["dds_over_shm_spin50_64B_p50"] = dds64->p50_us / spin64->p50_us;
    if (dds64 && same64) j["dds_over_shm_futex_1cpu_64B_p50"] = dds64->p50_us / same64->p50_us;
    if (dds64w && block64w)
      j["wake0_dds_over_shm_futex_64B_p50"] = dds64w->p50_us / block64w->p50_us;
    j["kernel_path"] = kernel_json;
    std::printf("%s\n", j.dump(2).c_str());
  } else {
    std::printf("\npinning: sender CPU %d, receiver CPU %d (forked process), %s\ntimed: %s\n",
                kSenderCpu, kReceiverCpu, g_realtime ? "SCHED_FIFO 10" : "SCHED_OTHER", timed);
    std::printf("shm-spin50: blocking topic, spin_us %u; shm-futex-1cpu: receiver on CPU %d too\n",
                kSpinUs, kSenderCpu);
    if (dds64 && poll64 && block64 && spin64 && same64) {
      std::printf(
          "64 B p50: DDS / shm-poll = %.0fx, / shm-futex = %.1fx, / shm-spin50 = %.0fx, / "
          "shm-futex-1cpu = %.1fx\n",
          dds64->p50_us / poll64->p50_us, dds64->p50_us / block64->p50_us,
          dds64->p50_us / spin64->p50_us, dds64->p50_us / same64->p50_us);
    }
    if (dds64w && block64w) {
      std::printf(
          "64 B p50, wake0 (idle CPUs wake within 0 us): shm-futex %.2f us, DDS / "
          "shm-futex = %.1fx\n",
          block64w->p50_us, dds64w->p50_us / block64w->p50_us);
    }
  }
  ::munmap(mem, sizeof(Shared));
  for (const Row& r : rows) {
    if (!r.ok) return 1;
  }
  for (const KernelRow& r : kernel_rows) {
    if (!r.ok) return 1;
  }
  return 0;
}
