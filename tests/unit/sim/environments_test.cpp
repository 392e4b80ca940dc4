// Every family's worlds are free of interpenetration and settle within 2 s.
// The test runs one seed per family by default (PLR_SIM_SEEDS raises it):
// piles take ~15 s of wall time each to drop and settle on this machine.
#include <gtest/gtest.h>

#include <cstdlib>

#include "plr/sim/physics.hpp"

namespace plr::sim {
namespace {

int seed_count() {
  const char* env = std::getenv("PLR_SIM_SEEDS");
  return env != nullptr ? std::max(1, std::atoi(env)) : 1;
}

class Environments : public ::testing::TestWithParam<EnvFamily> {};

// Walls come out of the generator at rest; piles come out of make_environment
// (dropped and settled). Either way a fresh simulation of the world must come
// to rest within 2 s without boxes sinking into each other.
TEST_P(Environments, WorldsAreCleanAndSettleWithin2Seconds) {
  const bool wall = GetParam() == EnvFamily::kA1 || GetParam() == EnvFamily::kA2;
  for (int seed = 0; seed < seed_count(); ++seed) {
    const auto s = static_cast<std::uint64_t>(seed);
    const World generated = generate_world(GetParam(), s);
    ASSERT_FALSE(generated.boxes.empty());
    EXPECT_TRUE(find_interpenetrations(generated, 1e-6).empty()) << "seed " << seed;
    const World w = wall ? generated : make_environment(GetParam(), s);
    EXPECT_TRUE(find_interpenetrations(w, 0.005).empty()) << "seed " << seed;
    Simulation sim(w);
    EXPECT_GE(sim.settle(2.0), 0.0) << "seed " << seed << " still moving after 2 s";
    const World settled = sim.world();
    EXPECT_EQ(settled.boxes.size(), w.boxes.size()) << "seed " << seed;
    EXPECT_TRUE(find_interpenetrations(settled, 0.005).empty()) << "seed " << seed;
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
