// Per-mode lattice parameters of the ARA* planner, read from YAML
// (plugins/planner_arastar/primitives/unloader.yaml documents the format).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "plr/sim/plan_types.hpp"

namespace plr::arastar {

struct ModeLattice {
  std::vector<int> joints;                   // configuration indices (M4: the arm's)
  std::vector<double> resolution;            // per planned variable
  std::vector<std::vector<int>> primitives;  // lattice steps per variable
  double snap_distance = 0.0;                // m, pose goals
  double snap_time = 0.0;                    // s, joint goals
  double ee_speed = 1.0;                     // m/s, arm heuristic
  double line_tolerance = 0.005;             // m, M4 deviation from the line
  double plate_step = 0.0;                   // m, M6 Cartesian plate steps (0: none)
};

struct LatticeConfig {
  std::map<sim::PlanMode, ModeLattice> modes;

  // Throw std::runtime_error "<source>: <cause>".
  static LatticeConfig from_file(const std::string& path);
  static LatticeConfig from_string(const std::string& yaml, const std::string& source = "<string>");
};

}  // namespace plr::arastar
