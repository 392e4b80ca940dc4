// The truck POMDP and the generator on tiny worlds: a first action that
// depends on the masses, workers that die, a generation resumed from its
// journal.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <signal.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <thread>

#include "plr/sim/testing/library_fingerprint.hpp"
#include "plr/sim/testing/worlds.hpp"
#include "truck/generate.hpp"
#include "truck/svg.hpp"
#include "truck/worker_pool.hpp"

namespace plr::generator {
namespace {

namespace fs = std::filesystem;

class TempDir {
 public:
  TempDir() {
    std::string pattern = (fs::temp_directory_path() / "plr_generator_XXXXXX").string();
    path_ = mkdtemp(pattern.data());
  }
  ~TempDir() { fs::remove_all(path_); }
  fs::path operator/(const std::string& name) const { return path_ / name; }

 private:
  fs::path path_;
};

// Two columns of two 0.45 m boxes side by side in the centre third, front
// face at x = 5: light, the plate takes the block at once; heavy, its cups
// cannot hold it.
sim::World block() {
  sim::World w;
  w.trailer.depth = 8.0;
  std::uint32_t id = 1;
  for (double y : {-0.23, 0.23})
    for (int r = 0; r < 2; ++r) {
      sim::Box b;
      b.id = id++;
      b.size = {0.45, 0.45, 0.35};
      b.pose.translation() = Eigen::Vector3d(5.0 + 0.225, y, 0.175 + 0.35 * r);
      w.boxes.push_back(b);
    }
  return w;
}

Problem block_problem(const std::string& name, const std::vector<double>& masses) {
  Problem p;
  p.name = name;
  p.family = "test";
  p.world = block();
  p.observation_json =
      R"({"h_pile":0.55,"pile_mid":0.25,"pile_high":0.4,"wall_mid":1.2,"wall_high":1.9})";
  for (const double m : masses) {
    sim::World w = p.world;
    for (sim::Box& b : w.boxes) b.mass = m + 0.1 * b.id;
    p.particles.push_back(w);
  }
  return p;
}

JobRunner& runner() {
  static auto r = JobRunner::create(sim::testing::small_scene_observation()).value();
  return *r;
}

using sim::testing::entry_fingerprint;

TEST(Generator, FindsTheBestFirstActionWhichDependsOnTheMasses) {
  GenerateOptions o;
  o.truck.horizon = 1;
  o.trials = 20;
  o.target_gap = 1e-6;
  std::map<std::string, sim::Action> chosen;
  for (const auto& [name, masses] :
       {std::pair<std::string, std::vector<double>>{"light", {3.0, 4.0}},
        {"heavy", {32.0, 36.0}}}) {
    const Problem p = block_problem(name, masses);
    // The exact best first action: every action on every particle.
    double best_value = -1e300;
    sim::Action best{};
    std::vector<SimOutcome> roots;
    for (const auto& w : p.particles) roots.push_back(runner().start(w).value());
    for (int a = 0; a < sim::kNumActions; ++a) {
      double v = 0;
      for (const SimOutcome& r : roots) {
        const auto out = runner().run({r.state, static_cast<sim::Action>(a)});
        ASSERT_TRUE(out) << out.error().message;
        v -= out->robot_time_s + (out->observation == kEmptyObservation
                                      ? 0.0
                                      : o.truck.seconds_per_box * out->boxes_left);
      }
      v /= static_cast<double>(roots.size());
      if (v > best_value + 1e-9) best_value = v, best = static_cast<sim::Action>(a);
    }
    LocalSimulator local(runner());
    const auto result = generate(p, o, runner(), local, nullptr);
    ASSERT_TRUE(result) << result.error().message;
    const sim::Strategy& s = result->entry.strategy;
    EXPECT_EQ(sim::to_string(s.nodes[s.root].action), sim::to_string(best)) << name;
    EXPECT_NEAR(result->entry.lower, best_value, 1e-6) << name;
    EXPECT_NEAR(result->entry.upper, best_value, 1e-6) << name;
    chosen[name] = s.nodes[s.root].action;
    std::printf("%s: %s, value %.2f\n", name.c_str(), sim::to_string(chosen[name]).c_str(),
                best_value);
  }
  EXPECT_NE(chosen["light"], chosen["heavy"]);
}

TEST(Generator, AWorkerKilledMidRunChangesNothing) {
  GenerateOptions o;
  o.truck.horizon = 2;
  o.trials = 4;
  const Problem p = block_problem("block", {4.0, 30.0});
  LocalSimulator local(runner());
  const auto alone = generate(p, o, runner(), local, nullptr);
  ASSERT_TRUE(alone) << alone.error().message;

  WorkerPoolOptions options;
  options.command = PLR_SIM_WORKER;
  options.observation_json = p.observation_json;
  auto pool = WorkerPool::create(options);
  ASSERT_TRUE(pool) << pool.error().message;
  // SIGKILL the first worker while it simulates, once the search has begun
  // (this small problem may be solved within the root's batch).
  const pid_t victim = (*pool)->pids()[0];
  std::atomic<bool> armed{false}, killed{false}, done{false};
  std::thread killer([&] {
    while (!done && !killed) {
      if (armed && (*pool)->busy() == 2) killed = ::kill(victim, SIGKILL) == 0;
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  });
  const auto pooled = generate(p, o, runner(), **pool, nullptr, [&](const GenerateProgress&) {
    armed = true;
    return true;
  });
  done = true;
  killer.join();
  ASSERT_TRUE(pooled) << pooled.error().message;
  EXPECT_TRUE(killed);
  EXPECT_GE((*pool)->restarts(), 1u);
  EXPECT_EQ(entry_fingerprint(pooled->entry), entry_fingerprint(alone->entry));
}

// A remote worker whose calls complete at once: the first `failures` of
// them fail as a call to a kernel that went away does; the others run the
// job here. (The real transport, DDS between network namespaces, is
// tests/integration/remote_workers_test.cpp.)
class InstantRemoteJob final : public RemoteJob {
 public:
  InstantRemoteJob(std::vector<std::uint8_t> job, bool fail) : job_(std::move(job)), fail_(fail) {}
  bool done() const override { return true; }
  plr::Expected<std::vector<std::uint8_t>> take() override {
    if (fail_)
      return plr::make_error(PLR_ERR_UNAVAILABLE, "kernel 'w' providing 'sim/simulate' is gone");
    auto frame = actions::decode_frame(job_.data(), job_.size(), "job");
    if (!frame) return frame.error();
    flatbuffers::FlatBufferBuilder fbb;
    actions::build_result(fbb, frame->id, runner().run(frame->request));
    return std::vector<std::uint8_t>(fbb.GetBufferPointer(),
                                     fbb.GetBufferPointer() + fbb.GetSize());
  }

 private:
  std::vector<std::uint8_t> job_;
  bool fail_;
};

TEST(Generator, RemoteCallsThatFailAreIssuedAgainAndChangeNothing) {
  GenerateOptions o;
  o.truck.horizon = 2;
  o.trials = 3;
  const Problem p = block_problem("block", {4.0, 30.0});
  LocalSimulator local(runner());
  const auto alone = generate(p, o, runner(), local, nullptr);
  ASSERT_TRUE(alone) << alone.error().message;

  for (const int local_workers : {0, 1}) {
    int calls = 0;
    WorkerPoolOptions options;
    options.command = PLR_SIM_WORKER;
    options.workers = local_workers;
    options.observation_json = p.observation_json;
    options.remote_workers = 2;
    options.remote_retry_s = 0.01;
    options.remote_send = [&](const flatbuffers::FlatBufferBuilder& job) {
      return std::make_unique<InstantRemoteJob>(
          std::vector<std::uint8_t>(job.GetBufferPointer(), job.GetBufferPointer() + job.GetSize()),
          ++calls <= 5);
    };
    auto pool = WorkerPool::create(options);
    ASSERT_TRUE(pool) << pool.error().message;
    EXPECT_EQ((*pool)->workers(), local_workers + 2);
    const auto pooled = generate(p, o, runner(), **pool, nullptr);
    ASSERT_TRUE(pooled) << pooled.error().message;
    EXPECT_EQ(entry_fingerprint(pooled->entry), entry_fingerprint(alone->entry)) << local_workers;
    // More failures than max_attempts, yet no job was given up: a kernel
    // gone is not the job's fault.
    EXPECT_EQ((*pool)->remote_failures(), 5u);
    EXPECT_GT((*pool)->remote_done(), 0u);
  }
}

TEST(Generator, ResumedFromItsJournalEndsWithTheSameStrategy) {
  TempDir dir;
  GenerateOptions o;
  o.truck.horizon = 2;
  o.trials = 4;
  const Problem p = block_problem("block", {4.0, 30.0});
  LocalSimulator local(runner());
  const auto whole = generate(p, o, runner(), local, nullptr);
  ASSERT_TRUE(whole) << whole.error().message;

  {
    auto journal = Journal::open(dir / "j");
    ASSERT_TRUE(journal);
    const auto cut = generate(p, o, runner(), local, journal->get(),
                              [](const GenerateProgress& g) { return g.trials < 2; });
    ASSERT_FALSE(cut);
    EXPECT_EQ(cut.error().code, PLR_ERR_CANCELLED);
  }
  // A kill in the middle of a write leaves a torn record behind.
  const auto size = fs::file_size(dir / "j");
  ASSERT_GT(size, 100u);
  fs::resize_file(dir / "j", size - 50);

  auto journal = Journal::open(dir / "j");
  ASSERT_TRUE(journal);
  EXPECT_GT((*journal)->loaded_count(), 0u);
  EXPECT_GT((*journal)->dropped_bytes(), 0u);
  const auto resumed = generate(p, o, runner(), local, journal->get());
  ASSERT_TRUE(resumed) << resumed.error().message;
  EXPECT_LT(resumed->simulated, whole->simulated);
  EXPECT_EQ(entry_fingerprint(resumed->entry), entry_fingerprint(whole->entry));
  EXPECT_NE(strategy_svg(resumed->entry.strategy)
                .find(sim::to_string(resumed->entry.strategy.nodes[0].action)),
            std::string::npos);
}

}  // namespace
}  // namespace plr::generator
