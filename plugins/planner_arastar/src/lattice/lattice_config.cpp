#include "lattice/lattice_config.hpp"

#include <yaml-cpp/yaml.h>

#include <fstream>
#include <sstream>
#include <stdexcept>

namespace plr::arastar {
namespace {

[[noreturn]] void fail(const std::string& source, const std::string& cause) {
  throw std::runtime_error(source + ": " + cause);
}

ModeLattice parse_mode(const YAML::Node& n, sim::PlanMode mode, const std::string& where) {
  ModeLattice m;
  m.joints = sim::planned_joints(mode);
  const std::size_t dims = mode == sim::PlanMode::kArmCartesian ? 1 : m.joints.size();
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

}  // namespace

LatticeConfig LatticeConfig::from_file(const std::string& path) {
  std::ifstream in(path);
  if (!in) fail(path, "cannot open file");
  std::stringstream ss;
  ss << in.rdbuf();
  return from_string(ss.str(), path);
}

LatticeConfig LatticeConfig::from_string(const std::string& yaml, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml);
  } catch (const YAML::Exception& e) {
    fail(source, std::string("YAML error: ") + e.what());
  }
  LatticeConfig c;
  for (int i = 1; i <= 6; ++i) {
    const auto mode = static_cast<sim::PlanMode>(i);
    const std::string key = "M" + std::to_string(i);
    if (!root[key]) fail(source, "missing mode '" + key + "'");
    try {
      c.modes[mode] = parse_mode(root[key], mode, source + ": " + key);
    } catch (const YAML::Exception& e) {
      fail(source, key + ": " + e.what());
    }
  }
  return c;
}

}  // namespace plr::arastar
