// A strategy with its continuations as one tree: each continuation's tree
// hangs where its parent's ends after the observations of its leaf.
#include "plr/sim/chain.hpp"

#include <gtest/gtest.h>

using namespace plr::sim;

namespace {

const Observation kWallMid = make_observation(Structure::kWall, Height::kMid, Side::kCenter);
const Observation kPileLow = make_observation(Structure::kPile, Height::kLow, Side::kRight);

LibraryEntry entry(const std::string& name, Strategy strategy) {
  LibraryEntry e;
  e.name = name;
  e.family = "A1";
  strategy.name = name;
  e.strategy = std::move(strategy);
  return e;
}

LibraryEntry continuation(const std::string& name, const std::string& parent,
                          std::vector<Observation> leaf, Strategy strategy) {
  LibraryEntry e = entry(name, std::move(strategy));
  e.parent = parent;
  e.leaf = std::move(leaf);
  e.start = {{0, 1, 10}};
  return e;
}

// Pick(high, left); on wall/mid/center a low sweep; the tree ends after it.
Strategy two_steps() {
  Strategy s;
  s.nodes = {{make_pick(Height::kHigh, Side::kLeft), {{kWallMid, 1}}},
             {make_sweep(Height::kLow), {}}};
  return s;
}

}  // namespace

TEST(Chain, AContinuationIsTakenWhereItsParentsTreeEndsOnItsLeaf) {
  Library lib;
  lib.entries = {entry("A1-1", two_steps()),
                 continuation("A1-1.1", "A1-1", {kWallMid, kPileLow}, two_steps()),
                 continuation("A1-1.1.1", "A1-1.1", {kWallMid, kPileLow},
                              single_action(make_sweep(Height::kHigh), "x"))};
  const auto c = chain(lib, 0);
  ASSERT_TRUE(c) << c.error().message;
  EXPECT_EQ(c->links, 3u);
  EXPECT_EQ(c->strategy.name, "A1-1");
  const Strategy& s = c->strategy;
  ASSERT_EQ(s.nodes.size(), 5u);
  // Parent: root, then wall/mid/center; the leaf's last observation now
  // leads to the continuation's root, and on down the second link.
  const auto n1 = s.next(s.root, kWallMid);
  ASSERT_TRUE(n1);
  EXPECT_EQ(c->entry_of_node[*n1], 0u);
  const auto n2 = s.next(*n1, kPileLow);
  ASSERT_TRUE(n2);
  EXPECT_EQ(c->entry_of_node[*n2], 1u);
  EXPECT_EQ(s.nodes[*n2].action, make_pick(Height::kHigh, Side::kLeft));
  const auto n4 = s.next(*s.next(*n2, kWallMid), kPileLow);
  ASSERT_TRUE(n4);
  EXPECT_EQ(c->entry_of_node[*n4], 2u);
  EXPECT_EQ(s.nodes[*n4].action, make_sweep(Height::kHigh));
  // Another observation at the leaf: the tree ends, as the parent's did.
  EXPECT_FALSE(s.next(*n1, kWallMid));
  // Without continuations the chain is the entry's strategy.
  const auto alone = chain(lib, 2);
  ASSERT_TRUE(alone);
  EXPECT_EQ(alone->links, 1u);
  EXPECT_EQ(format_yaml(alone->strategy), format_yaml(lib.entries[2].strategy));
  // Over the node budget a continuation is left out.
  const auto cut = chain(lib, 0, 3);
  ASSERT_TRUE(cut);
  EXPECT_EQ(cut->links, 1u);
}

TEST(Chain, ALeafThatIsNotWhereTheParentEndsIsRefused) {
  Library lib;
  lib.entries = {entry("A1-1", two_steps()),
                 continuation("A1-1.1", "A1-1", {kWallMid}, two_steps())};
  const auto c = chain(lib, 0);
  ASSERT_FALSE(c);
  EXPECT_NE(c.error().message.find("continuation 'A1-1.1' of 'A1-1'"), std::string::npos)
      << c.error().message;
  lib.entries[1].leaf = {kPileLow, kPileLow};
  EXPECT_FALSE(chain(lib, 0));
}
