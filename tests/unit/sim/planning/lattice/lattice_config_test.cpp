// Lattice files (sim/planning/lattice/lattice_config.cpp).
#include <gtest/gtest.h>

#include "plr/planning/lattice_config.hpp"
#include "plr/sim/shipped_files.hpp"

namespace plr::planning {
namespace {

const char* kMinimal = R"(
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
  const auto c = LatticeConfig::from_file(sim::shipped_file("robots/unloader_lattice.yaml").value());
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

TEST(LatticeConfig, ErrorsNameTheSourceAndTheMode) {
  EXPECT_EQ(error_of("M1: {resolution: [0.02]}"),
            "test.yaml: M1: 'resolution' needs 4 values, has 1");
  EXPECT_EQ(error_of("M1: [1, 2").rfind("test.yaml: YAML error: ", 0), 0u) << error_of("M1: [1, 2");
  std::string no_m3 = kMinimal;
  no_m3.erase(no_m3.find("M3:"), no_m3.find("M4:") - no_m3.find("M3:"));
  EXPECT_EQ(error_of(no_m3), "test.yaml: missing mode 'M3'");
  std::string bad_step = kMinimal;
  bad_step.replace(bad_step.find("steps: [1, 5]"), 13, "steps: [0]");
  EXPECT_EQ(error_of(bad_step), "test.yaml: M1: 'steps' must be positive");
  const auto missing = LatticeConfig::from_file("/nonexistent/lattice.yaml");
  ASSERT_FALSE(missing);
  EXPECT_EQ(missing.error().message, "/nonexistent/lattice.yaml: cannot open file");
}

}  // namespace
}  // namespace plr::planning
