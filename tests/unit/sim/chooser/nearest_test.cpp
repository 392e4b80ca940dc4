#include "plr/chooser/nearest.hpp"

#include <gtest/gtest.h>

#include "world_builder.hpp"

using namespace plr::chooser;
using plr::chooser::test::add_box;
using plr::chooser::test::column_y0;

namespace {

plr::sim::LibraryEntry entry(const std::string& name, plr::sim::World world) {
  plr::sim::LibraryEntry e;
  e.name = name;
  e.world = std::move(world);
  e.strategy = plr::sim::single_action(plr::sim::make_sweep(plr::sim::Height::kLow), name);
  return e;
}

plr::sim::World wall(double height, double x) {
  plr::sim::World w;
  for (int c = 0; c < 10; ++c)
    for (double z = 0; z < height - 1e-9; z += 0.5)
      add_box(w, x, x + 0.5, column_y0(c), column_y0(c + 1), z, z + 0.5);
  return w;
}

plr::sim::World pile(double depth) {
  plr::sim::World w;
  for (double x = 6.0; x < 6.0 + depth - 1e-9; x += 0.5)
    add_box(w, x, x + 0.5, column_y0(2), column_y0(8), 0.0, 0.5);
  return w;
}

// A low wall, a high wall, a pile: NN finds a new world's kind.
plr::sim::Library library() {
  plr::sim::Library l;
  l.entries = {entry("low wall", wall(1.0, 8.0)), entry("high wall", wall(2.5, 8.0)),
               entry("pile", pile(2.0))};
  return l;
}

Scaling scaling_of(const plr::sim::Library& l) {
  std::vector<Features> f;
  for (const auto& e : l.entries) f.push_back(features(e.world));
  return Scaling::fit(f);
}

TEST(Nearest, AGeneratingWorldIsItsOwnNearestAtDistanceZero) {
  const auto l = library();
  const Scaling s = scaling_of(l);
  const LibraryIndex index(l, s);
  for (std::size_t e = 0; e < l.entries.size(); ++e) {
    const Nearest n = index.nearest(s.apply(features(l.entries[e].world)));
    EXPECT_EQ(n.entry, e);
    EXPECT_NEAR(n.distance, 0.0, 1e-12);
  }
}

TEST(Nearest, ANewWorldGoesToTheEntryOfItsKind) {
  const auto l = library();
  const Scaling s = scaling_of(l);
  const LibraryIndex index(l, s);
  EXPECT_EQ(index.nearest(s.apply(features(wall(2.0, 9.0)))).entry, 1u);  // high wall
  EXPECT_EQ(index.nearest(s.apply(features(wall(0.5, 7.0)))).entry, 0u);  // low wall
  const Nearest p = index.nearest(s.apply(features(pile(1.5))));
  EXPECT_EQ(p.entry, 2u);
  EXPECT_GT(p.distance, 0.0);
}

TEST(Scaling, FitsEachFeatureToZeroMeanAndUnitDeviation) {
  Features a{}, b{};
  a[0] = 1.0;
  b[0] = 3.0;
  a[1] = b[1] = 7.0;  // constant: not divided by zero
  const Scaling s = Scaling::fit({a, b});
  EXPECT_DOUBLE_EQ(s.apply(a)[0], -1.0);
  EXPECT_DOUBLE_EQ(s.apply(b)[0], 1.0);
  EXPECT_DOUBLE_EQ(s.scale[1], kCellHeight);
  EXPECT_DOUBLE_EQ(s.apply(a)[1], 0.0);
}

// Starting worlds all worked to the same depth: a later world 1 m further
// in is 4 half-slices away, not thousands of (near-zero) deviations.
TEST(Scaling, NoDeviationIsSmallerThanTheFeaturesResolution) {
  Features a{}, b{}, later{};
  a[kFrontDistance] = 5.0;
  b[kFrontDistance] = 5.001;
  later[kFrontDistance] = 6.0;
  const Scaling s = Scaling::fit({a, b});
  EXPECT_NEAR(s.apply(later)[kFrontDistance], (6.0 - 5.0005) / (kSliceDepth / 2), 1e-9);
  EXPECT_DOUBLE_EQ(s.scale[holes_index(0)], 1.0);
  EXPECT_DOUBLE_EQ(s.scale[kBoxCount], 1.0);
}

TEST(Fingerprint, ChangesWithTheLibrary) {
  auto l = library();
  const auto before = fingerprint(l);
  EXPECT_EQ(fingerprint(library()), before);
  l.entries.pop_back();
  EXPECT_NE(fingerprint(l), before);
}

}  // namespace
