#include "plr/chooser/features.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

namespace plr::chooser {

namespace {

// Length of the overlap of [a0, a1] and [b0, b1].
double overlap(double a0, double a1, double b0, double b1) {
  return std::max(0.0, std::min(a1, b1) - std::max(a0, b0));
}

}  // namespace

Features features(const sim::World& world, const sim::ObservationParams& observation) {
  Features f{};
  if (world.boxes.empty()) return f;
  const double width = world.trailer.width;
  const double column_width = width / static_cast<double>(kColumns);
  const auto layers =
      static_cast<std::size_t>(std::ceil(world.trailer.height / kCellHeight - 1e-9));
  double front = std::numeric_limits<double>::infinity();
  double highest = 0.0;
  std::vector<sim::Bounds> bounds;
  bounds.reserve(world.boxes.size());
  for (const sim::Box& b : world.boxes) {
    bounds.push_back(sim::bounds(b));
    front = std::min(front, bounds.back().x0);
    highest = std::max(highest, bounds.back().z1);
  }

  // Covered volume per cell, added box by box over the cells each overlaps.
  std::vector<double> covered(kSlices * kColumns * layers, 0.0);
  const auto cell = [&](std::size_t s, std::size_t c, std::size_t k) -> double& {
    return covered[(s * kColumns + c) * layers + k];
  };
  const auto first_last = [](double lo, double hi, double origin, double step, std::size_t n) {
    const double a = std::floor((lo - origin) / step), b = std::ceil((hi - origin) / step);
    return std::pair<std::size_t, std::size_t>(
        static_cast<std::size_t>(std::clamp(a, 0.0, static_cast<double>(n))),
        static_cast<std::size_t>(std::clamp(b, 0.0, static_cast<double>(n))));
  };
  for (const sim::Bounds& b : bounds) {
    const auto [s0, s1] = first_last(b.x0, b.x1, front, kSliceDepth, kSlices);
    const auto [c0, c1] = first_last(b.y0, b.y1, -width / 2, column_width, kColumns);
    const auto [k0, k1] = first_last(b.z0, b.z1, 0.0, kCellHeight, layers);
    for (std::size_t s = s0; s < s1; ++s) {
      const double dx = overlap(b.x0, b.x1, front + s * kSliceDepth, front + (s + 1) * kSliceDepth);
      for (std::size_t c = c0; c < c1; ++c) {
        const double y = -width / 2 + c * column_width;
        const double dy = overlap(b.y0, b.y1, y, y + column_width);
        for (std::size_t k = k0; k < k1; ++k)
          cell(s, c, k) += dx * dy * overlap(b.z0, b.z1, k * kCellHeight, (k + 1) * kCellHeight);
      }
    }
  }
  const double half_cell = 0.5 * kSliceDepth * column_width * kCellHeight;

  for (std::size_t s = 0; s < kSlices; ++s) {
    double holes = 0;
    std::array<double, kColumns> h{};
    for (std::size_t c = 0; c < kColumns; ++c) {
      // The column's height is the top of its highest filled cell; a hole
      // is an empty cell below it (a gap a pick or sweep may bring down).
      std::size_t top = 0;
      for (std::size_t k = 0; k < layers; ++k)
        if (cell(s, c, k) >= half_cell) top = k + 1;
      for (std::size_t k = 0; k + 1 < top; ++k)
        if (cell(s, c, k) < half_cell) ++holes;
      h[c] = static_cast<double>(top) * kCellHeight;
      f[height_index(s, c)] = h[c];
    }
    for (std::size_t c = 0; c + 1 < kColumns; ++c)
      f[difference_index(s, c)] = std::abs(h[c + 1] - h[c]);
    f[holes_index(s)] = holes;
  }
  const sim::SceneAnalysis scene = sim::analyse(world, observation);
  f[kHighestStack] = highest;
  f[kPileDepth] = scene.pile_depth;
  f[kFirstWallHeight] = scene.wall_height;
  f[kBoxCount] = static_cast<double>(world.boxes.size());
  f[kFrontDistance] = front;
  return f;
}

double resolution(std::size_t index) {
  if (index < kSlices * kPerSlice) return index % kPerSlice == kPerSlice - 1 ? 1.0 : kCellHeight;
  switch (index) {
    case kPileDepth:
    case kFrontDistance:
      return kSliceDepth / 2;
    case kBoxCount:
      return 1.0;
    default:
      return kCellHeight;
  }
}

std::string feature_name(std::size_t index) {
  if (index < kSlices * kPerSlice) {
    const std::size_t s = index / kPerSlice, i = index % kPerSlice;
    if (i < kColumns) return fmt::format("height[s{}][c{}]", s, i);
    if (i < 2 * kColumns - 1) return fmt::format("difference[s{}][c{}]", s, i - kColumns);
    return fmt::format("holes[s{}]", s);
  }
  switch (index) {
    case kHighestStack:
      return "highest_stack";
    case kPileDepth:
      return "pile_depth";
    case kFirstWallHeight:
      return "first_wall_height";
    case kBoxCount:
      return "boxes";
    case kFrontDistance:
      return "front_distance";
    default:
      return fmt::format("feature[{}]", index);
  }
}

}  // namespace plr::chooser
