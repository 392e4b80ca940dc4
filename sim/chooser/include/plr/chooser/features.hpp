// Features of a perceived world W for the strategy chooser, in the manner of
// the features that learn Tetris policies (the paper, after Thiery and
// Scherrer): the box region in front of the robot discretised into a 3D
// grid, each column's height and holes, neighbouring columns' differences,
// the highest stack and the pile's depth. docs/chooser.md lists them one by
// one; kFeatureVersion changes whenever their meaning or order does, so a
// model trained on other features is refused.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

#include "plr/sim/observation.hpp"
#include "plr/sim/world.hpp"

namespace plr::chooser {

inline constexpr std::uint32_t kFeatureVersion = 1;

// The grid: kColumns across the trailer's width (from its right wall, y =
// -width/2, to its left), kSlices of kSliceDepth along x from the box
// nearest the robot, cells kCellHeight high from the floor. A cell is
// filled when boxes (their world-frame bounds) cover at least half of it.
inline constexpr std::size_t kColumns = 10;
inline constexpr std::size_t kSlices = 4;
inline constexpr double kSliceDepth = 0.5;   // m
inline constexpr double kCellHeight = 0.25;  // m

// Per slice: kColumns heights, kColumns - 1 height differences, holes;
// then five for the whole trailer.
inline constexpr std::size_t kPerSlice = 2 * kColumns;
inline constexpr std::size_t kGlobalFeatures = 5;
inline constexpr std::size_t kFeatureCount = kSlices * kPerSlice + kGlobalFeatures;
static_assert(kFeatureCount == 85, "the paper's 85 features");

using Features = std::array<double, kFeatureCount>;

// Index of a feature (slice s, column c) in Features.
constexpr std::size_t height_index(std::size_t s, std::size_t c) {
  return s * kPerSlice + c;
}
constexpr std::size_t difference_index(std::size_t s, std::size_t c) {
  return s * kPerSlice + kColumns + c;  // |h(c+1) - h(c)|, c < kColumns - 1
}
constexpr std::size_t holes_index(std::size_t s) {
  return s * kPerSlice + 2 * kColumns - 1;
}
inline constexpr std::size_t kHighestStack = kSlices * kPerSlice;
inline constexpr std::size_t kPileDepth = kHighestStack + 1;
inline constexpr std::size_t kFirstWallHeight = kHighestStack + 2;
inline constexpr std::size_t kBoxCount = kHighestStack + 3;
inline constexpr std::size_t kFrontDistance = kHighestStack + 4;

// The features of `world` (masses are not used). `observation` splits pile
// from wall for the pile depth and the first wall's height, as strategy H
// sees them.
Features features(const sim::World& world, const sim::ObservationParams& observation = {});

// "height[s1][c3]", "difference[s0][c2]", "holes[s2]", "highest_stack", ...
std::string feature_name(std::size_t index);

// The smallest change of a feature that means something: a cell's height for
// heights, one hole, half a slice of depth, one box.
double resolution(std::size_t index);

}  // namespace plr::chooser
