// What the in-process action tests share: the shipped robot and planner,
// hand-made walls of 0.4 m boxes with their thresholds, and a simulated robot
// with its in-process backend.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <thread>
#include <vector>

#include "plr/actions/action_model.hpp"
#include "plr/actions/in_process.hpp"
#include "plr/planning/lattice_planner.hpp"
#include "plr/sim/shipped_files.hpp"
#include "plr/sim/testing/worlds.hpp"

namespace plr::actions::testing {

inline const sim::RobotModel& robot() {
  static const sim::RobotModel m = sim::load_robot().value();
  return m;
}

inline planning::LatticePlanner& planner() {
  static planning::LatticePlanner p(
      planning::LatticeConfig::from_file(sim::shipped_file("robots/unloader_lattice.yaml").value())
          .value());
  return p;
}

// Hand-made walls of 0.4 m boxes: their thresholds.
inline ActionOptions options() {
  ActionOptions o;
  o.observation = sim::testing::small_scene_observation();
  return o;
}

inline sim::Box box(std::uint32_t id, double x, double y, double z0, double mass = 5.0) {
  sim::Box b;
  b.id = id;
  b.size = {0.4, 0.4, 0.4};
  b.mass = mass;
  b.pose.translation() = Eigen::Vector3d(x + 0.2, y, z0 + 0.2);
  return b;
}

// A wall of `cols` x `rows` 0.4 m boxes, front face at x, in an 8 m trailer.
inline sim::World wall(double x, int cols, int rows, double mass = 5.0) {
  sim::World w;
  w.trailer.depth = 8.0;
  std::uint32_t id = 1;
  for (int c = 0; c < cols; ++c)
    for (int r = 0; r < rows; ++r)
      w.boxes.push_back(box(id++, x, (c - (cols - 1) / 2.0) * 0.41, r * 0.4, mass));
  return w;
}

struct Fixture {
  explicit Fixture(const sim::World& truth, InProcessOptions options = {})
      : simulation(robot(), truth), backend(simulation, planner(), options) {}
  // The robot starting at q (its base inside the trailer).
  Fixture(const sim::JointVector& q, const sim::World& truth)
      : simulation(robot(), truth, q), backend(simulation, planner()) {}
  UnloaderSimulation simulation;
  InProcessBackend backend;
  Memory memory;
};

// Every core kept busy while it lives (at least two threads): what planning
// and physics must not notice.
class CpuLoad {
 public:
  CpuLoad() {
    for (unsigned i = 0; i < std::max(2u, std::thread::hardware_concurrency()); ++i)
      burners_.emplace_back([this] {
        volatile double x = 1;
        while (!stop_.load(std::memory_order_relaxed)) x = x * 1.0000001 + 1e-9;
      });
  }
  ~CpuLoad() {
    stop_ = true;
    for (auto& b : burners_) b.join();
  }
  CpuLoad(const CpuLoad&) = delete;
  CpuLoad& operator=(const CpuLoad&) = delete;

 private:
  std::atomic<bool> stop_{false};
  std::vector<std::thread> burners_;
};

// Two outcomes of the same action from the same state: equal to the bit,
// the planning made while moving included.
inline void expect_same_outcome(const Outcome& a, const Outcome& b) {
  EXPECT_EQ(a.applicable, b.applicable);
  EXPECT_EQ(a.boxes, b.boxes);
  EXPECT_EQ(a.unloaded_at_s, b.unloaded_at_s);
  EXPECT_EQ(a.robot_time_s, b.robot_time_s);
  EXPECT_EQ(a.exec_s, b.exec_s);
  EXPECT_EQ(a.plan_model_s, b.plan_model_s);
  EXPECT_EQ(a.plan_hidden_s, b.plan_hidden_s);
  EXPECT_EQ(a.plans_ahead, b.plans_ahead);
  EXPECT_EQ(a.plans_ahead_used, b.plans_ahead_used);
  EXPECT_EQ(a.drops, b.drops);
  ASSERT_EQ(a.queries.size(), b.queries.size());
  for (std::size_t i = 0; i < a.queries.size(); ++i) {
    EXPECT_EQ(a.queries[i].mode, b.queries[i].mode) << "query " << i;
    EXPECT_EQ(a.queries[i].status, b.queries[i].status) << "query " << i;
    EXPECT_EQ(a.queries[i].expansions, b.queries[i].expansions) << "query " << i;
    EXPECT_EQ(a.queries[i].planned_ahead, b.queries[i].planned_ahead) << "query " << i;
  }
}

}  // namespace plr::actions::testing
