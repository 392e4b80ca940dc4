// A simulation's full state as FlatBuffers bytes (sdk/schemas/sim_state.fbs):
// continued by a new simulation in this process or another one, it repeats
// the original bit for bit; bytes that are corrupt, truncated or wrong in a
// field are refused with a message naming the field, never a crash.
#include <gtest/gtest.h>
#include <spawn.h>
#include <sys/wait.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <random>

#include "plr/msg/sim_state_generated.h"
#include "plr/sim/generators.hpp"
#include "plr/sim/physics.hpp"

extern char** environ;

namespace plr::sim {
namespace {

using Bytes = std::vector<std::uint8_t>;

struct Scene {
  Simulation sim;
  LinkGeometry belt;
  SuctionPlate plate;
};

// Everything a state holds: `pile` boxes of a B1 pile still tumbling, four
// 40 kg boxes stalling a sloped belt, a box held by the suction plate that
// lifts it, one box already unloaded, contact springs, Simbody coordinates.
Scene busy_scene(std::size_t pile) {
  World w = generate_world(EnvFamily::kB1, 11);
  w.boxes.resize(pile);
  LinkGeometry belt;
  belt.size = {2.0, 1.0, 0.05};
  belt.pose.linear() = Eigen::AngleAxisd(0.35, Eigen::Vector3d::UnitY()).toRotationMatrix();
  belt.pose.translation() = Eigen::Vector3d(8.0, 0.0, 0.7);
  belt.belt_speed = 0.5;
  belt.feeds_belt = true;
  const auto add = [&](std::uint32_t id, const Eigen::Isometry3d& pose, double mass) {
    Box b;
    b.id = id;
    b.size = {0.3, 0.3, 0.3};
    b.pose = pose;
    b.mass = mass;
    w.boxes.push_back(b);
  };
  for (int i = 0; i < 4; ++i) {
    add(static_cast<std::uint32_t>(201 + i),
        belt.pose * Eigen::Translation3d(0.6 - 0.4 * i, 0.0, 0.176), 40.0);
  }
  add(301, Eigen::Isometry3d(Eigen::Translation3d(4.0, 0.8, 0.15)), 10.0);
  add(302, Eigen::Isometry3d(Eigen::Translation3d(-0.1, 0.0, 0.15)), 5.0);  // out at once
  SuctionPlate plate;
  plate.pose =
      Eigen::Translation3d(4.0, 0.8, 0.301) * Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX());
  Scene s{Simulation(w), belt, plate};
  s.sim.set_robot_links({belt});
  s.sim.set_suction_plate(plate);
  EXPECT_EQ(s.sim.suction_on(), std::vector<std::uint32_t>{301});
  for (int k = 0; k < 15; ++k) {
    s.plate.pose.translation().z() += 0.002;
    s.sim.set_suction_plate(s.plate);
    s.sim.step(0.01);
  }
  return s;
}

bool same_bits(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return std::memcmp(a.matrix().data(), b.matrix().data(), sizeof(double) * 16) == 0;
}

void expect_same(const World& a, const World& b) {
  ASSERT_EQ(a.boxes.size(), b.boxes.size());
  for (std::size_t i = 0; i < a.boxes.size(); ++i) {
    EXPECT_EQ(a.boxes[i].id, b.boxes[i].id);
    EXPECT_TRUE(same_bits(a.boxes[i].pose, b.boxes[i].pose)) << "box " << a.boxes[i].id;
  }
}

std::string message_of(const Bytes& bytes) {
  const auto r = Snapshot::from_bytes(bytes.data(), bytes.size());
  return r ? "accepted" : r.error().message;
}

TEST(StateBytes, ANewSimulationContinuesBitForBit) {
  Scene s = busy_scene(40);
  ASSERT_GT(s.sim.stats().awake, 10);  // the pile is still falling
  ASSERT_EQ(s.sim.held_boxes(), std::vector<std::uint32_t>{301});
  ASSERT_EQ(s.sim.unloaded().size(), 1u);
  ASSERT_LT(s.sim.belt_loads().at(0).speed_fraction, 1.0);
  const Bytes bytes = s.sim.snapshot().to_bytes();
  auto snapshot = Snapshot::from_bytes(bytes.data(), bytes.size());
  ASSERT_TRUE(snapshot) << snapshot.error().message;
  EXPECT_EQ(snapshot->to_bytes(), bytes);
  EXPECT_EQ(snapshot->time(), s.sim.time());
  expect_same(snapshot->world(), s.sim.world());
  auto copy = Simulation::from_snapshot(*snapshot);
  ASSERT_TRUE(copy) << copy.error().message;
  const World before = s.sim.world();
  // The same commands to both: the plate carries its box on, a paddle
  // sweeps into the pile.
  LinkGeometry paddle;
  paddle.size = {0.3, 1.2, 0.3};
  for (int k = 0; k < 100; ++k) {
    s.plate.pose.translation().x() += 0.003;
    paddle.pose.translation() = Eigen::Vector3d(11.5 + 0.01 * k, 0.0, 0.16);
    for (Simulation* sim : {&s.sim, &copy.value()}) {
      sim->set_robot_links({s.belt, paddle});
      sim->set_suction_plate(s.plate);
      sim->step(0.01);
    }
  }
  expect_same(s.sim.world(), copy->world());
  EXPECT_EQ(s.sim.snapshot().to_bytes(), copy->snapshot().to_bytes());  // all of the state
  int moved = 0;
  for (std::size_t i = 0; i < before.boxes.size(); ++i)
    moved += !before.boxes[i].pose.isApprox(s.sim.world().boxes[i].pose, 1e-6);
  EXPECT_GT(moved, 10);
}

Bytes read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return Bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// The helper (state_replay_main.cpp) reads the bytes, steps 1 s and writes
// its final state; a process of its own, with its own heap and addresses.
TEST(StateBytes, AnotherProcessContinuesBitForBit) {
  Scene s = busy_scene(40);
  const std::string in = ::testing::TempDir() + "state_bytes_in.psim";
  const std::string out = ::testing::TempDir() + "state_bytes_out.psim";
  {
    const Bytes bytes = s.sim.snapshot().to_bytes();
    std::ofstream file(in, std::ios::binary);
    file.write(reinterpret_cast<const char*>(bytes.data()),
               static_cast<std::streamsize>(bytes.size()));
  }
  std::remove(out.c_str());
  std::string helper = PLR_STATE_REPLAY, steps = "100";
  char* argv[] = {helper.data(), const_cast<char*>(in.c_str()), const_cast<char*>(out.c_str()),
                  steps.data(), nullptr};
  pid_t pid = 0;
  ASSERT_EQ(posix_spawn(&pid, helper.c_str(), nullptr, nullptr, argv, environ), 0);
  for (int k = 0; k < 100; ++k) s.sim.step(0.01);
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status;
  const Bytes theirs = read_file(out);
  auto replayed = Snapshot::from_bytes(theirs.data(), theirs.size());
  ASSERT_TRUE(replayed) << replayed.error().message;
  EXPECT_EQ(replayed->time(), s.sim.time());
  expect_same(replayed->world(), s.sim.world());
  EXPECT_EQ(theirs, s.sim.snapshot().to_bytes());
}

TEST(StateBytes, RestoreTakesAnySimulationsSnapshot) {
  Scene big = busy_scene(40);
  World one;
  one.boxes.push_back(generate_world(EnvFamily::kA1, 1).boxes[0]);
  Simulation small(one);
  small.restore(big.sim.snapshot());
  expect_same(small.world(), big.sim.world());
  for (Simulation* sim : {&big.sim, &small}) sim->step(0.2);
  EXPECT_EQ(small.snapshot().to_bytes(), big.sim.snapshot().to_bytes());
}

TEST(StateBytes, EmptyAndMisalignedInput) {
  EXPECT_TRUE(Snapshot().to_bytes().empty());
  EXPECT_EQ(message_of({}), "sim state: no bytes");
  const auto none = Simulation::from_snapshot(Snapshot());
  ASSERT_FALSE(none);
  EXPECT_EQ(none.error().message, "from_snapshot: empty snapshot");
  Scene s = busy_scene(5);
  const Bytes bytes = s.sim.snapshot().to_bytes();
  Bytes shifted(bytes.size() + 1);
  std::memcpy(shifted.data() + 1, bytes.data(), bytes.size());
  const auto r = Snapshot::from_bytes(shifted.data() + 1, bytes.size());
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(r->to_bytes(), bytes);
  Bytes other = bytes;
  std::memcpy(other.data() + 4, "PLRS", 4);
  EXPECT_EQ(message_of(other),
            "sim state: not a SimulationState buffer (no \"PSIM\" file identifier)");
}

// States with few or no boxes, events or shapes: empty vectors land at any
// alignment (found by the fuzzer: an empty one read as misaligned).
TEST(StateBytes, SmallStatesRoundTrip) {
  const World pile = generate_world(EnvFamily::kB1, 2);
  for (std::size_t n = 0; n <= 6; ++n) {
    for (const int links : {0, 1, 2}) {
      World w = pile;
      w.boxes.resize(n);
      Simulation sim(w);
      sim.set_robot_links(std::vector<LinkGeometry>(static_cast<std::size_t>(links)));
      for (const int steps : {0, 1}) {
        if (steps > 0) sim.step(0.001);
        const Bytes bytes = sim.snapshot().to_bytes();
        const auto back = Snapshot::from_bytes(bytes.data(), bytes.size());
        ASSERT_TRUE(back) << n << " boxes, " << links << " links: " << back.error().message;
        EXPECT_EQ(back->to_bytes(), bytes);
      }
    }
  }
}

TEST(StateBytes, TruncatedBytesAreRefused) {
  Scene s = busy_scene(5);
  const Bytes bytes = s.sim.snapshot().to_bytes();
  for (std::size_t n = 0; n < bytes.size(); ++n) {
    const Bytes cut(bytes.begin(), bytes.begin() + static_cast<long>(n));
    const std::string m = message_of(cut);
    ASSERT_EQ(m.rfind("sim state: ", 0), 0u) << n << ": " << m;
  }
}

// Random byte changes: refused with a message, or (a change the checks let
// through, e.g. in a velocity) a simulation that steps.
TEST(StateBytes, CorruptedBytesAreRefusedOrStepSafely) {
  Scene s = busy_scene(5);
  const Bytes bytes = s.sim.snapshot().to_bytes();
  std::mt19937_64 rng(17);
  std::uniform_int_distribution<std::size_t> where(0, bytes.size() - 1);
  std::uniform_int_distribution<int> value(0, 255), count(1, 4);
  int refused = 0, accepted = 0;
  for (int trial = 0; trial < 1500; ++trial) {
    Bytes bad = bytes;
    for (int k = count(rng); k > 0; --k) bad[where(rng)] = static_cast<std::uint8_t>(value(rng));
    const auto r = Snapshot::from_bytes(bad.data(), bad.size());
    if (!r) {
      ASSERT_EQ(r.error().message.rfind("sim state: ", 0), 0u) << r.error().message;
      ++refused;
      continue;
    }
    auto sim = Simulation::from_snapshot(r.value());
    ASSERT_TRUE(sim);
    sim->step(0.002);
    ++accepted;
  }
  EXPECT_GT(refused, 100);
  EXPECT_GT(accepted, 100);
}

// Valid FlatBuffers with one wrong field each, built with the object API.
class FieldErrors : public ::testing::Test {
 protected:
  void SetUp() override {
    Scene s = busy_scene(5);
    bytes_ = s.sim.snapshot().to_bytes();
  }
  std::unique_ptr<msg::SimulationStateT> state() const {
    return msg::UnPackSimulationState(bytes_.data());
  }
  static std::string message_of(const msg::SimulationStateT& t) {
    flatbuffers::FlatBufferBuilder fbb;
    msg::FinishSimulationStateBuffer(fbb, msg::SimulationState::Pack(fbb, &t));
    return sim::message_of(Bytes(fbb.GetBufferPointer(), fbb.GetBufferPointer() + fbb.GetSize()));
  }
  static msg::SimBody with(const msg::SimBody& b, double mass, msg::SimBodyMode mode) {
    return msg::SimBody(b.id(), mode, b.size(), mass, b.pose(), b.velocity(), b.angular_velocity(),
                        b.still(), b.rest(), b.grip(), b.capacity(), b.load());
  }
  Bytes bytes_;
};

TEST_F(FieldErrors, Bodies) {
  auto t = state();
  EXPECT_EQ(message_of(*t), "accepted");
  ASSERT_GE(t->bodies.size(), 5u);
  t->bodies[3] = with(t->bodies[3], std::nan(""), t->bodies[3].mode());
  EXPECT_EQ(message_of(*t), "sim state: bodies[3].mass: must be in [0.001, 100000]");
  // A denormal mass made the accelerations infinite and Simbody's inertias
  // NaN: it threw from the first step (fuzzing).
  t = state();
  t->bodies[3] = with(t->bodies[3], 4.6e-308, msg::SimBodyMode::Awake);
  EXPECT_EQ(message_of(*t), "sim state: bodies[3].mass: must be in [0.001, 100000]");
  t = state();
  t->bodies[0] = with(t->bodies[0], 1.0, static_cast<msg::SimBodyMode>(7));
  EXPECT_EQ(message_of(*t), "sim state: bodies[0].mode: unknown value 7");
  t = state();
  const msg::SimBody& b = t->bodies[2];
  const msg::SimTransform skew(
      msg::SimMat3(msg::Vec3(1, 0.1, 0), msg::Vec3(0, 1, 0), msg::Vec3(0, 0, 1)),
      b.pose().translation());
  t->bodies[2] =
      msg::SimBody(b.id(), b.mode(), b.size(), b.mass(), skew, b.velocity(), b.angular_velocity(),
                   b.still(), b.rest(), b.grip(), b.capacity(), b.load());
  EXPECT_EQ(message_of(*t), "sim state: bodies[2].pose: rotation must be orthonormal and proper");
  t = state();
  // Two bodies of one id, one of them where another box is: the first step
  // threw from Simbody (NaN inertia; fuzzing).
  t->bodies[3] =
      msg::SimBody(t->bodies[1].id(), t->bodies[3].mode(), t->bodies[3].size(), t->bodies[3].mass(),
                   t->bodies[3].pose(), t->bodies[3].velocity(), t->bodies[3].angular_velocity(),
                   t->bodies[3].still(), t->bodies[3].rest(), t->bodies[3].grip(),
                   t->bodies[3].capacity(), t->bodies[3].load());
  EXPECT_EQ(message_of(*t), "sim state: bodies[3].id: box " + std::to_string(t->bodies[1].id()) +
                                " is there twice");
  t = state();
  t->bodies.resize(10001, t->bodies[0]);
  EXPECT_EQ(message_of(*t), "sim state: bodies: 10001 entries, at most 10000");
}

TEST_F(FieldErrors, CountsAndOrder) {
  auto t = state();
  t->link_targets.clear();
  EXPECT_EQ(message_of(*t), "sim state: links: 1 shapes but 0 link_targets");
  t = state();
  ASSERT_GE(t->pairs.size(), 2u);
  std::swap(t->pairs[0], t->pairs[1]);
  EXPECT_EQ(message_of(*t), "sim state: pairs[1]: not sorted by (a, b, kind)");
  t = state();
  ASSERT_FALSE(t->slots.empty());
  t->q.pop_back();
  EXPECT_EQ(message_of(*t).rfind("sim state: q: need 7 q and 6 u per slot", 0), 0u);
  t = state();
  // A stretch this long made the friction force infinite (fuzzing).
  const msg::SimPair& p = t->pairs[0];
  t->pairs[0] = msg::SimPair(p.a(), p.b(), p.kind(), msg::Vec3(-1.2e306, 0, 0), p.twist());
  EXPECT_EQ(message_of(*t), "sim state: pairs[0].bristle: longer than 1000 m");
  t = state();
  t->q[0] *= 2.0;
  EXPECT_EQ(message_of(*t), "sim state: q[0]: quaternion not unit");
  t = state();
  t->rebuild = false;
  t->slots.pop_back();
  t->q.resize(7 * t->slots.size());
  t->u.resize(6 * t->slots.size());
  EXPECT_EQ(message_of(*t).rfind("sim state: slots: must list exactly the awake bodies", 0), 0u);
  t = state();
  t->options->belt_inertia = 0.0;
  EXPECT_EQ(message_of(*t), "sim state: options.belt_inertia: must be in [1e-06, 1e+06]");
  t = state();
  t->options->step = 1e-300;  // a step that small would never finish an action
  EXPECT_EQ(message_of(*t), "sim state: options.step: must be in [1e-05, 0.01]");
  t = state();
  // The contact damping divides by gravity: a denormal one made it infinite,
  // the velocities NaN, and the first step threw from Simbody (fuzzing).
  t->options->gravity = 1e-310;
  EXPECT_EQ(message_of(*t), "sim state: options.gravity: must be in [0.1, 100]");
  t = state();
  t->plate.reset();
  EXPECT_EQ(message_of(*t), "sim state: plate: plate and plate_target come together");
}

// The pump's limit has a field of its own; bytes written before it carry
// the limit in the plates' extent.z, and still load with it.
TEST_F(FieldErrors, PumpLimit) {
  auto t = state();
  ASSERT_TRUE(t->plate && t->plate_target);
  EXPECT_EQ(t->plate->extent().z(), 0.0);
  EXPECT_EQ(t->plate_pump_max_force, SuctionPlate{}.pump_max_force);
  EXPECT_EQ(t->plate_target_pump_max_force, SuctionPlate{}.pump_max_force);
  t->plate_target_pump_max_force = -1.0;
  EXPECT_EQ(message_of(*t),
            "sim state: plate_target_pump_max_force: must be finite, > 0 and <= 1e+09");

  t = state();
  t->plate_pump_max_force = t->plate_target_pump_max_force = 0.0;
  for (auto* plate : {t->plate.get(), t->plate_target.get()}) {
    *plate = msg::SimPlate(plate->pose(), msg::Vec3(plate->extent().x(), plate->extent().y(), 700),
                           plate->cups_x(), plate->cups_y(), plate->cup_radius(),
                           plate->cup_force(), plate->reach(), plate->max_tilt());
  }
  flatbuffers::FlatBufferBuilder fbb;
  msg::FinishSimulationStateBuffer(fbb, msg::SimulationState::Pack(fbb, t.get()));
  const auto old = Snapshot::from_bytes(fbb.GetBufferPointer(), fbb.GetSize());
  ASSERT_TRUE(old) << old.error().message;
  const Bytes now = old->to_bytes();
  const auto back = msg::UnPackSimulationState(now.data());
  EXPECT_EQ(back->plate_pump_max_force, 700.0);
  EXPECT_EQ(back->plate_target_pump_max_force, 700.0);
  EXPECT_EQ(back->plate->extent().z(), 0.0);
}

}  // namespace
}  // namespace plr::sim
