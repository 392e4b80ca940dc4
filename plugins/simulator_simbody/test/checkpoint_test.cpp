// The simulator's checkpoint on disk (src/checkpoint.cpp): what a restarted
// simulator host resumes from.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "checkpoint.hpp"

namespace plr::simulator {
namespace {

namespace fs = std::filesystem;

class CheckpointTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("plr_checkpoint_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(CheckpointTest, RoundTrip) {
  Checkpoint c;
  sim::Box b;
  b.id = 7;
  b.size = {0.3, 0.4, 0.5};
  b.mass = 12.5;
  b.pose.translation() = Eigen::Vector3d(9.0, -0.4, 0.25);
  c.world.boxes.push_back(b);
  c.robot.q << 1.0, 0.1, -1.0, 2.0, 0.2, 0.5, 0.0, 0.0;
  c.robot.held = {7};
  c.sim_time = 12.25;
  c.boxes_total = 30;
  c.boxes_unloaded = 4;
  save_checkpoint(dir_, c);
  const auto back = load_checkpoint(dir_);
  ASSERT_TRUE(back.has_value());
  EXPECT_EQ(back->robot.q, c.robot.q);
  EXPECT_EQ(back->robot.held, c.robot.held);
  EXPECT_EQ(back->sim_time, 12.25);
  EXPECT_EQ(back->boxes_total, 30u);
  EXPECT_EQ(back->boxes_unloaded, 4u);
  ASSERT_EQ(back->world.boxes.size(), 1u);
  EXPECT_EQ(back->world.boxes[0].mass, 12.5);
  EXPECT_TRUE(back->world.boxes[0].pose.isApprox(b.pose));
}

TEST_F(CheckpointTest, NoneIsNotAnError) {
  EXPECT_FALSE(load_checkpoint(dir_).has_value());
}

TEST_F(CheckpointTest, ADamagedOneIsRefusedByName) {
  save_checkpoint(dir_, Checkpoint{});
  std::ofstream(dir_ / "state.json") << "{\"q\": [1, 2]}";
  try {
    load_checkpoint(dir_);
    FAIL() << "a damaged checkpoint was accepted";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()), (dir_ / "state.json").string() + ": damaged checkpoint");
  }
}

}  // namespace
}  // namespace plr::simulator
