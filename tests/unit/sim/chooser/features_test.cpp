#include "plr/chooser/features.hpp"

#include <gtest/gtest.h>

#include <set>

#include "world_builder.hpp"

using namespace plr::chooser;
using plr::chooser::test::add_box;
using plr::chooser::test::column_y0;

namespace {

TEST(Features, AnEmptyTrailerHasOnlyZeros) {
  const Features f = features(plr::sim::World{});
  for (double v : f) EXPECT_EQ(v, 0.0);
}

TEST(Features, OneBoxGivesItsColumnsHeightAndTheStepBeside) {
  plr::sim::World w;
  add_box(w, 5.0, 5.5, column_y0(0), column_y0(1), 0.0, 0.5);
  const Features f = features(w);
  EXPECT_DOUBLE_EQ(f[height_index(0, 0)], 0.5);
  for (std::size_t s = 0; s < kSlices; ++s)
    for (std::size_t c = 0; c < kColumns; ++c)
      if (s != 0 || c != 0) {
        EXPECT_EQ(f[height_index(s, c)], 0.0) << feature_name(height_index(s, c));
      }
  EXPECT_DOUBLE_EQ(f[difference_index(0, 0)], 0.5);
  EXPECT_EQ(f[difference_index(0, 1)], 0.0);
  EXPECT_EQ(f[holes_index(0)], 0.0);
  EXPECT_DOUBLE_EQ(f[kHighestStack], 0.5);
  EXPECT_DOUBLE_EQ(f[kFrontDistance], 5.0);
  EXPECT_EQ(f[kBoxCount], 1.0);
}

TEST(Features, AGapUnderABoxIsAHole) {
  plr::sim::World w;
  add_box(w, 5.0, 5.5, column_y0(3), column_y0(4), 0.0, 0.25);
  add_box(w, 5.0, 5.5, column_y0(3), column_y0(4), 0.5, 0.75);
  const Features f = features(w);
  EXPECT_DOUBLE_EQ(f[height_index(0, 3)], 0.75);
  EXPECT_EQ(f[holes_index(0)], 1.0);
  EXPECT_DOUBLE_EQ(f[difference_index(0, 2)], 0.75);  // columns 2 -> 3
  EXPECT_DOUBLE_EQ(f[difference_index(0, 3)], 0.75);  // columns 3 -> 4
  EXPECT_DOUBLE_EQ(f[kHighestStack], 0.75);
}

TEST(Features, SlicesRunFromTheNearestBoxAndADeepBoxFillsEach) {
  plr::sim::World w;
  add_box(w, 4.0, 5.0, column_y0(9), column_y0(10), 0.0, 1.0);  // slices 0 and 1
  add_box(w, 5.5, 6.0, column_y0(5), column_y0(6), 0.0, 2.0);   // slice 3
  const Features f = features(w);
  EXPECT_DOUBLE_EQ(f[height_index(0, 9)], 1.0);
  EXPECT_DOUBLE_EQ(f[height_index(1, 9)], 1.0);
  EXPECT_EQ(f[height_index(2, 9)], 0.0);
  EXPECT_DOUBLE_EQ(f[height_index(3, 5)], 2.0);
  EXPECT_DOUBLE_EQ(f[kFrontDistance], 4.0);
  EXPECT_DOUBLE_EQ(f[kHighestStack], 2.0);
}

TEST(Features, ABoxCoveringLessThanHalfACellDoesNotFillIt) {
  plr::sim::World w;
  // 0.1 of the column's 0.25 m width: 40 % of each cell.
  add_box(w, 5.0, 5.5, column_y0(5) + 0.05, column_y0(5) + 0.15, 0.0, 1.0);
  const Features f = features(w);
  EXPECT_EQ(f[height_index(0, 5)], 0.0);
  EXPECT_DOUBLE_EQ(f[kHighestStack], 1.0);  // the highest stack is the boxes' own top
}

TEST(Features, PileDepthAndFirstWallAsHSeesThem) {
  plr::sim::World w;
  add_box(w, 6.0, 7.0, column_y0(2), column_y0(4), 0.0, 0.4);  // a pile box, 1 m deep
  for (int k = 0; k < 4; ++k)                                  // a wall column 2 m high
    add_box(w, 8.0, 8.5, column_y0(4), column_y0(6), 0.5 * k, 0.5 * (k + 1));
  const Features f = features(w);
  EXPECT_NEAR(f[kPileDepth], 1.0, 1e-9);
  EXPECT_NEAR(f[kFirstWallHeight], 2.0, 1e-9);
  EXPECT_EQ(f[kBoxCount], 5.0);
}

TEST(Features, EveryFeatureHasItsOwnName) {
  std::set<std::string> names;
  for (std::size_t i = 0; i < kFeatureCount; ++i) names.insert(feature_name(i));
  EXPECT_EQ(names.size(), kFeatureCount);
  EXPECT_EQ(feature_name(height_index(1, 3)), "height[s1][c3]");
  EXPECT_EQ(feature_name(holes_index(2)), "holes[s2]");
  EXPECT_EQ(feature_name(kPileDepth), "pile_depth");
}

}  // namespace
