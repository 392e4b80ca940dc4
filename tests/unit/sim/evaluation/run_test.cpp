// One evaluation run over a whole trailer: it goes on until the trailer is
// empty or the robot-time cap, and records which.
#include "plr/evaluation/run.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "plr/sim/testing/worlds.hpp"
#include "plr/sim/world_io.hpp"
#include "scene.hpp"

namespace plr::evaluation {
namespace {

namespace fs = std::filesystem;

class RunOne : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("plr_run_one_test_" + std::to_string(::getpid()));
    fs::create_directories(dir_);
    settings_.methods = {Method::kHardcoded};
    settings_.observation = sim::testing::small_scene_observation();
    auto rig = actions::Rig::create(actions::testing::options());
    ASSERT_TRUE(rig) << rig.error().message;
    rig_ = std::move(*rig);
  }
  void TearDown() override { fs::remove_all(dir_); }

  // H on a wall of 0.4 m boxes, `cols` by `rows`, cut at `cap_s`.
  nlohmann::json run(int cols, int rows, double cap_s, bool full_check = false) {
    const fs::path world = dir_ / "wall.yaml";
    EXPECT_TRUE(sim::save_world(actions::testing::wall(6.0, cols, rows), world));
    settings_.environments = {{"T", sim::EnvFamily::kA1, false, world}};
    settings_.max_robot_time_s = cap_s;
    return run_one(*rig_, settings_, resources_, {0, Method::kHardcoded, 1, full_check});
  }

  fs::path dir_;
  EvaluationSettings settings_;
  Resources resources_;
  std::unique_ptr<actions::Rig> rig_;
};

TEST_F(RunOne, GoesOnUntilTheTrailerIsEmpty) {
  // Two boxes on the floor, in reach.
  const nlohmann::json r = run(2, 1, 3600);
  ASSERT_FALSE(r.contains("error")) << r.dump(1);
  EXPECT_EQ(r["ended"], "empty") << r["stop_reason"];
  EXPECT_EQ(r["boxes_unloaded"], 2);
  EXPECT_LT(r["robot_time_s"].get<double>(), 3600);
}

TEST_F(RunOne, IsCutAtTheRobotTimeCapAndSaysSo) {
  // One action takes longer than a robot-second, and leaves boxes of a
  // three-high wall: the first is the last.
  const nlohmann::json r = run(3, 3, 1);
  ASSERT_FALSE(r.contains("error")) << r.dump(1);
  EXPECT_EQ(r["ended"], "cap") << r["stop_reason"];
  EXPECT_EQ(r["actions"], 1);
  EXPECT_GE(r["robot_time_s"].get<double>(), 1);
}

// A run simulates at the evaluation's level, its check at full, and each
// says which; the level is the rig's for the run, not left from the last.
TEST_F(RunOne, RunsAtTheSettingsFidelityAndItsCheckAtFull) {
  settings_.fidelity = sim::Fidelity::kFast;
  const nlohmann::json fast = run(2, 1, 3600);
  ASSERT_FALSE(fast.contains("error")) << fast.dump(1);
  EXPECT_EQ(fast["fidelity"], "fast");
  EXPECT_FALSE(fast.contains("fidelity_check"));
  EXPECT_EQ(rig_->simulation().physics().fidelity(), sim::Fidelity::kFast);
  const nlohmann::json full = run(2, 1, 3600, true);
  ASSERT_FALSE(full.contains("error")) << full.dump(1);
  EXPECT_EQ(full["fidelity"], "full");
  EXPECT_EQ(full["fidelity_check"], true);
  EXPECT_EQ(rig_->simulation().physics().fidelity(), sim::Fidelity::kFull);
  EXPECT_EQ(full["ended"], "empty");
}

}  // namespace
}  // namespace plr::evaluation
