// Lattice files (sim/planning/lattice/lattice_config.cpp).
#include <gtest/gtest.h>

#include "plr/planning/lattice_config.hpp"
#include "plr/sim/shipped_files.hpp"

namespace plr::planning {
namespace {

const std::string kMinimal = R"(
M1: {resolution: [0.02, 0.02, 0.02, 0.02], steps: [1, 5]}
M2: {resolution: [0.02, 0.02, 0.02, 0.02, 0.02], steps: [1]}
M3: {resolution: [0.01, 0.01, 0.01], steps: [1], snap_time: 3.0}
M4: {resolution: [0.01], steps: [1, 4], ee_speed: 0.5}
M5: {resolution: [0.01], primitives: [[10], [-10]]}
)";

std::string error_of(const std::string& yaml) {
  const auto c = LatticeConfig::from_string(yaml, "test.yaml");
  return c ? "" : c.error().message;
}

TEST(LatticeConfig, TheShippedFileLoads) {
  const auto c =
      LatticeConfig::from_file(sim::shipped_file("robots/unloader_lattice.yaml").value());
  ASSERT_TRUE(c) << c.error().message;
  EXPECT_EQ(c->modes.size(), 6u);
}

TEST(LatticeConfig, StepsBecomeSingleJointPrimitivesBothWays) {
  const auto c = LatticeConfig::from_string(kMinimal);
  ASSERT_TRUE(c) << c.error().message;
  const ModeLattice& m1 = c->modes.at(PlanMode::kArm);
  EXPECT_EQ(m1.joints, planned_joints(PlanMode::kArm));
  EXPECT_EQ(m1.primitives.size(), 2u * 4u * 2u);  // 2 step sizes x 4 joints x 2 signs
  EXPECT_EQ(m1.primitives.front(), (std::vector<int>{1, 0, 0, 0}));
  EXPECT_EQ(m1.primitives[1], (std::vector<int>{-1, 0, 0, 0}));
  EXPECT_EQ(c->modes.at(PlanMode::kBaseLine).primitives,
            (std::vector<std::vector<int>>{{10}, {-10}}));
  EXPECT_EQ(c->modes.at(PlanMode::kNose).snap_time, 3.0);
  EXPECT_EQ(c->modes.at(PlanMode::kArmCartesian).ee_speed, 0.5);
}

TEST(LatticeConfig, WithoutM6TheDefaultEscape) {
  const auto c = LatticeConfig::from_string(kMinimal);
  ASSERT_TRUE(c);
  const ModeLattice& m6 = c->modes.at(PlanMode::kEscape);
  const ModeLattice d = default_escape_lattice();
  EXPECT_EQ(m6.joints, d.joints);
  EXPECT_EQ(m6.resolution, d.resolution);
  EXPECT_EQ(m6.primitives, d.primitives);
  EXPECT_EQ(m6.plate_step, 0.015);
}

std::string with(const std::string& from, const std::string& to) {
  std::string yaml = kMinimal;
  yaml.replace(yaml.find(from), from.size(), to);
  return yaml;
}

TEST(LatticeConfig, ErrorsNameTheFileLineColumnAndKey) {
  EXPECT_EQ(error_of(with("[0.02, 0.02, 0.02, 0.02], steps", "[0.02], steps")),
            "test.yaml:2:18: M1.resolution: must have exactly 4 items, got 1");
  EXPECT_EQ(error_of("M1: [1, 2"), "test.yaml:1:1: syntax error: end of sequence flow not found");
  std::string no_m3 = kMinimal;
  no_m3.erase(no_m3.find("M3:"), no_m3.find("M4:") - no_m3.find("M3:"));
  EXPECT_EQ(error_of(no_m3), "test.yaml:2:1: missing required key 'M3'");
  EXPECT_EQ(error_of(with("M5: {resolution: [0.01], primitives: [[10], [-10]]}",
                          "M5: {resolution: [0.01]}")),
            "test.yaml:6:5: M5: no primitives ('steps' or 'primitives')");
  const auto missing = LatticeConfig::from_file("/nonexistent/lattice.yaml");
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().message,
            "/nonexistent/lattice.yaml: cannot read the lattice: No such file or directory");
}

// A mode's own expansion budget: absent is none (0); a negative one is refused.
TEST(LatticeConfig, AModesBudgetIsReadWhereGiven) {
  const auto c = LatticeConfig::from_string(
      with("snap_time: 3.0", "snap_time: 3.0, max_expansions: 250"), "test.yaml");
  ASSERT_TRUE(c) << c.error().message;
  EXPECT_EQ(c->modes.at(PlanMode::kNose).max_expansions, 250u);
  EXPECT_EQ(c->modes.at(PlanMode::kArm).max_expansions, 0u);
  EXPECT_NE(error_of(with("snap_time: 3.0", "snap_time: 3.0, max_expansions: -1"))
                .find("M3.max_expansions"),
            std::string::npos);
}

TEST(LatticeConfig, ExperienceIsOffUnlessTheFileTurnsItOn) {
  const auto off = LatticeConfig::from_string(kMinimal);
  ASSERT_TRUE(off) << off.error().message;
  EXPECT_FALSE(off->experience.enabled);
  const auto on = LatticeConfig::from_string(
      kMinimal + "experience: true\nexperience_weight: 3\nexperience_paths: 8\n");
  ASSERT_TRUE(on) << on.error().message;
  EXPECT_TRUE(on->experience.enabled);
  EXPECT_EQ(on->experience.weight, 3.0);
  EXPECT_EQ(on->experience.max_paths, 8u);
  EXPECT_NE(error_of(kMinimal + "experience: maybe\n").find("experience"), std::string::npos);
  EXPECT_NE(error_of(kMinimal + "experience_weight: 0.5\n").find("experience_weight"),
            std::string::npos);
}

TEST(LatticeConfig, BadTypesUnknownKeysAndRangesAreLocated) {
  // A value of the wrong type.
  EXPECT_EQ(error_of(with("ee_speed: 0.5", "ee_speed: fast")),
            "test.yaml:5:51: M4.ee_speed: expected a number, got 'fast'");
  EXPECT_EQ(
      error_of(with("primitives: [[10], [-10]]", "primitives: [10, [-10]]")),
      "test.yaml:6:39: M5.primitives[0]: expected a primitive (steps per variable), got '10'");
  // A key the reader does not know.
  EXPECT_EQ(error_of(with("snap_time: 3.0", "snap_tme: 3.0")),
            "test.yaml:4:50: M3.snap_tme: unknown key 'snap_tme' (did you mean 'snap_time'?)");
  EXPECT_EQ(error_of(kMinimal + "M7: {resolution: [1]}\n"),
            "test.yaml:7:1: M7: unknown key 'M7' (did you mean 'M1'?)");
  // Out of range.
  EXPECT_EQ(error_of(with("steps: [1, 5]", "steps: [0]")),
            "test.yaml:2:52: M1.steps[0]: must be positive, got 0");
  EXPECT_EQ(error_of(with("[0.01, 0.01, 0.01]", "[0.01, 0, 0.01]")),
            "test.yaml:4:25: M3.resolution[1]: must be positive, got 0");
  EXPECT_EQ(error_of(with("snap_time: 3.0", "snap_time: -3.0")),
            "test.yaml:4:61: M3.snap_time: must not be negative, got -3.0");
}

}  // namespace
}  // namespace plr::planning
