#include <gtest/gtest.h>

#include <map>

#include "plr/pomdp/belief.hpp"
#include "plr/pomdp/model.hpp"
#include "test_models.hpp"

namespace plr::pomdp {
namespace {

TEST(Belief, NormalizeMergesSortsAndScales) {
  Belief b;
  b.add(3, 1.0);
  b.add(1, 2.0);
  b.add(3, 1.0);
  b.add(7, 0.0);
  EXPECT_DOUBLE_EQ(b.normalize(), 4.0);
  ASSERT_EQ(b.size(), 2u);
  EXPECT_EQ(b.particles()[0].state, 1);
  EXPECT_DOUBLE_EQ(b.probability(1), 0.5);
  EXPECT_DOUBLE_EQ(b.probability(3), 0.5);
  EXPECT_DOUBLE_EQ(b.probability(7), 0.0);
}

TEST(Belief, SignatureIgnoresRoundingNoise) {
  Belief a({{0, 0.25}, {1, 0.75}});
  Belief b({{0, 0.25 + 1e-13}, {1, 0.75 - 1e-13}});
  Belief c({{0, 0.3}, {1, 0.7}});
  EXPECT_EQ(a.signature(1e-9), b.signature(1e-9));
  EXPECT_TRUE(a.approx_equal(b, 1e-9));
  EXPECT_NE(a.signature(1e-9), c.signature(1e-9));
  EXPECT_FALSE(a.approx_equal(c, 1e-9));
}

// Tiger's listen: the posterior after hearing the tiger left once is
// (0.85, 0.15), twice 0.85^2 / (0.85^2 + 0.15^2).
TEST(Belief, ExactUpdateOfTigerListen) {
  auto tiger = parse_cassandra(R"(discount: 0.95
states: left right
actions: listen
observations: hear-left hear-right
T: listen identity
O: listen
0.85 0.15
0.15 0.85
R: listen : * : * : * -1
)",
                               "tiger");
  ASSERT_TRUE(tiger) << tiger.error().message;
  Rng rng(1);
  const Expansion e = tiger->expand(tiger->initial_belief(), 0, rng);
  EXPECT_DOUBLE_EQ(e.reward, -1.0);
  ASSERT_EQ(e.outcomes.size(), 2u);
  EXPECT_DOUBLE_EQ(e.outcomes[0].probability, 0.5);
  EXPECT_NEAR(e.outcomes[0].next.probability(0), 0.85, 1e-12);
  const Belief twice = update_belief(*tiger, e.outcomes[0].next, 0, 0, rng);
  EXPECT_NEAR(twice.probability(0), 0.85 * 0.85 / (0.85 * 0.85 + 0.15 * 0.15), 1e-12);
  // P(hear-left | belief (0.85, 0.15)) = 0.85 * 0.85 + 0.15 * 0.15.
  const Expansion e2 = tiger->expand(e.outcomes[0].next, 0, rng);
  EXPECT_NEAR(e2.outcomes[0].probability, 0.745, 1e-12);
}

// A model known only by simulation: the default expand() groups simulated
// particles by observation.
class Coin final : public GenerativeModel {
 public:
  int num_actions() const override { return 1; }
  int num_observations() const override { return 2; }
  double discount() const override { return 0.9; }
  double min_reward() const override { return 0.0; }
  double max_reward() const override { return 1.0; }
  Belief initial_belief() const override { return Belief({{0, 0.25}, {1, 0.75}}); }
  bool is_terminal(StateId) const override { return false; }
  Step step(StateId s, ActionId, Rng&) const override { return {s, s, s == 1 ? 1.0 : 0.0, false}; }
};

TEST(Belief, ParticleExpansionGroupsByObservation) {
  Coin coin;
  Rng rng(3);
  const Expansion e = coin.expand(coin.initial_belief(), 0, rng);
  EXPECT_DOUBLE_EQ(e.reward, 0.75);
  ASSERT_EQ(e.outcomes.size(), 2u);
  EXPECT_DOUBLE_EQ(e.outcomes[0].probability, 0.25);
  EXPECT_DOUBLE_EQ(e.outcomes[1].probability, 0.75);
  EXPECT_DOUBLE_EQ(e.outcomes[1].next.probability(1), 1.0);
}

TEST(Belief, SampleStateFollowsWeights) {
  Rng rng(5);
  const Belief b({{0, 0.2}, {1, 0.8}});
  std::map<StateId, int> counts;
  for (int i = 0; i < 10000; ++i) ++counts[sample_state(b, rng)];
  EXPECT_NEAR(counts[1] / 10000.0, 0.8, 0.02);
}

}  // namespace
}  // namespace plr::pomdp
