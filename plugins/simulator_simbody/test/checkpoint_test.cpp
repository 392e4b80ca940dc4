// The simulator's checkpoint on disk (src/checkpoint.cpp): what a restarted
// simulator host resumes from.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdint>
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
  const auto saved = save_checkpoint(dir_, c);
  ASSERT_TRUE(saved) << saved.error().message;
  std::uint64_t on_disk = 0;
  for (const auto& entry : fs::recursive_directory_iterator(dir_))
    if (entry.is_regular_file()) on_disk += entry.file_size();
  EXPECT_EQ(*saved, on_disk);
  const auto loaded = load_checkpoint(dir_);
  ASSERT_TRUE(loaded) << loaded.error().message;
  const auto& back = *loaded;
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
  const auto none = load_checkpoint(dir_);
  ASSERT_TRUE(none) << none.error().message;
  EXPECT_FALSE(none->has_value());
}

TEST_F(CheckpointTest, ADamagedOneIsRefusedByName) {
  ASSERT_TRUE(save_checkpoint(dir_, Checkpoint{}));
  for (const char* state : {"{\"q\": [1, 2]}", "{\"q\": [1, 2, 3, 4, 5, 6, 7, \"8\"]}"}) {
    std::ofstream(dir_ / "state.json") << state;
    const auto damaged = load_checkpoint(dir_);
    ASSERT_FALSE(damaged) << state;
    EXPECT_EQ(damaged.error().message, (dir_ / "state.json").string() + ": damaged checkpoint");
  }
  std::ofstream(dir_ / "world.yaml") << "format: plr-world\nversion: 2\n";
  const auto world = load_checkpoint(dir_);
  ASSERT_FALSE(world);
  EXPECT_EQ(world.error().message,
            (dir_ / "world.yaml").string() +
                ":2:10: version: unsupported version 2 (this reader knows 1)");
}

TEST_F(CheckpointTest, SavingWhereNoFolderCanBeMadeNamesIt) {
  std::ofstream(dir_.string()) << "a file, not a folder";
  const auto saved = save_checkpoint(dir_ / "sub", Checkpoint{});
  ASSERT_FALSE(saved);
  EXPECT_EQ(saved.error().message, (dir_ / "sub").string() + ": Not a directory");
}

}  // namespace
}  // namespace plr::simulator
