// The truck POMDP and the generator on tiny worlds: a first action that
// depends on the masses, workers that die, a generation resumed from its
// stored results.
#include <gtest/gtest.h>

#include <fmt/format.h>

#include <signal.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <thread>

#include "plr/jobs/in_process_runner.hpp"
#include "plr/jobs/messages.hpp"
#include "plr/sim/testing/library_fingerprint.hpp"
#include "plr/sim/testing/worlds.hpp"
#include "truck/fidelity_check.hpp"
#include "truck/generate.hpp"
#include "truck/strategy_job.hpp"
#include "truck/svg.hpp"
#include "truck/worker_runner.hpp"

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

// sim::testing::small_scene_observation() as JSON.
constexpr char kObservation[] =
    R"({"h_pile":0.55,"pile_mid":0.25,"pile_high":0.4,"wall_mid":1.2,"wall_high":1.9})";

Problem block_problem(const std::string& name, const std::vector<double>& masses) {
  Problem p;
  p.name = name;
  p.family = "test";
  p.world = block();
  p.observation_json = kObservation;
  for (const double m : masses) {
    sim::World w = p.world;
    for (sim::Box& b : w.boxes) b.mass = m + 0.1 * b.id;
    p.particles.push_back(w);
  }
  return p;
}

actions::Rig& rig() {
  static auto r = actions::make_rig(kObservation).value();
  return *r;
}

// Simulations in this process, one after the other.
struct InProcess {
  InProcess() { actions::add_sim_action(kinds); }
  jobs::Kinds kinds;
  jobs::InProcessRunner runner{kinds};
  Simulator simulator{runner, 1, kObservation};
};

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
    for (const auto& w : p.particles) roots.push_back(actions::start_state(rig(), w).value());
    for (int a = 0; a < sim::kNumActions; ++a) {
      double v = 0;
      for (const SimOutcome& r : roots) {
        const auto out = actions::simulate(rig(), {r.state, static_cast<sim::Action>(a)});
        ASSERT_TRUE(out) << out.error().message;
        v -= out->robot_time_s + (out->observation == kEmptyObservation
                                      ? 0.0
                                      : o.truck.seconds_per_box * out->boxes_left);
      }
      v /= static_cast<double>(roots.size());
      if (v > best_value + 1e-9) best_value = v, best = static_cast<sim::Action>(a);
    }
    InProcess local;
    const auto result = generate(p, o, rig(), local.simulator, nullptr);
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
  InProcess local;
  const auto alone = generate(p, o, rig(), local.simulator, nullptr);
  ASSERT_TRUE(alone) << alone.error().message;

  WorkerOptions options;
  options.local.command = {PLR_SIM_WORKER};
  options.local.workers = 2;
  auto pool = WorkerRunner::create(options);
  ASSERT_TRUE(pool) << pool.error().message;
  Simulator simulator(**pool, (*pool)->workers(), p.observation_json);
  // SIGKILL the first worker while it simulates, once the search has begun
  // (this small problem may be solved within the root's batch).
  const pid_t victim = (*pool)->pids()[0];
  std::atomic<bool> armed{false}, killed{false}, done{false};
  std::thread killer([&] {
    while (!done && !killed) {
      if (armed && simulator.busy() == 2) killed = ::kill(victim, SIGKILL) == 0;
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  });
  const auto pooled = generate(p, o, rig(), simulator, nullptr, [&](const GenerateProgress&) {
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
class InstantRemoteCall final : public RemoteCall {
 public:
  InstantRemoteCall(jobs::Bytes request, bool fail) : request_(std::move(request)), fail_(fail) {}
  bool done() const override { return true; }
  plr::Expected<jobs::Bytes> take() override {
    if (fail_)
      return plr::make_error(PLR_ERR_UNAVAILABLE, "kernel 'w' providing 'sim/simulate' is gone");
    auto message = jobs::decode_message(request_.data(), request_.size(), "request");
    if (!message) return message.error();
    // Both remote slots' threads call here: one simulation, one at a time.
    static std::mutex m;
    static const InProcess here;
    std::lock_guard lock(m);
    return jobs::encode_reply(message->id, here.kinds.run(message->job));
  }

 private:
  jobs::Bytes request_;
  bool fail_;
};

TEST(Generator, RemoteCallsThatFailAreIssuedAgainAndChangeNothing) {
  GenerateOptions o;
  o.truck.horizon = 2;
  o.trials = 3;
  const Problem p = block_problem("block", {4.0, 30.0});
  InProcess local;
  const auto alone = generate(p, o, rig(), local.simulator, nullptr);
  ASSERT_TRUE(alone) << alone.error().message;

  for (const unsigned local_workers : {0u, 1u}) {
    std::atomic<int> calls{0};
    WorkerOptions options;
    options.local.command = {PLR_SIM_WORKER};
    options.local.workers = local_workers;
    options.remote_workers = 2;
    options.remote_retry_s = 0.01;
    options.remote_send = [&](const jobs::Bytes& request) {
      return std::make_unique<InstantRemoteCall>(request, ++calls <= 5);
    };
    auto pool = WorkerRunner::create(options);
    ASSERT_TRUE(pool) << pool.error().message;
    EXPECT_EQ((*pool)->workers(), static_cast<int>(local_workers) + 2);
    Simulator simulator(**pool, (*pool)->workers(), p.observation_json);
    const auto pooled = generate(p, o, rig(), simulator, nullptr);
    ASSERT_TRUE(pooled) << pooled.error().message;
    EXPECT_EQ(entry_fingerprint(pooled->entry), entry_fingerprint(alone->entry)) << local_workers;
    // More failures than max_attempts, yet no job was given up: a kernel
    // gone is not the job's fault.
    EXPECT_EQ((*pool)->remote_failures(), 5u);
    EXPECT_GT((*pool)->remote_done(), 0u);
  }
}

TEST(Generator, ResumedFromItsStoredResultsEndsWithTheSameStrategy) {
  TempDir dir;
  GenerateOptions o;
  o.truck.horizon = 2;
  o.trials = 4;
  const Problem p = block_problem("block", {4.0, 30.0});
  InProcess local;
  const auto whole = generate(p, o, rig(), local.simulator, nullptr);
  ASSERT_TRUE(whole) << whole.error().message;

  auto store = jobs::Store::open(dir / "store");
  ASSERT_TRUE(store);
  const auto cut = generate(p, o, rig(), local.simulator, &*store,
                            [](const GenerateProgress& g) { return g.trials < 2; });
  ASSERT_FALSE(cut);
  EXPECT_EQ(cut.error().code, PLR_ERR_CANCELLED);
  // A kill in the middle of a write leaves a result cut short behind: it
  // counts as missing and is simulated again.
  std::vector<fs::path> results;
  for (const auto& f : fs::directory_iterator(dir / "store/results")) results.push_back(f.path());
  ASSERT_GT(results.size(), 1u);
  fs::resize_file(results.front(), fs::file_size(results.front()) / 2);

  const auto resumed = generate(p, o, rig(), local.simulator, &*store);
  ASSERT_TRUE(resumed) << resumed.error().message;
  EXPECT_LT(resumed->simulated, whole->simulated);
  EXPECT_EQ(entry_fingerprint(resumed->entry), entry_fingerprint(whole->entry));
  EXPECT_NE(strategy_svg(resumed->entry.strategy)
                .find(sim::to_string(resumed->entry.strategy.nodes[0].action)),
            std::string::npos);
}

// Where `strategy` ends on a particle, found by running it by hand (one
// action at a time on the rig, no truck model): the observations seen, the
// state there, and whether the trailer is empty.
struct Walked {
  std::vector<sim::Observation> path;
  SimOutcome state;
  bool empty = false;
};

Walked walk(const sim::Strategy& strategy, SimOutcome state) {
  Walked w;
  std::uint32_t node = strategy.root;
  for (;;) {
    auto next = actions::simulate(rig(), {state.state, strategy.nodes[node].action});
    EXPECT_TRUE(next) << next.error().message;
    if (!next) return w;
    state = *next;
    if (state.observation == kEmptyObservation) {
      w.empty = true;
      break;
    }
    w.path.push_back(static_cast<sim::Observation>(state.observation));
    const auto child = strategy.next(node, w.path.back());
    if (!child) break;
    node = *child;
  }
  w.state = state;
  return w;
}

TEST(Continuation, StartsFromTheBeliefItsParentReachesAtTheLeaf) {
  GenerateOptions o;
  o.truck.horizon = 1;
  o.trials = 2;
  // Light, the block goes at once; heavy, it stays: two leaves at least
  // until the trailer is empty on both.
  const Problem p = block_problem("block", {4.0, 30.0, 31.0});
  InProcess local;
  const auto parent = generate(p, o, rig(), local.simulator, nullptr);
  ASSERT_TRUE(parent) << parent.error().message;
  const auto picked = continued_leaves(parent->leaves, 1.0);
  ASSERT_EQ(picked.size(), 1u);
  const Leaf& leaf = parent->leaves[picked[0]];
  ASSERT_FALSE(leaf.empty);
  auto next = continuation(p, parent->leaves, picked[0], rig());
  ASSERT_TRUE(next) << next.error().message;
  const auto child = generate(*next, o, rig(), local.simulator, nullptr);
  ASSERT_TRUE(child) << child.error().message;
  const sim::LibraryEntry& e = child->entry;
  EXPECT_EQ(e.name, fmt::format("block.{}", picked[0] + 1));
  EXPECT_EQ(e.parent, "block");
  EXPECT_EQ(e.leaf, leaf.path);

  // The parent's strategy run by hand on each particle: those whose
  // observations are the leaf's, in the states they end in, are the
  // continuation's belief; the others are not in it.
  std::vector<sim::StartParticle> expected;
  std::size_t most = 0;
  std::map<std::pair<std::vector<sim::Observation>, bool>, std::size_t> reached;
  for (std::uint32_t i = 0; i < p.particles.size(); ++i) {
    const Walked w =
        walk(parent->entry.strategy, actions::start_state(rig(), p.particles[i]).value());
    most = std::max(most, w.empty ? 0 : ++reached[{w.path, w.empty}]);
    if (!w.empty && w.path == leaf.path)
      expected.push_back({i, actions::state_hash(*w.state.state), w.state.boxes_left});
  }
  ASSERT_FALSE(expected.empty());
  EXPECT_EQ(expected.size(), most) << "the continued leaf is the one most particles reach";
  EXPECT_EQ(e.start, expected);
  EXPECT_EQ(e.provenance.particles, expected.size());
  EXPECT_LT(e.start.front().boxes_left, p.world.boxes.size());
  // W is the trailer as the robot sees it there, not the parent's.
  EXPECT_EQ(e.world.boxes.size(), e.start.front().boxes_left);
}

TEST(Continuation, EveryLeafReachedByTheShareGetsOneAndTheMostReachedAlways) {
  const auto leaf = [](std::vector<sim::Observation> path, std::size_t n, bool empty = false) {
    Leaf l;
    l.path = std::move(path);
    l.empty = empty;
    l.particles.resize(n);
    l.states.resize(n);
    l.share = static_cast<double>(n) / 5.0;
    return l;
  };
  const auto o = [](int i) { return static_cast<sim::Observation>(i); };
  std::vector<Leaf> leaves = {leaf({o(1)}, 1), leaf({o(2)}, 2), leaf({o(3)}, 2), leaf({}, 0, true)};
  EXPECT_EQ(continued_leaves(leaves, 1.0), std::vector<std::size_t>{1});
  // On a tie, where more is left to unload.
  leaves[2].states[1].boxes_left = 1;
  EXPECT_EQ(continued_leaves(leaves, 1.0), std::vector<std::size_t>{2});
  leaves[2].states[1].boxes_left = 0;
  EXPECT_EQ(continued_leaves(leaves, 0.4), (std::vector<std::size_t>{1, 2}));
  EXPECT_EQ(continued_leaves(leaves, 0.2), (std::vector<std::size_t>{0, 1, 2}));
  EXPECT_TRUE(continued_leaves({leaf({}, 5, true)}, 0.2).empty());
}

// A job's fidelity reaches the worker process: the state it restores there
// runs at that level (the same bytes as the same job at that level here),
// not at the level of the worker's rig.
TEST(Fidelity, AWorkerProcessSimulatesAtTheLevelOfTheJob) {
  const Problem p = block_problem("block", {4.0});
  rig().set_fidelity(sim::Fidelity::kFull);
  const SimOutcome root = actions::start_state(rig(), p.particles[0]).value();
  std::vector<SimRequest> batch;
  for (int a = 0; a < sim::kNumActions; ++a) batch.push_back({root.state, sim::Action(a)});
  WorkerOptions options;
  options.local.command = {PLR_SIM_WORKER};
  options.local.workers = 1;
  auto pool = WorkerRunner::create(options);
  ASSERT_TRUE(pool) << pool.error().message;
  Simulator simulator(**pool, 1, p.observation_json);
  std::map<sim::Fidelity, std::vector<std::vector<std::uint8_t>>> here;
  for (const sim::Fidelity level : {sim::Fidelity::kFull, sim::Fidelity::kFast}) {
    simulator.set_fidelity(level);
    const auto there = simulator.run(batch);
    rig().set_fidelity(level);
    for (std::size_t i = 0; i < batch.size(); ++i) {
      ASSERT_TRUE(there[i].outcome) << there[i].outcome.error().message;
      const auto local = actions::simulate(rig(), batch[i]);
      ASSERT_TRUE(local) << local.error().message;
      EXPECT_EQ(*there[i].outcome->state, *local->state)
          << sim::to_string(batch[i].action) << " at " << sim::to_string(level);
      here[level].push_back(*local->state);
    }
  }
  rig().set_fidelity(sim::Fidelity::kFull);
  // The levels differ on this world, so a worker at the wrong one is seen.
  std::size_t differ = 0;
  for (std::size_t i = 0; i < batch.size(); ++i)
    differ += here[sim::Fidelity::kFull][i] != here[sim::Fidelity::kFast][i];
  EXPECT_GT(differ, 0u);
}

// The value of `strategy` from `start`, run by hand on the rig (at its
// fidelity), as the search counts a return: each action's robot time, the
// terminal estimate of the boxes left at the horizon; where the tree has no
// edge, the lower heuristic for the rest of the horizon.
double value_by_hand(const sim::Strategy& strategy, SimOutcome state, const TruckOptions& t) {
  double value = 0.0;
  std::uint32_t node = strategy.root;
  for (int depth = 1; depth <= t.horizon; ++depth) {
    auto next = actions::simulate(rig(), {state.state, strategy.nodes[node].action});
    EXPECT_TRUE(next) << next.error().message;
    if (!next) return NAN;
    state = *next;
    value -= state.robot_time_s;
    if (state.observation == kEmptyObservation) return value;
    if (depth == t.horizon) return value - t.seconds_per_box * state.boxes_left;
    const auto child = strategy.next(node, static_cast<sim::Observation>(state.observation));
    if (!child)
      return value - ((t.horizon - depth) * t.min_action_s + t.seconds_per_box * state.boxes_left);
    node = *child;
  }
  return value;
}

// Issue 45: a strategy that enters the library from a lower level is
// re-evaluated at full fidelity on fresh particles, and the library records
// both values.
TEST(Fidelity, AStrategyMadeAtFastIsValuedAtFullFidelityOnFreshParticles) {
  TempDir dir;
  GenerateOptions o;
  o.truck.horizon = 2;
  o.trials = 3;
  o.seed = 7;
  o.fidelity = sim::Fidelity::kFast;
  Problem p = make_problem(block(), sim::EnvFamily::kB1, "block", 2, o.seed);
  p.observation_json = kObservation;
  InProcess local;
  auto store = jobs::Store::open(dir / "store");
  ASSERT_TRUE(store);
  const auto made = generate(p, o, rig(), local.simulator, &*store);
  ASSERT_TRUE(made) << made.error().message;
  const sim::LibraryEntry& e = made->entry;
  EXPECT_EQ(e.fidelity, "fast");
  ASSERT_TRUE(e.check);
  EXPECT_EQ(e.check->full_particles, 2u);
  EXPECT_EQ(e.check->first_particle, kFreshParticle);

  // At its level: the tree on the generator's particles, simulated at fast.
  rig().set_fidelity(sim::Fidelity::kFast);
  double at_level = 0.0;
  for (const sim::World& w : p.particles) {
    at_level += value_by_hand(e.strategy, actions::start_state(rig(), w).value(), o.truck) / 2.0;
  }
  EXPECT_DOUBLE_EQ(e.check->value, at_level);

  // At full fidelity: the fresh particles, other masses than the generator's.
  rig().set_fidelity(sim::Fidelity::kFull);
  double at_full = 0.0;
  for (std::uint32_t j = 0; j < 2; ++j) {
    const sim::World fresh =
        sim::sample_masses(p.world, sim::EnvFamily::kB1,
                           sim::particle_seed(o.seed, static_cast<int>(kFreshParticle + j)));
    for (const sim::World& used : p.particles)
      for (std::size_t b = 0; b < fresh.boxes.size(); ++b)
        EXPECT_NE(fresh.boxes[b].mass, used.boxes[b].mass);
    const SimOutcome root = actions::start_state(rig(), fresh).value();
    at_full += value_by_hand(e.strategy, root, o.truck) / 2.0;
    // Simulated at full fidelity, kept under full fidelity's key.
    EXPECT_TRUE(fs::exists(store->result_file(Simulator::key(
        {root.state, e.strategy.nodes[e.strategy.root].action}, sim::Fidelity::kFull))));
  }
  EXPECT_DOUBLE_EQ(e.check->full_value, at_full);
  // The generator's own particles were never simulated at full fidelity.
  for (const sim::World& w : p.particles) {
    const SimOutcome root = actions::start_state(rig(), w).value();
    EXPECT_FALSE(fs::exists(store->result_file(Simulator::key(
        {root.state, e.strategy.nodes[e.strategy.root].action}, sim::Fidelity::kFull))));
  }

  // The library keeps both, and the tool shows them.
  sim::Library lib;
  lib.entries = {e};
  const auto bytes = sim::serialize(lib);
  const auto back = sim::deserialize_library(bytes.data(), bytes.size(), "l.plrl");
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->entries[0].fidelity, "fast");
  EXPECT_EQ(back->entries[0].check, e.check);
}

// A strategy handed to a Slurm task carries the level; at full its input is
// what it was before the setting.
TEST(Fidelity, AStrategyJobCarriesItsLevel) {
  StrategyJob job;
  job.options.fidelity = sim::Fidelity::kFast;
  const auto back = decode_strategy_job(encode(job));
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->options.fidelity, sim::Fidelity::kFast);
  job.options.fidelity = sim::Fidelity::kFull;
  const jobs::Bytes full = encode(job);
  EXPECT_EQ(std::string(full.begin(), full.end()).find("fidelity"), std::string::npos);
  EXPECT_EQ(decode_strategy_job(full)->options.fidelity, sim::Fidelity::kFull);
}

}  // namespace
}  // namespace plr::generator
