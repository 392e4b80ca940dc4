// Contact, stacking, falling, robot pushing, snapshots.
#include <gtest/gtest.h>

#include <array>
#include <chrono>

#include "paddle_through_pile.hpp"
#include "plr/sim/generators.hpp"
#include "plr/sim/physics.hpp"

namespace plr::sim {
namespace {

Box make_box(std::uint32_t id, Eigen::Vector3d size, Eigen::Vector3d centre, double mass) {
  Box b;
  b.id = id;
  b.size = size;
  b.pose.translation() = centre;
  b.mass = mass;
  return b;
}

const Box& find(const World& w, std::uint32_t id) {
  for (const Box& b : w.boxes) {
    if (b.id == id) return b;
  }
  throw std::runtime_error("box missing");
}

// A column of `n` 0.4 m cubes at (x, y) on the floor.
World column(int n, double x = 10.0, double y = 0.0, double mass = 8.0) {
  World w;
  for (int i = 0; i < n; ++i) {
    w.boxes.push_back(
        make_box(static_cast<std::uint32_t>(i + 1), {0.4, 0.4, 0.4}, {x, y, 0.2 + 0.4 * i}, mass));
  }
  return w;
}

TEST(Physics, BoxRestsOnFloor) {
  World w = column(1);
  w.boxes[0].pose.translation().z() = 0.5;
  Simulation sim(w);
  EXPECT_GE(sim.settle(3.0), 0.0);
  const World settled = sim.world();  // a copy: keep it alive for the reference
  const Box& b = settled.boxes[0];
  EXPECT_NEAR(b.pose.translation().z(), 0.2, 0.002);
  EXPECT_NEAR(b.pose.translation().x(), 10.0, 0.002);
}

TEST(Physics, DroppedBoxLandsOnTheOneBelow) {
  World w = column(1, 10.0, 0.0, 20.0);
  w.boxes.push_back(make_box(2, {0.4, 0.4, 0.4}, {10.05, 0.03, 0.4 + 1.0 + 0.2}, 5.0));
  Simulation sim(w);
  sim.step(0.3);
  EXPECT_GT(find(sim.world(), 2).pose.translation().z(), 0.9);  // still falling
  EXPECT_GE(sim.settle(3.0), 0.0);
  const World after = sim.world();
  EXPECT_NEAR(find(after, 2).pose.translation().z(), 0.6, 0.004);  // on top, not through
  EXPECT_NEAR(find(after, 1).pose.translation().z(), 0.2, 0.004);
  EXPECT_LT(std::abs(find(after, 2).pose.translation().x() - 10.05), 0.1);  // bounced, still on top
}

TEST(Physics, StackStandsWithoutSleeping) {
  World w;
  std::uint32_t id = 1;
  for (int c = 0; c < 3; ++c) {
    for (int r = 0; r < 4; ++r) {
      w.boxes.push_back(make_box(id++, {0.4, 0.4, 0.4}, {15.0, -0.41 + 0.41 * c, 0.2 + 0.4 * r},
                                 2.0 + 5.0 * ((c + r) % 3)));
    }
  }
  PhysicsOptions o;
  o.sleeping = false;
  Simulation sim(w, o);
  sim.step(2.0);
  EXPECT_EQ(sim.stats().awake, 12);
  for (const Box& b : sim.world().boxes) {
    const Box& start = find(w, b.id);
    EXPECT_LT((b.pose.translation() - start.pose.translation()).norm(), 0.005) << b.id;
  }
}

TEST(Physics, WallOf150BoxesStands10Seconds) {
  const World w = generate_world(EnvFamily::kA1, 7);
  ASSERT_GE(w.boxes.size(), 150u);
  Simulation sim(w);
  sim.step(10.0);
  EXPECT_TRUE(sim.at_rest());
  double worst = 0.0;
  for (const Box& b : sim.world().boxes) {
    worst = std::max(worst, (b.pose.translation() - find(w, b.id).pose.translation()).norm());
  }
  EXPECT_LT(worst, 0.01);
  EXPECT_EQ(sim.world().boxes.size(), w.boxes.size());
  // Resting boxes sleep: most of the 20000 steps integrate nothing.
  EXPECT_LT(sim.stats().dynamic_steps, sim.stats().steps / 4);
}

Box yawed(Box b, double yaw) {
  b.pose.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return b;
}

// A heavy box on a light one used to rock on the light box's soft contacts
// for over a second; the stack must come to rest like cardboard does.
TEST(Physics, HeavyBoxOnALightOneComesToRestQuickly) {
  World w;
  w.boxes.push_back(make_box(1, {0.4, 0.4, 0.4}, {10.0, 0.0, 0.2}, 2.0));
  w.boxes.push_back(yawed(make_box(2, {0.4, 0.3, 0.3}, {10.05, 0.0, 0.556}, 30.0), 0.5));
  Simulation sim(w);
  const double rest = sim.settle(2.0);
  EXPECT_GE(rest, 0.0);
  EXPECT_LT(rest, 1.0);  // it rocked for over 3 s
  EXPECT_NEAR(find(sim.world(), 2).pose.translation().z(), 0.55, 0.002);
}

// Five boxes, each turned against the one below, mixed masses: the stack
// settles, and without sleeping it neither rings nor walks afterwards
// (edge-face contacts between turned boxes used to chatter).
TEST(Physics, StackOfTurnedBoxesSettlesAndStaysPut) {
  World w;
  const std::array<double, 5> mass{3.0, 12.0, 5.0, 9.0, 4.0}, yaw{0.0, 0.7, 0.2, 1.1, 0.4};
  double z = 0.0;
  for (std::size_t i = 0; i < 5; ++i) {
    const double h = 0.25 + 0.02 * static_cast<double>(i);
    w.boxes.push_back(yawed(
        make_box(static_cast<std::uint32_t>(i + 1), {0.42, 0.36, h},
                 {10.0 + 0.02 * static_cast<double>(i % 2), 0.0, z + 0.5 * h + 0.001}, mass[i]),
        yaw[i]));
    z += h + 0.002;
  }
  EXPECT_GE(Simulation(w).settle(1.5), 0.0);
  PhysicsOptions awake;
  awake.sleeping = false;
  Simulation sim(w, awake);
  sim.step(1.0);
  const World landed = sim.world();
  sim.step(2.0);
  for (const Box& b : sim.world().boxes) {
    EXPECT_LT((b.pose.translation() - find(landed, b.id).pose.translation()).norm(), 5e-4) << b.id;
  }
}

// Damping and sleeping must not hold up what really falls: a box whose
// centre overhangs the edge of the box below tips off.
TEST(Physics, OverhangingBoxTipsOver) {
  World w = column(1, 10.0, 0.0, 8.0);
  w.boxes.push_back(make_box(2, {0.4, 0.3, 0.3}, {10.0 + 0.2 + 0.05, 0.0, 0.4 + 0.151}, 8.0));
  Simulation sim(w);
  EXPECT_GE(sim.settle(3.0), 0.0);
  const Box top = find(sim.world(), 2);
  EXPECT_LT(top.pose.translation().z(), 0.4);  // down beside the lower box
}

// A woken box on the verge of tipping is not balanced and must not fall
// asleep early: its centre of mass 1 cm beyond the edge below, it tips.
TEST(Physics, BarelyOverhangingBoxTipsOver) {
  World w = column(1, 10.0, 0.0, 8.0);
  w.boxes.push_back(make_box(2, {0.4, 0.3, 0.3}, {10.0 + 0.2 + 0.01, 0.0, 0.4 + 0.151}, 8.0));
  Simulation sim(w);
  EXPECT_GE(sim.settle(5.0), 0.0);
  EXPECT_LT(find(sim.world(), 2).pose.translation().z(), 0.4);
}

// A fast box wakes the sleeping boxes near the box itself, not all near its
// bounding box (which a turned box overfills).
TEST(Physics, FastTurnedBoxWakesOnlyBoxesNearIt) {
  World w;
  const Eigen::Matrix3d turn = Eigen::AngleAxisd(M_PI / 4, Eigen::Vector3d::UnitZ()).matrix();
  w.boxes.push_back(make_box(1, {0.4, 0.4, 0.4}, {10.0, 0.0, 0.2}, 8.0));
  w.boxes.back().pose.linear() = turn;
  // 5 mm beyond the turned box's bounding box, 25 mm from the box.
  const double reach = 0.2 * std::sqrt(2.0);
  w.boxes.push_back(make_box(2, {0.4, 0.4, 0.4}, {10.0 + reach + 0.005 + 0.2, 0.23, 0.2}, 8.0));
  Simulation sim(w);
  ASSERT_GE(sim.settle(2.0), 0.0);
  // A paddle pushes the turned box along its face that looks at box 2.
  const Eigen::Vector3d along = Eigen::Vector3d(1.0, -1.0, 0.0).normalized();
  LinkGeometry paddle;
  paddle.size = {0.05, 0.3, 0.2};
  paddle.pose.linear() = Eigen::AngleAxisd(-M_PI / 4, Eigen::Vector3d::UnitZ()).matrix();
  const Eigen::Vector3d start = Eigen::Vector3d(10.0, 0.0, 0.2) - (0.2 + 0.025 + 0.02) * along;
  int most_awake = 0;
  for (int k = 0; k <= 30; ++k) {
    paddle.pose.translation() = start + 0.005 * k * along;
    sim.set_robot_links({paddle});
    sim.step(0.01);
    most_awake = std::max(most_awake, sim.stats().awake);
  }
  EXPECT_GT(find(sim.world(), 1).pose.translation().x(), 10.05);  // pushed well past box 2
  EXPECT_EQ(most_awake, 1);
}

// A box woken by a neighbour's removal that does not disturb it sleeps again
// well before sleep_time.
TEST(Physics, UndisturbedWokenBoxSleepsSoon) {
  World w = column(1, 10.0, 0.0);
  w.boxes.push_back(make_box(2, {0.4, 0.4, 0.4}, {10.41, 0.0, 0.2}, 8.0));
  Simulation sim(w);
  ASSERT_GE(sim.settle(2.0), 0.0);
  sim.remove_box(1);
  ASSERT_FALSE(sim.at_rest());  // the neighbour 1 cm away was woken
  const double slept = sim.settle(1.0);
  ASSERT_GE(slept, 0.0);
  EXPECT_LT(slept, 0.5 * PhysicsOptions{}.sleep_time);
  EXPECT_LT((find(sim.world(), 2).pose.translation() - Eigen::Vector3d(10.41, 0.0, 0.2)).norm(),
            1e-3);
}

TEST(Physics, RemovingTheBottomBoxDropsTheColumn) {
  Simulation sim(column(4));
  ASSERT_GE(sim.settle(2.0), 0.0);
  sim.remove_box(1);
  sim.step(0.05);
  EXPECT_FALSE(sim.at_rest());
  ASSERT_GE(sim.settle(3.0), 0.0);
  for (std::uint32_t id = 2; id <= 4; ++id) {
    EXPECT_NEAR(find(sim.world(), id).pose.translation().z(), 0.2 + 0.4 * (id - 2), 0.005) << id;
  }
  EXPECT_TRUE(sim.unloaded().empty());  // removal by hand is not unloading
}

TEST(Physics, PushingTheBottomBoxOutDropsTheOnesAbove) {
  Simulation sim(column(3, 10.0, 0.0));
  ASSERT_GE(sim.settle(2.0), 0.0);
  // A flat paddle, lower than the bottom box, sweeps it sideways out of the
  // column (stopping before it would squeeze it into the side wall). A fixed
  // fence above the bottom box holds back the ones on top, which friction
  // would otherwise carry along.
  LinkGeometry paddle, fence;
  paddle.size = {0.3, 0.05, 0.3};
  fence.size = {0.6, 0.05, 0.8};
  fence.pose.translation() = Eigen::Vector3d(10.0, 0.25, 0.85);
  for (int k = 0; k <= 120; ++k) {
    paddle.pose.translation() = Eigen::Vector3d(10.0, -0.5 + 0.01 * k, 0.16);
    sim.set_robot_links({paddle, fence});
    sim.step(0.01);
  }
  sim.set_robot_links({});
  sim.settle(3.0);
  const World w = sim.world();
  EXPECT_GT(find(w, 1).pose.translation().y(), 0.4);  // pushed out
  // The two above fell by about one box height (they may have tipped).
  EXPECT_LT(find(w, 2).pose.translation().z(), 0.45);
  EXPECT_LT(find(w, 3).pose.translation().z(), 0.85);
}

TEST(Physics, BoxesStayInsideTheTrailer) {
  World w;
  w.boxes.push_back(make_box(1, {0.4, 0.4, 0.4}, {15.5, 1.0, 0.3}, 5.0));
  Simulation sim(w);
  LinkGeometry pusher;
  pusher.size = {0.2, 0.2, 0.3};
  for (int k = 0; k <= 100; ++k) {
    pusher.pose.translation() = Eigen::Vector3d(14.8 + 0.004 * k, 1.0, 0.2);
    sim.set_robot_links({pusher});
    sim.step(0.01);
  }
  const Box b = sim.world().boxes[0];
  EXPECT_LT(b.pose.translation().x(), 16.0 - 0.19);  // stopped by the front wall
  EXPECT_LT(b.pose.translation().y(), 1.25 - 0.19);  // and the side wall
}

World run_sweep(Simulation& sim) {
  test::drive_paddle(sim);
  return sim.world();
}

TEST(Physics, RestoreThenRepeatIsIdentical) {
  Simulation sim(test::small_pile());
  sim.step(0.4);  // boxes still tumbling: the snapshot holds moving bodies
  const Snapshot snap = sim.snapshot();
  const World first = run_sweep(sim);
  sim.restore(snap);
  EXPECT_DOUBLE_EQ(sim.time(), snap.time());
  const World second = run_sweep(sim);
  ASSERT_EQ(first.boxes.size(), second.boxes.size());
  bool moved = false;
  for (std::size_t i = 0; i < first.boxes.size(); ++i) {
    EXPECT_EQ(first.boxes[i].pose.matrix(), second.boxes[i].pose.matrix()) << i;
    moved = moved || !first.boxes[i].pose.isApprox(test::small_pile().boxes[i].pose);
  }
  EXPECT_TRUE(moved);
  // A second simulation from the same world and commands agrees too.
  Simulation other(test::small_pile());
  other.step(0.4);
  const World third = run_sweep(other);
  for (std::size_t i = 0; i < first.boxes.size(); ++i) {
    EXPECT_EQ(first.boxes[i].pose.matrix(), third.boxes[i].pose.matrix()) << i;
  }
}

// A snapshot is a copy and a restore rebuilds Simbody lazily: neither steps
// nor builds a system, and the run after the restore repeats bit for bit.
TEST(Physics, SnapshotOf200MovingBoxesIsACopyAndRepeats) {
  World w = generate_world(EnvFamily::kA1, 3);
  const World extra = generate_world(EnvFamily::kA2, 3);
  for (Box b : extra.boxes) {
    if (w.boxes.size() >= 200) break;
    b.id += 1000;
    b.pose.translation().x() -= 4.0;
    w.boxes.push_back(b);
  }
  ASSERT_GE(w.boxes.size(), 200u);
  Simulation sim(w);
  sim.step(0.01);  // all awake: the snapshot holds Simbody coordinates of every box
  ASSERT_EQ(sim.stats().awake, static_cast<int>(w.boxes.size()));
  const PhysicsStats before = sim.stats();
  const Snapshot snap = sim.snapshot();
  EXPECT_EQ(sim.stats().steps, before.steps);
  EXPECT_EQ(sim.stats().rebuilds, before.rebuilds);
  sim.step(0.01);
  const World after = sim.world();
  const PhysicsStats stepped = sim.stats();
  sim.restore(snap);
  EXPECT_EQ(sim.stats().steps, stepped.steps);
  EXPECT_EQ(sim.stats().rebuilds, stepped.rebuilds);
  EXPECT_DOUBLE_EQ(sim.time(), snap.time());
  sim.step(0.01);
  const World again = sim.world();
  for (std::size_t i = 0; i < after.boxes.size(); ++i) {
    EXPECT_EQ(after.boxes[i].pose.matrix(), again.boxes[i].pose.matrix()) << i;
  }
}

TEST(Physics, RejectsWorldsWithoutMasses) {
  World w = column(1);
  w.boxes[0].mass = 0.0;
  try {
    Simulation sim(w);
    FAIL();
  } catch (const std::invalid_argument& e) {
    EXPECT_STREQ(e.what(), "Simulation: box 1 has no mass (the simulator needs the true world)");
  }
}

}  // namespace
}  // namespace plr::sim
