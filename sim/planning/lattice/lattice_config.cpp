#include "plr/planning/lattice_config.hpp"

#include <plr/yaml_reader.hpp>

#include <cstdint>
#include <string>
#include <vector>

namespace plr::planning {
namespace {

// Far beyond any useful lattice, small enough to keep a mistyped file from
// building millions of primitives.
constexpr std::size_t kMaxSteps = 64;
constexpr std::int64_t kMaxStep = 10'000;
constexpr std::size_t kMaxPrimitives = 4096;
constexpr std::int64_t kMaxBudget = 100'000'000;

const std::vector<std::string> kModeKeys = {"resolution",     "steps",      "primitives",
                                            "snap_distance",  "snap_time",  "ee_speed",
                                            "line_tolerance", "plate_step", "max_expansions"};

ModeLattice read_mode(const yaml::Map& fields, PlanMode mode) {
  ModeLattice m;
  m.joints = planned_joints(mode);
  const std::size_t dims = mode == PlanMode::kArmCartesian ? 1 : m.joints.size();
  for (const yaml::Node& r :
       fields.required("resolution").list("a list of resolutions", dims, dims))
    m.resolution.push_back(r.positive().value_or(1.0));
  for (const yaml::Node& step : fields.find("steps").list("a list of step counts", 0, kMaxSteps)) {
    const auto k = step.integer(1, kMaxStep);
    if (!k) continue;
    for (std::size_t d = 0; d < dims; ++d) {
      for (int sign : {1, -1}) {
        std::vector<int> p(dims, 0);
        p[d] = sign * static_cast<int>(*k);
        m.primitives.push_back(p);
      }
    }
  }
  for (const yaml::Node& p :
       fields.find("primitives").list("a list of primitives", 0, kMaxPrimitives)) {
    std::vector<int> v;
    for (const yaml::Node& x : p.list("a primitive (steps per variable)", dims, dims))
      v.push_back(static_cast<int>(x.integer(-kMaxStep, kMaxStep).value_or(0)));
    m.primitives.push_back(std::move(v));
  }
  m.snap_distance = fields.find("snap_distance").number(0.0).value_or(m.snap_distance);
  m.snap_time = fields.find("snap_time").number(0.0).value_or(m.snap_time);
  m.ee_speed = fields.find("ee_speed").positive().value_or(m.ee_speed);
  m.line_tolerance = fields.find("line_tolerance").positive().value_or(m.line_tolerance);
  m.plate_step = fields.find("plate_step").number(0.0).value_or(m.plate_step);
  m.max_expansions =
      static_cast<std::uint64_t>(fields.find("max_expansions").integer(0, kMaxBudget).value_or(0));
  return m;
}

Expected<LatticeConfig> read(Expected<yaml::Document> doc) {
  if (!doc) return doc.error();
  const yaml::Map top = doc->root().map(
      "a map of mode -> lattice",
      {"M1", "M2", "M3", "M4", "M5", "M6", "experience", "experience_weight", "experience_paths"});
  LatticeConfig c;
  if (!top) return doc->error();
  c.experience.enabled = top.find("experience").boolean().value_or(c.experience.enabled);
  c.experience.weight =
      top.find("experience_weight").number(1.0, 100.0).value_or(c.experience.weight);
  c.experience.max_paths = static_cast<std::size_t>(
      top.find("experience_paths").integer(1, 1000).value_or(c.experience.max_paths));
  for (int i = 1; i <= 6; ++i) {
    const auto mode = static_cast<PlanMode>(i);
    const std::string key = "M" + std::to_string(i);
    const yaml::Node n = mode == PlanMode::kEscape ? top.find(key) : top.required(key);
    if (!n.present()) {
      if (mode == PlanMode::kEscape) c.modes[mode] = default_escape_lattice();
      continue;
    }
    const yaml::Map fields = n.map("a mode's lattice", kModeKeys);
    if (!fields) continue;
    c.modes[mode] = read_mode(fields, mode);
    if (c.modes[mode].primitives.empty() && doc->ok())
      n.error("no primitives ('steps' or 'primitives')");
  }
  return doc->result(std::move(c));
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
  return read(yaml::Document::open(path, "the lattice"));
}

plr::Expected<LatticeConfig> LatticeConfig::from_string(const std::string& yaml,
                                                        const std::string& source) {
  return read(yaml::Document::parse(yaml, source));
}

}  // namespace plr::planning
