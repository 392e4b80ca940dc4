// Per-mode state lattices: the lattice planner's, and the M6 escape's that
// every planner runs. Read from YAML (sim/robots/unloader_lattice.yaml
// documents the format).
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <plr/expected.hpp>

#include "plr/planning/plan_query.hpp"

namespace plr::planning {

struct ModeLattice {
  std::vector<int> joints;                   // configuration indices (M4: the arm's)
  std::vector<double> resolution;            // per planned variable
  std::vector<std::vector<int>> primitives;  // lattice steps per variable
  double snap_distance = 0.0;                // m, pose goals
  double snap_time = 0.0;                    // s, joint goals
  double ee_speed = 1.0;                     // m/s, arm heuristic
  double line_tolerance = 0.005;             // m, M4 deviation from the line
  double plate_step = 0.0;                   // m, M6 Cartesian plate steps (0: none)
  // The mode's own expansion budget (0: none): a search that has not found
  // a solution by then gives up, whatever budget the query allows. Sized
  // from the expansions successful searches took (docs/planner.md).
  std::uint64_t max_expansions = 0;
};

// Reuse of earlier paths within a trailer (experience graphs, Phillips et
// al. 2012) for the modes whose searches recur and can be long: M1, M2.
struct ExperienceSettings {
  bool enabled = false;
  // w_E: moves off the stored paths count w_E times their heuristic; a
  // first solution at ε costs at most ε w_E times the optimal lattice path.
  // A stored path is only followed when its cost beats w_E times the
  // straight-line estimate; with 2 no recorded A1 query followed one (the
  // search was only greedier), with 5 the hard ones did (docs/planner.md).
  double weight = 5.0;
  std::size_t max_paths = 16;  // per mode; the oldest is dropped
};

struct LatticeConfig {
  std::map<PlanMode, ModeLattice> modes;
  ExperienceSettings experience;

  // Read with plr/yaml_reader.hpp: unknown keys are errors, step and
  // primitive counts are bounded. The error is the first problem as one line,
  // "<source>:line:col: M1.steps[0]: must be positive, got 0". A file without
  // M6 gets default_escape_lattice().
  static plr::Expected<LatticeConfig> from_file(const std::string& path);
  static plr::Expected<LatticeConfig> from_string(const std::string& yaml,
                                                  const std::string& source = "<string>");
};

// The M6 escape's lattice unless a planner brings its own: unit steps of base,
// arm and nose lift, plus Cartesian plate steps.
ModeLattice default_escape_lattice();

}  // namespace plr::planning
