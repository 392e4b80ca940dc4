#include "plr/planning/shortcut.hpp"

namespace plr::planning {

using sim::CollisionChecker;
using sim::JointVector;

std::vector<JointVector> shortcut_path(const std::vector<JointVector>& input,
                                       const CollisionChecker& checker) {
  // Lattice paths repeat primitives: drop waypoints inside straight runs
  // first (exact, no check needed), which leaves few candidates.
  std::vector<JointVector> path;
  for (const JointVector& q : input) {
    if (!path.empty() && (q - path.back()).norm() < 1e-12) continue;
    if (path.size() >= 2) {
      const JointVector d1 = path.back() - path[path.size() - 2], d2 = q - path.back();
      if (d1.normalized().dot(d2.normalized()) > 1.0 - 1e-9) path.pop_back();
    }
    path.push_back(q);
  }
  if (path.size() <= 2) return path;
  std::vector<JointVector> out{path.front()};
  std::size_t i = 0;
  while (i + 1 < path.size()) {
    std::size_t next = i + 1;
    for (std::size_t j = path.size() - 1; j > i + 1; --j) {
      if (checker.is_motion_valid(path[i], path[j])) {
        next = j;
        break;
      }
    }
    out.push_back(path[next]);
    i = next;
  }
  return out;
}

}  // namespace plr::planning
