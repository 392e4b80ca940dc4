#include <gtest/gtest.h>

#include <filesystem>

#include "plr/pomdp/cassandra_reader.hpp"
#include "plr/pomdp/model_io.hpp"
#include "plr/pomdp/policy_tree.hpp"
#include "plr/pomdp/pomdpx_reader.hpp"
#include "plr/pomdp/text.hpp"
#include "test_models.hpp"

namespace plr::pomdp {
namespace {

const std::filesystem::path kReference = PLR_POMDP_BENCHMARKS;
const std::filesystem::path kData = PLR_POMDP_TEST_DATA;

std::string cassandra_error(const char* text) {
  auto m = parse_cassandra(text, "m.pomdp");
  return m ? std::string("no error") : m.error().message;
}

std::string pomdpx_error(const std::string& text) {
  auto m = parse_pomdpx(text, "m.pomdpx");
  return m ? std::string("no error") : m.error().message;
}

double transition(const TabularModel& m, int a, int s, int next) {
  for (const Transition& t : m.transitions(a, s)) {
    if (t.next == next) return t.probability;
  }
  return 0.0;
}

double observation(const TabularModel& m, int a, int next, int o) {
  for (const ObsProb& p : m.observations(a, next)) {
    if (p.observation == o) return p.probability;
  }
  return 0.0;
}

void expect_tiger(const TabularModel& m) {
  ASSERT_EQ(m.num_states(), 2);
  ASSERT_EQ(m.num_actions(), 3);
  ASSERT_EQ(m.num_observations(), 2);
  EXPECT_DOUBLE_EQ(m.discount(), 0.95);
  EXPECT_DOUBLE_EQ(transition(m, 0, 0, 0), 1.0);
  EXPECT_DOUBLE_EQ(transition(m, 1, 0, 1), 0.5);
  EXPECT_DOUBLE_EQ(observation(m, 0, 0, 0), 0.85);
  EXPECT_DOUBLE_EQ(observation(m, 0, 1, 0), 0.15);
  EXPECT_DOUBLE_EQ(observation(m, 1, 1, 0), 0.5);
  EXPECT_DOUBLE_EQ(m.reward(0, 0), -1.0);
  EXPECT_DOUBLE_EQ(m.reward(1, 0), -100.0);
  EXPECT_DOUBLE_EQ(m.reward(1, 1), 10.0);
  EXPECT_DOUBLE_EQ(m.reward(2, 0), 10.0);
  EXPECT_DOUBLE_EQ(m.initial_belief().probability(0), 0.5);
  EXPECT_FALSE(m.is_terminal(0));
}

TEST(CassandraReader, ReadsTiger) {
  auto m = read_cassandra(kReference / "Tiger.pomdp");
  ASSERT_TRUE(m) << m.error().message;
  expect_tiger(*m);
  EXPECT_EQ(m->action_names[1], "open-left");
}

TEST(CassandraReader, ReadsRockSample44) {
  auto m = load_model(kReference / "RockSample_4_4.pomdp");
  ASSERT_TRUE(m) << m.error().message;
  EXPECT_EQ(m->num_states(), 257);
  EXPECT_EQ(m->num_actions(), 9);
  EXPECT_EQ(m->num_observations(), 2);
  EXPECT_EQ(m->initial_belief().size(), 16u);
  EXPECT_TRUE(m->is_terminal(256));  // "st"
  EXPECT_FALSE(m->is_terminal(0));
  EXPECT_DOUBLE_EQ(m->max_reward(), 10.0);
  EXPECT_DOUBLE_EQ(m->min_reward(), -100.0);
}

TEST(CassandraReader, LaterLinesOverrideAndWildcardsExpand) {
  auto m = parse_cassandra(R"(discount: 0.9
values: cost
states: 3
actions: a b
observations: x y
start: 0.2 0.3 0.5
T: * : * : 0 1
T: b : 1 : 0 0
T: b : 1 : 2 1.0
O: * : * uniform
O: a : 2
1 0
R: * : * : * : * 4
R: a : 2 : 0 : x 10
)",
                           "m.pomdp");
  ASSERT_TRUE(m) << m.error().message;
  EXPECT_DOUBLE_EQ(transition(*m, 1, 1, 2), 1.0);
  EXPECT_DOUBLE_EQ(transition(*m, 1, 1, 0), 0.0);
  EXPECT_DOUBLE_EQ(observation(*m, 0, 2, 0), 1.0);
  EXPECT_DOUBLE_EQ(observation(*m, 1, 2, 0), 0.5);
  // Costs are negated; a reward that depends on the observation is folded
  // into its expectation: O(x | a, 0) = 0.5, so -(0.5 * 10 + 0.5 * 4).
  EXPECT_DOUBLE_EQ(m->reward(0, 2), -7.0);
  EXPECT_DOUBLE_EQ(m->reward(1, 2), -4.0);
  EXPECT_DOUBLE_EQ(m->initial_belief().probability(2), 0.5);
}

TEST(CassandraReader, LocatedErrors) {
  EXPECT_EQ(
      cassandra_error("discount: 0.9\nstates: a b\nactions: x\nobservations: o\nT: x : a : c 1\n"),
      "m.pomdp:5:12: unknown state 'c'");
  EXPECT_EQ(cassandra_error(
                "discount: 0.9\nstates: a b\nactions: x\nobservations: o\nT: x : a : b 1.5\n"),
            "m.pomdp:5:14: probability 1.5 is not in [0, 1]");
  EXPECT_EQ(cassandra_error("discount: 0.9\nstates: a b\nactions: x\nobservations: o\n"
                            "T: x : a : b 0.5\nT: x : b : b 1\nO: x : * : o 1\n"),
            "m.pomdp:5:1: T probabilities for action 'x' in state 'a' sum to 0.5, not 1");
  EXPECT_EQ(
      cassandra_error("discount: 0.9\nstates: a b\nactions: x\nobservations: o\nT: x identity\n"),
      "m.pomdp:5:6: O has no entries for action 'x' in state 'a'");
  EXPECT_EQ(cassandra_error("discount: 1.5\n"), "m.pomdp:1:11: the discount must be in [0, 1]");
  EXPECT_EQ(cassandra_error("discount: 0.9\nstates: a\nT: x : a : a 1\n"),
            "m.pomdp:3:1: states, actions and observations must be declared before this line");
  EXPECT_EQ(cassandra_error("discount: 0.9\nstates: a a\n"),
            "m.pomdp:2:11: state 'a' declared twice");
  EXPECT_EQ(cassandra_error("discount: 0.9\nbogus line\n"),
            "m.pomdp:2:1: expected a statement (discount:, values:, states:, actions:, "
            "observations:, start:, T:, O:, R:), found 'bogus'");
  EXPECT_EQ(
      cassandra_error("discount: 0.9\nstates: a b\nactions: x\nobservations: o\nT: x\n1 0\n0"),
      "m.pomdp:7:1: unexpected end of file, expected a probability");
  EXPECT_EQ(cassandra_error(""), "m.pomdp:1:1: no discount: line");
}

TEST(CassandraReader, SizeLimits) {
  ReadLimits small;
  small.max_states = 10;
  small.max_entries = 50;
  auto m = parse_cassandra("discount: 0.9\nstates: 11\n", "m.pomdp", small);
  ASSERT_FALSE(m);
  EXPECT_EQ(m.error().message, "m.pomdp:2:9: state count 11 is not in [1, 10]");
  m = parse_cassandra("discount: 0.9\nstates: 10\nactions: 2\nobservations: 2\nT: * uniform\n",
                      "m.pomdp", small);
  ASSERT_FALSE(m);
  EXPECT_EQ(m.error().message, "m.pomdp:5:1: more than 50 table entries");
  small.max_file_bytes = 4;
  m = parse_cassandra("discount: 0.9\n", "m.pomdp", small);
  ASSERT_FALSE(m);
  EXPECT_EQ(m.error().message, "m.pomdp:1:1: file larger than 4 bytes");
}

TEST(CassandraReader, MissingFile) {
  auto m = load_model("/nonexistent/x.pomdp");
  ASSERT_FALSE(m);
  EXPECT_EQ(m.error().message.rfind("/nonexistent/x.pomdp:1:1: cannot read: ", 0), 0u)
      << m.error().message;
}

// Tiger in POMDPX, factored the way SARSOP's examples write it.
const char* kTigerX = R"(<?xml version="1.0" encoding="ISO-8859-1"?>
<pomdpx version="0.1" id="tiger">
<Discount>0.95</Discount>
<Variable>
  <StateVar vnamePrev="tiger_0" vnameCurr="tiger_1" fullyObs="false">
    <ValueEnum>left right</ValueEnum>
  </StateVar>
  <ObsVar vname="hear"><ValueEnum>hear-left hear-right</ValueEnum></ObsVar>
  <ActionVar vname="act"><ValueEnum>listen open-left open-right</ValueEnum></ActionVar>
  <RewardVar vname="r"/>
</Variable>
<InitialStateBelief>
  <CondProb><Var>tiger_0</Var><Parent>null</Parent>
    <Parameter type="TBL"><Entry><Instance>-</Instance><ProbTable>uniform</ProbTable></Entry></Parameter>
  </CondProb>
</InitialStateBelief>
<StateTransitionFunction>
  <CondProb><Var>tiger_1</Var><Parent>act tiger_0</Parent>
    <Parameter type="TBL">
      <Entry><Instance>listen - -</Instance><ProbTable>identity</ProbTable></Entry>
      <Entry><Instance>open-left * -</Instance><ProbTable>0.5 0.5</ProbTable></Entry>
      <Entry><Instance>open-right * -</Instance><ProbTable>uniform</ProbTable></Entry>
    </Parameter>
  </CondProb>
</StateTransitionFunction>
<ObsFunction>
  <CondProb><Var>hear</Var><Parent>act tiger_1</Parent>
    <Parameter type="TBL">
      <Entry><Instance>listen - -</Instance><ProbTable>0.85 0.15 0.15 0.85</ProbTable></Entry>
      <Entry><Instance>open-left * -</Instance><ProbTable>uniform</ProbTable></Entry>
      <Entry><Instance>open-right * -</Instance><ProbTable>uniform</ProbTable></Entry>
    </Parameter>
  </CondProb>
</ObsFunction>
<RewardFunction>
  <Func><Var>r</Var><Parent>act tiger_0</Parent>
    <Parameter type="TBL">
      <Entry><Instance>listen *</Instance><ValueTable>-1</ValueTable></Entry>
      <Entry><Instance>open-left -</Instance><ValueTable>-100 10</ValueTable></Entry>
      <Entry><Instance>open-right -</Instance><ValueTable>10 -100</ValueTable></Entry>
    </Parameter>
  </Func>
</RewardFunction>
</pomdpx>
)";

TEST(PomdpxReader, TigerMatchesTheCassandraFile) {
  auto m = parse_pomdpx(kTigerX, "tiger.pomdpx");
  ASSERT_TRUE(m) << m.error().message;
  expect_tiger(*m);
  EXPECT_EQ(m->state_names[1], "right");
  EXPECT_EQ(m->observation_names[0], "hear-left");
}

// Two state variables and two observation variables: the flat model is
// their product (first variable slowest).
TEST(PomdpxReader, FlattensFactoredModels) {
  auto m = read_pomdpx(kData / "factored.pomdpx");
  ASSERT_TRUE(m) << m.error().message;
  ASSERT_EQ(m->num_states(), 4);
  ASSERT_EQ(m->num_observations(), 4);
  EXPECT_EQ(m->state_names[2], "b1,s0");
  // flip toggles b and keeps c: (b0,c1) -> (b1,c1).
  EXPECT_DOUBLE_EQ(transition(*m, 1, 1, 3), 1.0);
  // Observations of b and c are exact apart from 0.2 noise on c.
  EXPECT_DOUBLE_EQ(observation(*m, 0, 3, 3), 0.8);
  EXPECT_DOUBLE_EQ(observation(*m, 0, 3, 2), 0.2);
  // Reward 1 for c1 after any action plus 2 for flipping in b0.
  EXPECT_DOUBLE_EQ(m->reward(1, 1), 3.0);
  EXPECT_DOUBLE_EQ(m->reward(0, 0), 0.0);
  EXPECT_DOUBLE_EQ(m->initial_belief().probability(1), 0.3);
}

TEST(PomdpxReader, LocatedErrors) {
  EXPECT_EQ(pomdpx_error("<pomdpx>\n<Discount>0.9</Discount>\n<Variable>\n</pomdpx>"),
            "m.pomdpx:4: XML: mismatched tag");
  EXPECT_EQ(pomdpx_error("<pomdp/>"), "m.pomdpx:1: root element is <pomdp>, not <pomdpx>");
  std::string bad = kTigerX;
  bad.replace(bad.find("0.85 0.15 0.15"), 14, "0.85 0.15 0.25");
  EXPECT_EQ(pomdpx_error(bad),
            "m.pomdpx:27: ObsFunction P(hear | act=listen, tiger_1=right) sums "
            "to 1.1, not 1");
  bad = kTigerX;
  bad.replace(bad.find("open-left * -</Instance><ProbTable>0.5"), 9, "open-down");
  EXPECT_EQ(pomdpx_error(bad), "m.pomdpx:21: 'open-down' is not a value of 'act'");
  bad = kTigerX;
  bad.replace(
      bad.find(
          "act tiger_0</Parent>\n    <Parameter type=\"TBL\">\n      <Entry><Instance>listen - -"),
      3, "axe");
  EXPECT_EQ(pomdpx_error(bad), "m.pomdpx:18: unknown variable 'axe'");
}

// The tokenizer and number parser both readers and the policy trees share.
TEST(Text, TokensAndNumbers) {
  const auto t =
      text::tokenize("T: a:b # note\n  1e-3\t+2", {.colon_tokens = true, .comments = true});
  ASSERT_EQ(t.size(), 7u);
  EXPECT_EQ(t[1].text, ":");
  EXPECT_EQ(t[3].text, ":");
  EXPECT_EQ(t[4].text, "b");
  EXPECT_EQ(t[5].text, "1e-3");
  EXPECT_EQ(t[5].line, 2);
  EXPECT_EQ(t[5].column, 3);
  EXPECT_EQ(text::words("a:b  c\n"), (std::vector<std::string_view>{"a:b", "c"}));
  EXPECT_EQ(text::to_number("+2"), 2.0);
  EXPECT_EQ(text::to_number("-0.5"), -0.5);
  EXPECT_FALSE(text::to_number("+-1"));
  EXPECT_FALSE(text::to_number("1e999"));
  EXPECT_FALSE(text::to_number("inf"));
  EXPECT_FALSE(text::to_number("1.5x"));
  EXPECT_FALSE(text::to_number(""));
  EXPECT_EQ(text::to_index("12"), 12);
  EXPECT_FALSE(text::to_index("-1"));
  EXPECT_FALSE(text::to_index("1.0"));
}

TEST(PolicyTree, RoundTripAndErrors) {
  PolicyTree t;
  t.nodes = {{1, {{0, 1}, {2, 2}}, -1.5, 2.0}, {0, {}, 0.0, 0.0}, {2, {}, 1.0, 1.0}};
  const std::string text = format_policy_tree(t);
  auto back = parse_policy_tree(text, "t");
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(back->nodes.size(), 3u);
  EXPECT_EQ(back->next(0, 2), 2u);
  EXPECT_FALSE(back->next(0, 1).has_value());
  EXPECT_DOUBLE_EQ(back->nodes[0].lower, -1.5);
  EXPECT_EQ(back->depth(), 2u);
  auto bad =
      parse_policy_tree("plr-policy-tree 1\nnodes 2 root 0\n0 1 0 0 0:1\n1 0 0 0 0:1\n", "t");
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error().message, "t:4: node 1 has more than one parent");
  bad = parse_policy_tree("plr-policy-tree 1\nnodes 2 root 0\n0 x 0 0\n", "t");
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error().message, "t:3: expected '0 <action> <lower> <upper> [obs:child ...]'");
  bad = parse_policy_tree("plr-policy-tree 1\nnodes 3 root 0\n0 1 0 0\n", "t");
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error().message, "t:2: 3 nodes announced, fewer lines follow");
}

}  // namespace
}  // namespace plr::pomdp
