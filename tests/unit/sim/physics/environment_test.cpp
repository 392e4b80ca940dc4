// Generated worlds per family. The test runs two spread seeds per family by
// default, plus the seeds that once failed (PLR_SIM_SEEDS=N runs seeds
// 0..N-1 instead); `bench_sim --generators 100` runs 100 per family and
// prints how many settle (all: docs/notes-sim.md).
#include <gtest/gtest.h>

#include <cstdlib>
#include <vector>

#include "plr/sim/physics.hpp"

namespace plr::sim {
namespace {

// Besides two spread seeds, those that once failed: B1 40 (just missed 2 s),
// B2 8, 27, 95 (a column leaning over; a light box sinking under ~150 kg; a
// heavy stack swaying on a 3 kg box) and 45 (a heavy box on a light column
// swaying past 2 s until contact damping followed the carried load).
std::vector<std::uint64_t> seeds(EnvFamily family) {
  const char* env = std::getenv("PLR_SIM_SEEDS");
  if (env == nullptr && family == EnvFamily::kB1) return {0, 40, 57};
  if (env == nullptr && family == EnvFamily::kB2) return {0, 8, 27, 45, 57, 95};
  if (env == nullptr) return {0, 57};
  std::vector<std::uint64_t> all(static_cast<std::size_t>(std::max(1, std::atoi(env))));
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = i;
  return all;
}

class Environments : public ::testing::TestWithParam<EnvFamily> {};

// Every generated world is free of interpenetration and, simulated from its
// generated state (walls stacked, piles hovering before their drop), comes
// to rest within 2 s without sinking. Piles settled for a while by
// make_environment must not sink into each other either.
TEST_P(Environments, WorldsAreCleanAndSettleWithin2Seconds) {
  const bool wall = GetParam() == EnvFamily::kA1 || GetParam() == EnvFamily::kA2;
  for (const std::uint64_t seed : seeds(GetParam())) {
    const World generated = generate_world(GetParam(), seed);
    ASSERT_FALSE(generated.boxes.empty());
    EXPECT_TRUE(find_interpenetrations(generated, 1e-6).empty()) << "seed " << seed;
    Simulation sim(generated);
    EXPECT_GE(sim.settle(2.0), 0.0) << "seed " << seed << " still moving after 2 s";
    EXPECT_EQ(sim.world().boxes.size(), generated.boxes.size()) << "seed " << seed;
    EXPECT_TRUE(find_interpenetrations(sim.world(), 0.005).empty()) << "seed " << seed;
    if (!wall) {
      const World pile = make_environment(GetParam(), seed, Trailer{}, 1.0);
      EXPECT_EQ(pile.boxes.size(), generated.boxes.size()) << "seed " << seed;
      EXPECT_TRUE(find_interpenetrations(pile, 0.005).empty()) << "seed " << seed;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Families, Environments,
                         ::testing::Values(EnvFamily::kA1, EnvFamily::kA2, EnvFamily::kB1,
                                           EnvFamily::kB2),
                         [](const auto& info) { return std::string(to_string(info.param)); });

TEST(Environments, MakeEnvironmentIsDeterministic) {
  const World a = make_environment(EnvFamily::kB1, 5, Trailer{}, 0.3);
  const World b = make_environment(EnvFamily::kB1, 5, Trailer{}, 0.3);
  ASSERT_EQ(a.boxes.size(), b.boxes.size());
  for (std::size_t i = 0; i < a.boxes.size(); ++i) {
    EXPECT_EQ(a.boxes[i].pose.matrix(), b.boxes[i].pose.matrix());
  }
}

}  // namespace
}  // namespace plr::sim
