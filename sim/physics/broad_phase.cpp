#include "broad_phase.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <iterator>

namespace plr::sim::detail {
namespace {

// About a box's size: a box covers a few cells and a query visits a few.
constexpr double kCellSize = 0.5;  // m

int cells_along(double length) {
  return std::max(1, static_cast<int>(std::ceil(length / kCellSize)));
}

}  // namespace

BroadPhase::BroadPhase(const Trailer& trailer)
    : origin_(0.0, -0.5 * trailer.width, 0.0),
      count_{cells_along(trailer.depth), cells_along(trailer.width), cells_along(trailer.height)},
      last_(count_[0] - 1, count_[1] - 1, count_[2] - 1),
      cells_(static_cast<std::size_t>(count_[0] * count_[1] * count_[2])) {}

BroadPhase::Cell BroadPhase::cell_of(const Eigen::Vector3d& p) const {
  // Monotonic in p, so the cells of overlapping boxes overlap; what lies
  // outside the trailer falls into its border cells.
  const Eigen::Array3d at = ((p - origin_).array() / kCellSize).max(0.0).min(last_);
  return {static_cast<int>(at[0]), static_cast<int>(at[1]), static_cast<int>(at[2])};
}

void BroadPhase::insert(int body, const Range& r) {
  for (int x = r.lo[0]; x <= r.hi[0]; ++x)
    for (int y = r.lo[1]; y <= r.hi[1]; ++y)
      for (int z = r.lo[2]; z <= r.hi[2]; ++z) cells_[index(x, y, z)].push_back(body);
}

void BroadPhase::erase(int body, const Range& r) {
  for (int x = r.lo[0]; x <= r.hi[0]; ++x)
    for (int y = r.lo[1]; y <= r.hi[1]; ++y)
      for (int z = r.lo[2]; z <= r.hi[2]; ++z) {
        std::vector<int>& c = cells_[index(x, y, z)];
        *std::find(c.begin(), c.end(), body) = c.back();
        c.pop_back();
      }
}

void BroadPhase::update(const std::vector<Body>& bodies) {
  const std::size_t n = bodies.size();
  lo_.resize(n);
  hi_.resize(n);
  range_.resize(n);
  kind_.resize(n, 0);
  moving_.clear();
  for (std::size_t i = 0; i < n; ++i) {
    update_body(bodies[i], i);
    if (kind_[i] == kMoving) moving_.push_back(static_cast<int>(i));
  }
  stale_ = false;
}

void BroadPhase::update(const std::vector<Body>& bodies, const std::vector<int>& moving) {
  if (stale_ || kind_.size() != bodies.size()) {
    update(bodies);
    return;
  }
  visit_.clear();
  std::set_union(moving_.begin(), moving_.end(), moving.begin(), moving.end(),
                 std::back_inserter(visit_));
  moving_.clear();
  for (const int body : visit_) {
    const auto i = static_cast<std::size_t>(body);
    update_body(bodies[i], i);
    if (kind_[i] == kMoving) moving_.push_back(body);
  }
}

void BroadPhase::update_body(const Body& b, std::size_t i) {
  const int body = static_cast<int>(i);
  const std::uint8_t kind = b.mode == Mode::kGone     ? 0
                            : b.mode == Mode::kAsleep ? kSleeping
                                                      : kMoving;
  if (kind == kSleeping && kind_[i] == kSleeping) return;  // has not moved
  if (kind == 0) {
    if (kind_[i] != 0) erase(body, range_[i]);
    kind_[i] = 0;
    return;
  }
  const Eigen::Vector3d e = b.box.pose.linear().cwiseAbs() * (0.5 * b.box.size);
  lo_[i] = b.box.pose.translation() - e;
  hi_[i] = b.box.pose.translation() + e;
  const Range r{cell_of(lo_[i]), cell_of(hi_[i])};
  if (kind_[i] == 0) {
    insert(body, r);
  } else if (r != range_[i]) {
    erase(body, range_[i]);
    insert(body, r);
  }
  range_[i] = r;
  kind_[i] = kind;
}

void BroadPhase::query(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, unsigned which,
                       std::vector<int>& out) const {
  out.clear();
  const std::size_t words = (kind_.size() + 63) / 64;
  met_.assign(words, 0);
  hit_.assign(words, 0);
  const Cell a = cell_of(lo), b = cell_of(hi);
  for (int x = a[0]; x <= b[0]; ++x)
    for (int y = a[1]; y <= b[1]; ++y)
      for (int z = a[2]; z <= b[2]; ++z)
        for (const int j : cells_[index(x, y, z)]) {
          const auto k = static_cast<std::size_t>(j);
          const std::uint64_t bit = std::uint64_t{1} << (k % 64);
          if ((met_[k / 64] & bit) != 0) continue;  // spans several cells
          met_[k / 64] |= bit;
          if ((kind_[k] & which) != 0 && !disjoint(lo, hi, lo_[k], hi_[k])) hit_[k / 64] |= bit;
        }
  for (std::size_t w = 0; w < words; ++w) {
    for (std::uint64_t bits = hit_[w]; bits != 0; bits &= bits - 1)
      out.push_back(static_cast<int>(64 * w) + std::countr_zero(bits));
  }
}

void BroadPhase::filter(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, unsigned which,
                        const std::vector<int>& candidates, std::vector<int>& out) const {
  out.clear();
  for (const int j : candidates) {
    const auto k = static_cast<std::size_t>(j);
    if ((kind_[k] & which) != 0 && !disjoint(lo, hi, lo_[k], hi_[k])) out.push_back(j);
  }
}

}  // namespace plr::sim::detail
