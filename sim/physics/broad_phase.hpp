// Internal: which boxes may touch a given box or robot shape (the broad
// phase of contact). Sleeping boxes do not move, so they sit in a uniform
// grid over the trailer that changes only when a box falls asleep or wakes;
// the few that move (awake, held) are tested against a query directly.
// Queries list body indices in ascending order, so contacts are visited in
// the same order as by testing every pair, and give the same results.
#pragma once

#include <Eigen/Geometry>
#include <array>
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
  enum Which : unsigned { kSleeping = 1, kMoving = 2 };

  explicit BroadPhase(const Trailer& trailer);

  // Every box's world-aligned bounding box for the step starting now (a
  // sleeping box keeps the one it fell asleep with: it has not moved).
  void update(const std::vector<Body>& bodies);
  const Eigen::Vector3d& lo(std::size_t body) const { return lo_[body]; }
  const Eigen::Vector3d& hi(std::size_t body) const { return hi_[body]; }

  // Into `out`, ascending: the boxes (of `which` kind, none gone) whose
  // bounding boxes overlap [lo, hi] (touching counts).
  void query(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, unsigned which,
             std::vector<int>& out) const;

 private:
  using Cell = std::array<int, 3>;
  Cell cell_of(const Eigen::Vector3d& p) const;  // clamped to the grid
  std::vector<int>& cell(const Cell& c) { return cells_[index(c)]; }
  std::size_t index(const Cell& c) const;

  Eigen::Vector3d origin_;
  Cell count_;
  std::vector<std::vector<int>> cells_;  // sleeping bodies overlapping each cell
  std::vector<Eigen::Vector3d> lo_, hi_;
  std::vector<Cell> cell_lo_, cell_hi_;  // a sleeping body's cells
  std::vector<bool> in_grid_;
  std::vector<int> moving_;  // awake and held bodies, ascending
};

}  // namespace plr::sim::detail
