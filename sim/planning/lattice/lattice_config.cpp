#include "plr/planning/lattice_config.hpp"

#include <yaml-cpp/yaml.h>

#include <fstream>
#include <sstream>

namespace plr::planning {
namespace {

// The reader stops at the first error; the public functions return it.
struct Failure {
  std::string what;
};

[[noreturn]] void fail(const std::string& source, const std::string& cause) {
  throw Failure{source + ": " + cause};
}

ModeLattice parse_mode(const YAML::Node& n, PlanMode mode, const std::string& where) {
  ModeLattice m;
  m.joints = planned_joints(mode);
  const std::size_t dims = mode == PlanMode::kArmCartesian ? 1 : m.joints.size();
  if (!n["resolution"]) fail(where, "missing 'resolution'");
  m.resolution = n["resolution"].as<std::vector<double>>();
  if (m.resolution.size() != dims) {
    fail(where, "'resolution' needs " + std::to_string(dims) + " values, has " +
                    std::to_string(m.resolution.size()));
  }
  for (double r : m.resolution) {
    if (!(r > 0.0)) fail(where, "resolutions must be positive");
  }
  if (n["steps"]) {
    for (int k : n["steps"].as<std::vector<int>>()) {
      if (k <= 0) fail(where, "'steps' must be positive");
      for (std::size_t d = 0; d < dims; ++d) {
        for (int sign : {1, -1}) {
          std::vector<int> p(dims, 0);
          p[d] = sign * k;
          m.primitives.push_back(p);
        }
      }
    }
  }
  if (n["primitives"]) {
    for (const auto& p : n["primitives"]) {
      auto v = p.as<std::vector<int>>();
      if (v.size() != dims) fail(where, "a primitive needs " + std::to_string(dims) + " values");
      m.primitives.push_back(std::move(v));
    }
  }
  if (m.primitives.empty()) fail(where, "no primitives ('steps' or 'primitives')");
  m.snap_distance = n["snap_distance"].as<double>(0.0);
  m.snap_time = n["snap_time"].as<double>(0.0);
  m.ee_speed = n["ee_speed"].as<double>(1.0);
  m.line_tolerance = n["line_tolerance"].as<double>(0.005);
  m.plate_step = n["plate_step"].as<double>(0.0);
  if (!(m.ee_speed > 0.0) || !(m.line_tolerance > 0.0))
    fail(where, "ee_speed and line_tolerance must be positive");
  return m;
}

LatticeConfig parse(const std::string& yaml, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml);
  } catch (const YAML::Exception& e) {
    fail(source, std::string("YAML error: ") + e.what());
  }
  LatticeConfig c;
  for (int i = 1; i <= 6; ++i) {
    const auto mode = static_cast<PlanMode>(i);
    const std::string key = "M" + std::to_string(i);
    if (!root[key]) {
      if (mode != PlanMode::kEscape) fail(source, "missing mode '" + key + "'");
      c.modes[mode] = default_escape_lattice();
      continue;
    }
    try {
      c.modes[mode] = parse_mode(root[key], mode, source + ": " + key);
    } catch (const YAML::Exception& e) {
      fail(source, key + ": " + e.what());
    }
  }
  return c;
}

}  // namespace

ModeLattice default_escape_lattice() {
  ModeLattice m;
  m.joints = planned_joints(PlanMode::kEscape);
  // 1 cm of base and nose lift, 0.02 rad of each arm joint: small enough
  // that the first free state is close to where the robot got stuck.
  m.resolution = {0.01, 0.02, 0.02, 0.02, 0.02, 0.01};
  for (std::size_t d = 0; d < m.joints.size(); ++d) {
    for (int sign : {1, -1}) {
      std::vector<int> p(m.joints.size(), 0);
      p[d] = sign;
      m.primitives.push_back(std::move(p));
    }
  }
  m.plate_step = 0.015;
  return m;
}

plr::Expected<LatticeConfig> LatticeConfig::from_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) return plr::make_error(PLR_ERR_INVALID, path + ": cannot open file");
  std::stringstream ss;
  ss << in.rdbuf();
  return from_string(ss.str(), path);
}

plr::Expected<LatticeConfig> LatticeConfig::from_string(const std::string& yaml,
                                                        const std::string& source) {
  try {
    return parse(yaml, source);
  } catch (const Failure& f) {
    return plr::make_error(PLR_ERR_INVALID, f.what);
  }
}

}  // namespace plr::planning
