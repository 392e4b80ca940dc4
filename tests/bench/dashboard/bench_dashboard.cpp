// bench_dashboard: what the web monitor (plugins/monitor_web) costs the
// pipeline's process. An in-process kernel gets a small unloading job's
// traffic on its bus (an A1-sized world of 170 boxes with a 16 m trailer's
// octree, as the simulator publishes it during every motion, the executor's
// state with a 60-point curve, progress and clock, each at 10 Hz),
// once without and once with the monitor pushing the dashboard at 10 Hz to a
// connected page and streaming two topics and the 3D scene (/scene, a
// foxglove.SceneUpdate at 10 Hz) to a Foxglove client. The cost is
// the process's CPU time minus the feeder's and the clients' own threads,
// with the monitor minus without, as a share of one core.
//   bench_dashboard [--quick] [--json]
#include "bench_cli.hpp"
#include "bench_util.hpp"
#include "kernel.hpp"
#include "pipeline_config.hpp"
#include "test_endpoint.hpp"

#include <plr/message.hpp>
#include <plr/messages.hpp>

#include <spdlog/spdlog.h>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <nlohmann/json.hpp>

#include <sys/resource.h>
#include <time.h>

#include <atomic>
#include <chrono>
#include <cstring>
#include <iostream>
#include <thread>

namespace {

using namespace plr;
using Clock = std::chrono::steady_clock;
namespace net = boost::asio;
namespace beast = boost::beast;
using tcp = net::ip::tcp;

double process_cpu_s() {
  rusage u{};
  ::getrusage(RUSAGE_SELF, &u);
  return static_cast<double>(u.ru_utime.tv_sec + u.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

double cpu_s(clockid_t clock) {
  timespec t{};
  ::clock_gettime(clock, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

clockid_t cpu_clock(std::thread& t) {
  clockid_t c{};
  ::pthread_getcpuclockid(t.native_handle(), &c);
  return c;
}

std::uint16_t free_port() {
  net::io_context ioc;
  tcp::acceptor a(ioc, {net::ip::make_address("127.0.0.1"), 0});
  return a.local_endpoint().port();
}

// The bus traffic of a small unloading run, at `hz`.
class Feeder {
 public:
  Feeder(kernel::Bus& bus, double hz) : bus_(bus), hz_(hz) {
    world_ = advertise<msg::WorldState>("world");
    state_ = advertise<msg::ExecutorState>("executor/state");
    progress_ = advertise<msg::Progress>("progress");
    clock_ = advertise<msg::Clock>("clock");
  }
  ~Feeder() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
    bus_.remove_endpoint(&endpoint_);
  }
  void start() {
    bus_.set_live(&endpoint_, true);
    thread_ = std::thread([this] { loop(); });
  }
  clockid_t clock() { return cpu_clock(thread_); }

 private:
  template <class T>
  std::uint64_t advertise(const std::string& topic) {
    return *bus_.advertise(&endpoint_, topic, MessageTraits<T>::type_id(), 1);
  }
  void publish(std::uint64_t publisher, const flatbuffers::FlatBufferBuilder& fbb) {
    std::uint8_t* data = nullptr;
    plr_msg* m = bus_.loan(publisher, fbb.GetSize(), &data);
    std::memcpy(data, fbb.GetBufferPointer(), fbb.GetSize());
    m->offset = 0;
    m->size = fbb.GetSize();
    (void)bus_.publish(publisher, m);
  }
  void loop() {
    auto next = Clock::now();
    for (std::uint32_t tick = 0; !stop_; ++tick) {
      next += std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1 / hz_));
      std::this_thread::sleep_until(next);
      flatbuffers::FlatBufferBuilder w;
      std::vector<msg::BoxState> boxes;
      for (std::uint32_t i = 0; i < kBoxes; ++i)
        boxes.emplace_back(i, msg::Vec3(0.4, 0.4, 0.4),
                           msg::Pose(msg::Vec3(14.0 - 0.4 * (i / 36), -1.0 + 0.4 * (i % 6),
                                               0.2 + 0.4 * ((i / 6) % 6)),
                                     msg::Quat(0, 0, 0, 1)),
                           0.0);
      const std::vector<double> q{0.001 * tick, 0.1, 0.2, 0.3, 0.4, 0.0, 0.0, 0.0};
      const auto robot = msg::CreateJointStateDirect(w, &q);
      const msg::Vec3 trailer(2.5, 2.7, 16.0);
      w.Finish(msg::CreateWorldStateDirect(w, 0, &trailer, &octree_, 0.05, &boxes, robot, nullptr,
                                           tick / 10, false));
      publish(world_, w);
      flatbuffers::FlatBufferBuilder s;
      std::vector<msg::CurveSample> curve;
      for (std::uint32_t i = 0; i < 60; ++i) curve.emplace_back(0.5 * i, i / 2);
      s.Finish(msg::CreateExecutorStateDirect(s, "#3 PickMidLeft", "plan: arm", 0, 0, 30, tick / 10,
                                              0.1 * tick, &curve, nullptr));
      publish(state_, s);
      flatbuffers::FlatBufferBuilder p;
      p.Finish(msg::CreateProgress(p, 0.1 * tick, 30, tick / 10));
      publish(progress_, p);
      flatbuffers::FlatBufferBuilder c;
      c.Finish(msg::CreateClock(c, tick * 100'000'000ll));
      publish(clock_, c);
    }
  }

  static constexpr std::uint32_t kBoxes = 170;
  kernel::Bus& bus_;
  double hz_;
  // The size of a 16 m trailer's octree at 5 cm (the monitor does not read it).
  const std::vector<std::uint8_t> octree_ = std::vector<std::uint8_t>(57'000, 0x55);
  kernel::testing::TestEndpoint endpoint_{"feeder"};
  std::uint64_t world_ = 0, state_ = 0, progress_ = 0, clock_ = 0;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// A WebSocket client reading everything it is sent (a page or Foxglove).
class Reader {
 public:
  Reader(std::uint16_t port, bool foxglove) {
    thread_ = std::thread([this, port, foxglove] {
      try {
        net::io_context ioc;
        beast::websocket::stream<tcp::socket> ws(ioc);
        ws.next_layer().connect({net::ip::make_address("127.0.0.1"), port});
        if (foxglove)
          ws.set_option(
              beast::websocket::stream_base::decorator([](beast::websocket::request_type& r) {
                r.set(beast::http::field::sec_websocket_protocol, "foxglove.websocket.v1");
              }));
        ws.handshake("127.0.0.1", foxglove ? "/" : "/ws");
        std::uint32_t subscribed = 0, scene = 0;
        while (!stop_) {
          beast::flat_buffer b;
          ws.read(b);
          bytes_ += b.size();
          ++messages_;
          if (foxglove && ws.got_binary() && b.size() >= 5) {
            // Opcode 1, then the subscription id (little-endian).
            std::uint32_t sub = 0;
            std::memcpy(&sub, static_cast<const char*>(b.data().data()) + 1, 4);
            if (scene != 0 && sub == scene) {
              ++scene_messages_;
              scene_bytes_ += b.size();
            }
          }
          if (!foxglove || ws.got_binary()) continue;
          const auto j = nlohmann::json::parse(beast::buffers_to_string(b.data()), nullptr, false);
          if (!j.is_object() || j.value("op", "") != "advertise") continue;
          for (const auto& c : j["channels"])
            if (c["topic"] == "world" || c["topic"] == "executor/state" || c["topic"] == "/scene") {
              if (c["topic"] == "/scene") scene = subscribed + 1;
              const nlohmann::json sub = {
                  {"op", "subscribe"},
                  {"subscriptions", {{{"id", ++subscribed}, {"channelId", c["id"]}}}}};
              ws.text(true);
              ws.write(net::buffer(sub.dump()));
            }
        }
      } catch (const std::exception&) {
        // The server went away: the run is over.
      }
    });
  }
  // Called after the server stopped (its close ends the blocking read).
  void join() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  clockid_t clock() { return cpu_clock(thread_); }
  std::uint64_t messages() const { return messages_; }
  std::uint64_t bytes() const { return bytes_; }
  std::uint64_t scene_messages() const { return scene_messages_; }
  std::uint64_t scene_bytes() const { return scene_bytes_; }

 private:
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> messages_{0}, bytes_{0}, scene_messages_{0}, scene_bytes_{0};
  std::thread thread_;
};

struct Figures {
  double wall_s = 0, process_cpu_s = 0, others_cpu_s = 0;
  std::uint64_t page_messages = 0, page_bytes = 0, foxglove_messages = 0;
  std::uint64_t scene_messages = 0, scene_bytes = 0;
  double cost() const { return (process_cpu_s - others_cpu_s) / wall_s; }
};

Figures measure(bool monitor, double seconds, double hz) {
  const auto port = free_port();
  std::string yaml = "pipeline: bench_dashboard\nplugin_paths: [" PLR_PLUGIN_DIR "]\nnodes:\n";
  yaml += monitor ? "  monitor: {plugin: monitor_web, params: {port: " + std::to_string(port) +
                        ", update_hz: " + std::to_string(hz) + "}}\n"
                  : "  idle: {plugin: demo_doubler}\n";
  auto config = kernel::parse_pipeline_config(yaml, "bench.yaml");
  if (!config) throw std::runtime_error(config.error().message);
  Figures f;
  auto k = std::make_unique<kernel::Kernel>(*config, "main", "");
  auto feeder = std::make_unique<Feeder>(k->bus(), hz);
  if (auto s = k->start(); !s) throw std::runtime_error(s.error().message);
  std::unique_ptr<Reader> page, foxglove;
  if (monitor) {
    page = std::make_unique<Reader>(port, false);
    foxglove = std::make_unique<Reader>(port, true);
  }
  // Settled: connected, subscribed, the first telemetry sent.
  std::this_thread::sleep_for(std::chrono::milliseconds(1500));
  feeder->start();
  // The feeder's and the clients' threads are not the pipeline's cost.
  std::vector<clockid_t> others{feeder->clock()};
  if (monitor) others.insert(others.end(), {page->clock(), foxglove->clock()});
  const auto others_cpu = [&] {
    double sum = 0;
    for (auto c : others) sum += cpu_s(c);
    return sum;
  };
  const auto t0 = Clock::now();
  const double cpu0 = process_cpu_s(), others0 = others_cpu();
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  f.process_cpu_s = process_cpu_s() - cpu0;
  f.others_cpu_s = others_cpu() - others0;
  f.wall_s = std::chrono::duration<double>(Clock::now() - t0).count();
  feeder.reset();
  k->stop();
  k.reset();
  if (page) {
    page->join();
    foxglove->join();
    f.page_messages = page->messages();
    f.page_bytes = page->bytes();
    f.foxglove_messages = foxglove->messages();
    f.scene_messages = foxglove->scene_messages();
    f.scene_bytes = foxglove->scene_bytes();
  }
  return f;
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false, json = false;
  CLI::App app{"The web monitor's CPU cost to the pipeline's process at 10 Hz"};
  plr::bench::add_quick_flag(app, quick, "5 s per case instead of 20");
  plr::bench::add_json_flag(app, json);
  plr::bench::parse_or_exit(app, argc, argv);
  spdlog::set_level(spdlog::level::warn);
  const double seconds = quick ? 5 : 20;
  const double hz = 10;
  plr::bench::Progress progress("bench_dashboard", 2);
  const auto without = measure(false, seconds, hz);
  progress.step("without the monitor");
  const auto with = measure(true, seconds, hz);
  progress.step("with the monitor");
  progress.finish();
  const double cost = with.cost() - without.cost();
  if (json) {
    std::cout << nlohmann::json{{"seconds", seconds},
                                {"update_hz", hz},
                                {"cpu_without", without.cost()},
                                {"cpu_with", with.cost()},
                                {"monitor_cost_of_a_core", cost},
                                {"page_messages", with.page_messages},
                                {"page_bytes", with.page_bytes},
                                {"foxglove_messages", with.foxglove_messages},
                                {"scene_messages", with.scene_messages},
                                {"scene_bytes", with.scene_bytes}}
                     .dump()
              << "\n";
  } else {
    std::printf("bench_dashboard: %.0f s at %.0f Hz (world, executor state, progress, clock)\n",
                seconds, hz);
    std::printf("%-34s %10s\n", "", "% of a core");
    std::printf("%-34s %10.2f\n", "pipeline process, no monitor", 100 * without.cost());
    std::printf("%-34s %10.2f\n", "with monitor + page + Foxglove", 100 * with.cost());
    std::printf("%-34s %10.2f\n", "monitor's cost", 100 * cost);
    std::printf(
        "page: %llu updates (%.1f kB each); Foxglove: %llu messages, of which %llu "
        "scenes (%.1f kB each)\n",
        static_cast<unsigned long long>(with.page_messages),
        with.page_messages ? with.page_bytes / 1e3 / with.page_messages : 0.0,
        static_cast<unsigned long long>(with.foxglove_messages),
        static_cast<unsigned long long>(with.scene_messages),
        with.scene_messages ? with.scene_bytes / 1e3 / with.scene_messages : 0.0);
  }
  return 0;
}
