// Generated worlds per family. The test runs one seed per family by default
// (PLR_SIM_SEEDS raises it): dropping a pile costs seconds of wall time.
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

// Every generated world is free of interpenetration. Walls come out at rest
// and must stay so (at rest within 2 s, nothing sinks). Piles are dropped
// and settled for a while by make_environment; they must not sink into each
// other either. (Piles keep a residual jitter: they are not checked for rest
// here; bench_sim --environments reports how many do rest within 2 s.)
TEST_P(Environments, WorldsAreCleanAndWallsSettleWithin2Seconds) {
  const bool wall = GetParam() == EnvFamily::kA1 || GetParam() == EnvFamily::kA2;
  for (int seed = 0; seed < seed_count(); ++seed) {
    const auto s = static_cast<std::uint64_t>(seed);
    const World generated = generate_world(GetParam(), s);
    ASSERT_FALSE(generated.boxes.empty());
    EXPECT_TRUE(find_interpenetrations(generated, 1e-6).empty()) << "seed " << seed;
    if (wall) {
      Simulation sim(generated);
      EXPECT_GE(sim.settle(2.0), 0.0) << "seed " << seed << " still moving after 2 s";
      EXPECT_EQ(sim.world().boxes.size(), generated.boxes.size()) << "seed " << seed;
      EXPECT_TRUE(find_interpenetrations(sim.world(), 0.005).empty()) << "seed " << seed;
    } else {
      const World pile = make_environment(GetParam(), s, Trailer{}, 1.0);
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
