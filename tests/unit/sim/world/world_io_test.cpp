#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "plr/sim/generators.hpp"
#include "plr/sim/world_io.hpp"

namespace plr::sim {
namespace {

namespace fs = std::filesystem;

class WorldIo : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() /
           ("plr_world_io_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
            "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  fs::path write(const std::string& name, const std::string& text) {
    const fs::path p = dir_ / name;
    std::ofstream(p) << text;
    return p;
  }

  std::string error_of(const std::string& text) {
    const fs::path p = write("bad.yaml", text);
    const auto world = load_world(p);
    if (world) {
      ADD_FAILURE() << "no error for:\n" << text;
      return {};
    }
    const std::string& msg = world.error().message;
    const std::string prefix = p.string() + ":";
    EXPECT_EQ(msg.rfind(prefix, 0), 0u) << msg;
    return msg.substr(prefix.size());
  }

  fs::path dir_;
};

const std::string kHeader =
    "format: plr-world\nversion: 1\ntrailer: {width: 2.5, height: 2.7, depth: 16}\n";

TEST_F(WorldIo, RoundTripIsExact) {
  const World w = generate_world(EnvFamily::kA2, 42);
  const fs::path p = dir_ / "w.yaml";
  ASSERT_TRUE(save_world(w, p));
  const auto loaded = load_world(p);
  ASSERT_TRUE(loaded) << loaded.error().message;
  const World& r = *loaded;
  ASSERT_EQ(r.boxes.size(), w.boxes.size());
  EXPECT_EQ(r.trailer.depth, w.trailer.depth);
  for (std::size_t i = 0; i < w.boxes.size(); ++i) {
    EXPECT_EQ(r.boxes[i].id, w.boxes[i].id);
    EXPECT_EQ(r.boxes[i].size, w.boxes[i].size);
    EXPECT_EQ(r.boxes[i].mass, w.boxes[i].mass);
    EXPECT_TRUE(r.boxes[i].pose.isApprox(w.boxes[i].pose, 1e-14));
  }
  // Nothing but the file remains: the temporary file was renamed.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir_), fs::directory_iterator()), 1);
}

TEST_F(WorldIo, OrientationIsOptionalAndMassMayBeZero) {
  const fs::path p =
      write("w.yaml", kHeader + "boxes:\n  - {id: 3, size: [1, 2, 3], position: [4, 0, 1.5]}\n");
  const auto loaded = load_world(p);
  ASSERT_TRUE(loaded) << loaded.error().message;
  const World& w = *loaded;
  ASSERT_EQ(w.boxes.size(), 1u);
  EXPECT_EQ(w.boxes[0].id, 3u);
  EXPECT_EQ(w.boxes[0].mass, 0.0);
  EXPECT_TRUE(w.boxes[0].pose.linear().isIdentity());
}

// A 1e4 m trailer or a 1e6 m box grew memory until the process was killed.
TEST_F(WorldIo, SizesArePhysicallyBounded) {
  EXPECT_EQ(error_of("format: plr-world\nversion: 1\ntrailer: {width: 2.5, height: 2.7, depth: "
                     "1e4}\nboxes: []\n"),
            "3:43: trailer.depth: must be between 0.5 and 20, got 1e4");
  EXPECT_EQ(error_of(kHeader + "boxes:\n  - {id: 1, size: [1e6, 1, 1], position: [1, 0, 0.5]}\n"),
            "5:20: boxes[0].size[0]: must be between 0.01 and 4, got 1e6");
  EXPECT_EQ(error_of(kHeader + "boxes:\n  - {id: 1, size: [1, 1, 1], position: [1e300, 0, 0.5]}\n"),
            "5:41: boxes[0].position[0]: must be between -100 and 100, got 1e300");
  EXPECT_EQ(error_of(kHeader +
                     "boxes:\n  - {id: 1, size: [1, 1, 1], position: [1, 0, 0.5], mass: 1e9}\n"),
            "5:59: boxes[0].mass: must be between 0 and 1000, got 1e9");
}

TEST_F(WorldIo, ErrorsNameLineAndKey) {
  EXPECT_EQ(error_of(kHeader + "boxes:\n  - {id: 1, size: [1, 1, 1], position: [1, 0, 0.5]}\n"
                               "  - {id: 2, position: [3, 0, 0.5]}\n"),
            "6:5: boxes[1]: missing required key 'size'");
  EXPECT_EQ(error_of(kHeader + "boxes:\n  - {id: 1, size: [1, 1], position: [1, 0, 0.5]}\n"),
            "5:19: boxes[0].size: must have exactly 3 items, got 2");
  EXPECT_EQ(error_of(kHeader + "boxes:\n  - id: 1\n    size: [1, 1, 1]\n    position: [1, 0, 0.5]\n"
                               "    mass: heavy\n"),
            "8:11: boxes[0].mass: expected a number, got 'heavy'");
  EXPECT_EQ(error_of(kHeader + "boxes:\n  - {id: 1, size: [1, -1, 1], position: [1, 0, 0.5]}\n"),
            "5:23: boxes[0].size[1]: must be between 0.01 and 4, got -1");
  EXPECT_EQ(error_of(kHeader + "boxes:\n  - {id: 1, size: [1, 1, 1], position: [1, 0, 0.5]}\n"
                               "  - {id: 1, size: [1, 1, 1], position: [3, 0, 0.5]}\n"),
            "6:10: boxes[1].id: duplicate id 1 (also boxes[0].id)");
  EXPECT_EQ(error_of("format: plr-world\nversion: 1\ntrailer: {width: 2.5, height: 0, depth: 16}\n"
                     "boxes: []\n"),
            "3:31: trailer.height: must be between 0.5 and 4, got 0");
  EXPECT_EQ(error_of("format: plr-world\nversion: 2\n"),
            "2:10: version: unsupported version 2 (this reader knows 1)");
  EXPECT_EQ(error_of("format: something\nversion: 1\n"),
            "1:9: format: expected 'plr-world', got 'something'");
  EXPECT_EQ(error_of(kHeader + "boxes: [\n"), "5:1: syntax error: end of sequence flow not found");
}

TEST_F(WorldIo, BadTypesUnknownKeysAndRangesAreLocated) {
  // A value of the wrong type.
  EXPECT_EQ(error_of(kHeader + "boxes:\n  - {id: 1, size: 1, position: [1, 0, 0.5]}\n"),
            "5:19: boxes[0].size: expected 3 sizes, got '1'");
  EXPECT_EQ(error_of(kHeader + "boxes: {id: 1}\n"),
            "4:8: boxes: expected a list of boxes, got a map");
  // A key the reader does not know, with the one it probably meant.
  EXPECT_EQ(
      error_of(kHeader + "boxes:\n  - {id: 1, size: [1, 1, 1], position: [1, 0, 0.5], mas: 2}\n"),
      "5:53: boxes[0].mas: unknown key 'mas' (did you mean 'mass'?)");
  EXPECT_EQ(error_of("format: plr-world\nversion: 1\n"
                     "trailer: {width: 2.5, height: 2.7, depth: 16, length: 3}\nboxes: []\n"),
            "3:47: trailer.length: unknown key 'length' (known keys: width, height, depth)");
  // Out of range.
  EXPECT_EQ(error_of(kHeader + "boxes:\n  - {id: -1, size: [1, 1, 1], position: [1, 0, 0.5]}\n"),
            "5:10: boxes[0].id: must not be negative, got -1");
  EXPECT_EQ(
      error_of(kHeader + "boxes:\n  - {id: 1, size: [1, 1, 1], position: [1, 0, 0.5], mass: -2}\n"),
      "5:59: boxes[0].mass: must be between 0 and 1000, got -2");
  EXPECT_EQ(error_of(kHeader + "boxes:\n  - {id: 1, size: [1, 1, 1], position: [1, 0, 0.5],"
                               " orientation: [0, 0, 0, 0]}\n"),
            "5:66: boxes[0].orientation: must be a rotation, got a zero quaternion");
}

TEST_F(WorldIo, MissingFileIsReported) {
  const auto world = load_world(dir_ / "nope.yaml");
  ASSERT_FALSE(world);
  EXPECT_EQ(world.error().message,
            (dir_ / "nope.yaml").string() + ": cannot read the world: No such file or directory");
}

TEST_F(WorldIo, ParsedTextIsNamedByItsOrigin) {
  const auto world = parse_world("format: plr-world\nversion: 2\n", "--world");
  ASSERT_FALSE(world);
  EXPECT_EQ(world.error().message,
            "--world:2:10: version: unsupported version 2 (this reader knows 1)");
}

TEST_F(WorldIo, SaveIntoMissingDirectoryFailsCleanly) {
  const fs::path p = dir_ / "no" / "such" / "w.yaml";
  const Status saved = save_world(World{}, p);
  ASSERT_FALSE(saved);
  EXPECT_EQ(saved.error().message,
            p.string() + ": cannot create a temporary file: No such file or directory");
}

}  // namespace
}  // namespace plr::sim
