// Internal: which boxes may touch a given box or robot shape (the broad
// phase of contact): every box in a uniform grid over the trailer by its
// world-aligned bounding box. A box changes cells only when its bounding box
// crosses a cell border, and a sleeping box does not move at all, so the
// grid is updated, not rebuilt, every step. Queries list body indices in
// ascending order, so contacts are visited in the same order as by testing
// every pair, and give the same results.
#pragma once

#include <Eigen/Geometry>
#include <array>
#include <cstdint>
#include <vector>

#include "state.hpp"

namespace plr::sim::detail {

// Two world-aligned bounding boxes that do not even touch.
inline bool disjoint(const Eigen::Vector3d& lo1, const Eigen::Vector3d& hi1,
                     const Eigen::Vector3d& lo2, const Eigen::Vector3d& hi2) {
  return (lo1.array() > hi2.array()).any() || (lo2.array() > hi1.array()).any();
}

class BroadPhase {
 public:
  enum Which : std::uint8_t { kSleeping = 1, kMoving = 2 };  // moving: awake or held

  explicit BroadPhase(const Trailer& trailer);

  // Every box's bounding box for the step starting now (a sleeping box keeps
  // the one it fell asleep with: it has not moved).
  void update(const std::vector<Body>& bodies);
  // The same, visiting only the bodies in `moving` (ascending) and those
  // moving at the last update: the others slept, and have not moved, unless
  // a sleeping box was removed since (mark_stale()).
  void update(const std::vector<Body>& bodies, const std::vector<int>& moving);
  void mark_stale() { stale_ = true; }
  const Eigen::Vector3d& lo(std::size_t body) const { return lo_[body]; }
  const Eigen::Vector3d& hi(std::size_t body) const { return hi_[body]; }

  // Into `out`, ascending: the boxes of kind `which` (a Which or both) whose
  // bounding boxes overlap [lo, hi] (touching counts).
  void query(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, unsigned which,
             std::vector<int>& out) const;
  // The same answer as query() when `candidates` (ascending) holds every
  // box it would find, testing only those.
  void filter(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, unsigned which,
              const std::vector<int>& candidates, std::vector<int>& out) const;

 private:
  using Cell = std::array<int, 3>;
  struct Range {
    Cell lo, hi;
    bool operator!=(const Range& o) const { return lo != o.lo || hi != o.hi; }
  };
  Cell cell_of(const Eigen::Vector3d& p) const;  // clamped to the grid
  std::size_t index(int x, int y, int z) const {
    return static_cast<std::size_t>((x * count_[1] + y) * count_[2] + z);
  }
  void insert(int body, const Range& r);
  void update_body(const Body& b, std::size_t i);
  void erase(int body, const Range& r);

  Eigen::Vector3d origin_;
  Cell count_;
  Eigen::Array3d last_;                  // count_ - 1
  std::vector<std::vector<int>> cells_;  // bodies overlapping each cell
  std::vector<Eigen::Vector3d> lo_, hi_;
  std::vector<Range> range_;        // a box's cells
  std::vector<std::uint8_t> kind_;  // a Which; 0: not in the grid (gone)
  std::vector<int> moving_;         // kind kMoving at the last update, ascending
  std::vector<int> visit_;          // scratch
  bool stale_ = true;               // the next update visits every body
  // A query's scratch, one bit per body: met in a cell, and an answer (read
  // in index order, which sorts the answers).
  mutable std::vector<std::uint64_t> met_, hit_;
};

}  // namespace plr::sim::detail
