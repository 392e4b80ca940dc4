#include "plr/sim/strategy.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

namespace plr::sim {
namespace {

namespace fs = std::filesystem;

class TempDir {
 public:
  TempDir() {
    std::string pattern = (fs::temp_directory_path() / "plr_strategy_XXXXXX").string();
    path_ = mkdtemp(pattern.data());
  }
  ~TempDir() { fs::remove_all(path_); }
  const fs::path& path() const { return path_; }

 private:
  fs::path path_;
};

Strategy example() {
  Strategy s;
  s.name = "example";
  s.root = 0;
  s.nodes = {{make_pick(Height::kHigh, Side::kLeft),
              {{make_observation(Structure::kWall, Height::kHigh, Side::kLeft), 1},
               {make_observation(Structure::kPile, Height::kLow, Side::kCenter), 2}}},
             {make_sweep(Height::kMid), {}},
             {make_pick(Height::kLow, Side::kRight), {}}};
  return s;
}

TEST(Actions, AllTwelveRoundTrip) {
  int picks = 0, sweeps = 0;
  for (int i = 0; i < kNumActions; ++i) {
    const auto a = static_cast<Action>(i);
    const auto parsed = parse_action(to_string(a));
    ASSERT_TRUE(parsed) << to_string(a);
    EXPECT_EQ(*parsed, a);
    if (kind(a) == ActionKind::kPick) {
      ++picks;
      EXPECT_EQ(make_pick(height(a), side(a)), a);
    } else {
      ++sweeps;
      EXPECT_EQ(make_sweep(height(a)), a);
    }
  }
  EXPECT_EQ(picks, 9);
  EXPECT_EQ(sweeps, 3);
  EXPECT_EQ(to_string(Action::PickMidRight), "Pick(mid, right)");
  EXPECT_EQ(to_string(Action::SweepHigh), "Sweep(high)");
  EXPECT_EQ(make_pick(Height::kMid, Side::kRight), Action::PickMidRight);
  EXPECT_EQ(parse_action(" pick( HIGH , center ) "), Action::PickHighCenter);
  EXPECT_FALSE(parse_action("Pick(high)"));
  EXPECT_FALSE(parse_action("Sweep(left)"));
  EXPECT_FALSE(parse_action("Push(low)"));
}

TEST(Observations, AllEighteenRoundTrip) {
  for (int i = 0; i < kNumObservations; ++i) {
    const auto o = static_cast<Observation>(i);
    const auto parsed = parse_observation(to_string(o));
    ASSERT_TRUE(parsed) << to_string(o);
    EXPECT_EQ(*parsed, o);
    EXPECT_EQ(make_observation(structure(o), height(o), side(o)), o);
  }
  EXPECT_EQ(make_observation(Structure::kWall, Height::kMid, Side::kCenter),
            Observation::WallMidCenter);
  EXPECT_EQ(to_string(Observation::PileHighRight), "pile/high/right");
  EXPECT_FALSE(parse_observation("heap/low/left"));
  EXPECT_FALSE(parse_observation("wall/low"));
}

TEST(Strategy, WalksTheTree) {
  const Strategy s = example();
  EXPECT_TRUE(validate(s));
  EXPECT_EQ(s.next(0, Observation::WallHighLeft), 1u);
  EXPECT_EQ(s.next(0, Observation::PileLowCenter), 2u);
  EXPECT_FALSE(s.next(0, Observation::WallLowLeft));
  EXPECT_FALSE(s.next(1, Observation::WallHighLeft));
  EXPECT_EQ(s.depth(), 2u);
  EXPECT_EQ(single_action(Action::SweepLow, "h").depth(), 1u);
}

TEST(Strategy, ValidateNamesTheFault) {
  Strategy s = example();
  s.nodes[0].children[1].second = 7;
  EXPECT_EQ(validate(s).error().message, "node 0: child 7 out of range");
  s = example();
  s.nodes[0].children[1].first = s.nodes[0].children[0].first;
  EXPECT_EQ(validate(s).error().message, "node 0: two edges for wall/high/left");
  s = example();
  s.nodes[2].children.push_back({Observation::WallLowLeft, 0});
  EXPECT_EQ(validate(s).error().message, "root 0 has a parent");
  s = example();
  s.nodes[2].children.push_back({Observation::WallLowLeft, 1});
  EXPECT_EQ(validate(s).error().message, "node 1 has 2 parents (a tree needs exactly one)");
  s = example();
  s.root = 3;
  EXPECT_EQ(validate(s).error().message, "root 3 out of range (3 nodes)");
  EXPECT_EQ(validate(Strategy{}).error().message, "strategy has no nodes");
  s = example();
  s.nodes[1].action = static_cast<Action>(12);
  EXPECT_EQ(validate(s).error().message, "node 1: invalid action 12");
  // A detached cycle: every node has one parent except the root.
  s = example();
  s.nodes[1].children.push_back({Observation::WallLowLeft, 2});
  s.nodes[2].children.push_back({Observation::WallLowLeft, 1});
  s.nodes[0].children.clear();
  EXPECT_EQ(validate(s).error().message, "2 nodes are not reachable from the root");
}

void expect_same(const Strategy& a, const Strategy& b) {
  EXPECT_EQ(a.name, b.name);
  EXPECT_EQ(a.root, b.root);
  ASSERT_EQ(a.nodes.size(), b.nodes.size());
  for (std::size_t i = 0; i < a.nodes.size(); ++i) {
    EXPECT_EQ(a.nodes[i].action, b.nodes[i].action);
    EXPECT_EQ(a.nodes[i].children, b.nodes[i].children);
  }
}

TEST(StrategyFile, BinaryRoundTripWithIdentifier) {
  TempDir dir;
  const auto file = dir.path() / "s.plrs";
  ASSERT_TRUE(save_strategy(example(), file));
  std::ifstream in(file, std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), {});
  ASSERT_GE(bytes.size(), 8u);
  EXPECT_EQ(bytes.substr(4, 4), "PLRS");
  const auto loaded = load_strategy(file);
  ASSERT_TRUE(loaded) << loaded.error().message;
  expect_same(*loaded, example());
  // Nothing but the file itself is left behind.
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator{}), 1);
}

TEST(StrategyFile, YamlRoundTrip) {
  TempDir dir;
  const auto file = dir.path() / "s.yaml";
  ASSERT_TRUE(save_strategy(example(), file));
  const auto loaded = load_strategy(file);
  ASSERT_TRUE(loaded) << loaded.error().message;
  expect_same(*loaded, example());
}

std::string load_error(const fs::path& file) {
  const auto loaded = load_strategy(file);
  return loaded ? "no error" : loaded.error().message;
}

TEST(StrategyFile, BadFilesGiveOneLineErrors) {
  TempDir dir;
  const auto missing = dir.path() / "missing.plrs";
  EXPECT_EQ(load_error(missing), missing.string() + ": cannot open");

  const auto garbage = dir.path() / "garbage.plrs";
  std::ofstream(garbage) << "this is not a flatbuffer at all";
  EXPECT_EQ(load_error(garbage),
            garbage.string() + ": not a strategy file (no \"PLRS\" identifier)");

  // Right identifier, corrupted offsets.
  auto bytes = serialize(example());
  for (std::size_t i = 8; i < bytes.size(); ++i) bytes[i] = 0xff;
  const auto corrupt = dir.path() / "corrupt.plrs";
  std::ofstream(corrupt, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()),
             static_cast<std::streamsize>(bytes.size()));
  EXPECT_EQ(load_error(corrupt),
            corrupt.string() + ": corrupt strategy file (verification failed)");

  // Well-formed buffer, invalid tree.
  Strategy bad = example();
  bad.nodes[0].children[0].second = 9;
  const auto tree = dir.path() / "tree.plrs";
  const auto tree_bytes = serialize(bad);
  std::ofstream(tree, std::ios::binary)
      .write(reinterpret_cast<const char*>(tree_bytes.data()),
             static_cast<std::streamsize>(tree_bytes.size()));
  EXPECT_EQ(load_error(tree), tree.string() + ": node 0: child 9 out of range");

  const auto yaml = dir.path() / "bad.yaml";
  std::ofstream(yaml) << "format: plr-strategy\nversion: 1\nnodes:\n  - {action: Jump(high)}\n";
  EXPECT_EQ(load_error(yaml),
            yaml.string() + ":4:14: nodes[0].action: 'Jump(high)' is not Pick(h, s) or Sweep(h)");
  for (const auto& f : {garbage, corrupt, tree, yaml})
    EXPECT_EQ(load_error(f).find('\n'), std::string::npos);
}

std::string yaml_error(const std::string& nodes) {
  const auto parsed =
      parse_yaml("format: plr-strategy\nversion: 1\nroot: 0\nnodes:\n" + nodes, "s.yaml");
  return parsed ? "no error" : parsed.error().message;
}

TEST(StrategyFile, YamlErrorsAreLocated) {
  // A value of the wrong type.
  EXPECT_EQ(yaml_error("  - {action: [Sweep(low)]}\n"),
            "s.yaml:5:14: nodes[0].action: expected an action, got a list");
  EXPECT_EQ(yaml_error("  - {action: Sweep(low), children: {wall/low/left: one}}\n"),
            "s.yaml:5:52: nodes[0].children.wall/low/left: expected an integer, got 'one'");
  // A key the reader does not know.
  EXPECT_EQ(yaml_error("  - {action: Sweep(low), child: {}}\n"),
            "s.yaml:5:26: nodes[0].child: unknown key 'child' (known keys: action, children)");
  EXPECT_EQ(yaml_error("  - {action: Sweep(low), children: {wall/low/up: 0}}\n"),
            "s.yaml:5:37: nodes[0].children.wall/low/up: 'wall/low/up' is not "
            "pile|wall/low|mid|high/left|center|right");
  // Out of range: a child or the root past the last node.
  EXPECT_EQ(yaml_error("  - {action: Sweep(low), children: {wall/low/left: 1}}\n"),
            "s.yaml:5:52: nodes[0].children.wall/low/left: must be between 0 and 0, got 1");
  EXPECT_EQ(yaml_error("  - {action: Sweep(low)}\n").find("no error"), 0u);
  // What only the whole tree shows is reported at the list of nodes.
  EXPECT_EQ(yaml_error("  - {action: Sweep(low), children: {wall/low/left: 0}}\n"),
            "s.yaml:5:3: nodes: root 0 has a parent");
  EXPECT_EQ(yaml_error(" []\n"), "s.yaml:5:2: nodes: a strategy needs at least one node");
}

TEST(StrategyFile, RefusesToWriteInvalidTreesAndReportsIoErrors) {
  TempDir dir;
  Strategy bad = example();
  bad.root = 5;
  const auto file = dir.path() / "x.plrs";
  const Status invalid = save_strategy(bad, file);
  ASSERT_FALSE(invalid);
  EXPECT_EQ(
      invalid.error().message,
      file.string() + ": refusing to write an invalid strategy: root 5 out of range (3 nodes)");
  EXPECT_FALSE(fs::exists(file));
  const auto nowhere = dir.path() / "no" / "such" / "dir.plrs";
  const Status missing = save_strategy(example(), nowhere);
  ASSERT_FALSE(missing) << "saved into a missing folder";
  EXPECT_EQ(missing.error().message,
            nowhere.string() + ": cannot create a temporary file: No such file or directory");
}

}  // namespace
}  // namespace plr::sim
