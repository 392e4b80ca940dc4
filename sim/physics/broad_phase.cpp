#include "broad_phase.hpp"

#include <algorithm>
#include <cmath>

namespace plr::sim::detail {
namespace {

// About a box's size: a box covers a few cells and a query visits a few.
constexpr double kCellSize = 0.5;  // m

}  // namespace

BroadPhase::BroadPhase(const Trailer& trailer)
    : origin_(0.0, -0.5 * trailer.width, 0.0),
      count_{std::max(1, static_cast<int>(std::ceil(trailer.depth / kCellSize))),
             std::max(1, static_cast<int>(std::ceil(trailer.width / kCellSize))),
             std::max(1, static_cast<int>(std::ceil(trailer.height / kCellSize)))},
      cells_(static_cast<std::size_t>(count_[0] * count_[1] * count_[2])) {}

BroadPhase::Cell BroadPhase::cell_of(const Eigen::Vector3d& p) const {
  // Monotonic in p, so the cells of overlapping boxes overlap; what lies
  // outside the trailer falls into its border cells.
  Cell c{};
  for (int k = 0; k < 3; ++k) {
    const double at = std::floor((p[k] - origin_[k]) / kCellSize);
    c[static_cast<std::size_t>(k)] =
        static_cast<int>(std::clamp(at, 0.0, static_cast<double>(count_[k] - 1)));
  }
  return c;
}

std::size_t BroadPhase::index(const Cell& c) const {
  return static_cast<std::size_t>((c[0] * count_[1] + c[1]) * count_[2] + c[2]);
}

void BroadPhase::update(const std::vector<Body>& bodies) {
  const std::size_t n = bodies.size();
  lo_.resize(n);
  hi_.resize(n);
  cell_lo_.resize(n);
  cell_hi_.resize(n);
  in_grid_.resize(n, false);
  moving_.clear();
  for (std::size_t i = 0; i < n; ++i) {
    const Body& b = bodies[i];
    const bool asleep = b.mode == Mode::kAsleep;
    if (in_grid_[i]) {
      if (asleep) continue;  // has not moved
      for (int x = cell_lo_[i][0]; x <= cell_hi_[i][0]; ++x)
        for (int y = cell_lo_[i][1]; y <= cell_hi_[i][1]; ++y)
          for (int z = cell_lo_[i][2]; z <= cell_hi_[i][2]; ++z) {
            std::vector<int>& c = cell({x, y, z});
            const auto it = std::find(c.begin(), c.end(), static_cast<int>(i));
            *it = c.back();
            c.pop_back();
          }
      in_grid_[i] = false;
    }
    if (b.mode == Mode::kGone) continue;
    const Eigen::Vector3d e = b.box.pose.linear().cwiseAbs() * (0.5 * b.box.size);
    lo_[i] = b.box.pose.translation() - e;
    hi_[i] = b.box.pose.translation() + e;
    if (!asleep) {
      moving_.push_back(static_cast<int>(i));
      continue;
    }
    cell_lo_[i] = cell_of(lo_[i]);
    cell_hi_[i] = cell_of(hi_[i]);
    for (int x = cell_lo_[i][0]; x <= cell_hi_[i][0]; ++x)
      for (int y = cell_lo_[i][1]; y <= cell_hi_[i][1]; ++y)
        for (int z = cell_lo_[i][2]; z <= cell_hi_[i][2]; ++z)
          cell({x, y, z}).push_back(static_cast<int>(i));
    in_grid_[i] = true;
  }
}

void BroadPhase::query(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, unsigned which,
                       std::vector<int>& out) const {
  out.clear();
  if ((which & kSleeping) != 0) {
    const Cell a = cell_of(lo), b = cell_of(hi);
    for (int x = a[0]; x <= b[0]; ++x)
      for (int y = a[1]; y <= b[1]; ++y)
        for (int z = a[2]; z <= b[2]; ++z)
          for (const int j : cells_[index({x, y, z})]) {
            const auto k = static_cast<std::size_t>(j);
            if (!disjoint(lo, hi, lo_[k], hi_[k])) out.push_back(j);
          }
    // A box spanning several cells is met once per cell.
    std::sort(out.begin(), out.end());
    out.erase(std::unique(out.begin(), out.end()), out.end());
  }
  if ((which & kMoving) != 0) {
    const std::size_t sleeping = out.size();
    for (const int j : moving_) {
      const auto k = static_cast<std::size_t>(j);
      if (!disjoint(lo, hi, lo_[k], hi_[k])) out.push_back(j);
    }
    std::inplace_merge(out.begin(), out.begin() + static_cast<long>(sleeping), out.end());
  }
}

}  // namespace plr::sim::detail
