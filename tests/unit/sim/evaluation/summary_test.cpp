// The evaluation's figures (sim/evaluation/summary.cpp) on a few synthetic
// runs (runs.hpp), each checked against its arithmetic done by hand.
#include "plr/evaluation/summary.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "plr/evaluation/run.hpp"
#include "runs.hpp"

namespace plr::evaluation {
namespace {

const nlohmann::json& summary() {
  static const nlohmann::json s = summarize(testing::settings(), testing::runs(), true);
  return s;
}

const nlohmann::json& method(const char* env, const char* m) {
  return summary()["environments"][env]["methods"][m];
}

TEST(BoxesAt, IsTheLastPointAtOrBeforeTheTime) {
  const nlohmann::json curve = {{5, 1}, {10, 2}, {20, 5}};
  EXPECT_EQ(boxes_at(curve, 0), 0);
  EXPECT_EQ(boxes_at(curve, 5), 1);
  EXPECT_EQ(boxes_at(curve, 19.9), 2);
  EXPECT_EQ(boxes_at(curve, 20), 5);
  EXPECT_EQ(boxes_at(curve, 1e9), 5);
  EXPECT_EQ(boxes_at(nlohmann::json::array(), 10), 0);
}

TEST(Summary, TheGridRunsFromZeroToTheHorizon) {
  const auto& grid = summary()["grid_s"];
  ASSERT_EQ(grid.size(), static_cast<std::size_t>(kGridPoints));
  EXPECT_EQ(grid.front(), 0.0);
  EXPECT_DOUBLE_EQ(grid[1].get<double>(), 1.0);
  EXPECT_EQ(grid.back(), 120.0);
}

TEST(Summary, TheMeanCurveAndItsStandardErrorOverAMethodsRuns) {
  // At 60 s H's runs have 10, 6 and 10 boxes: mean 26/3, sample sd
  // sqrt(16/3), standard error that over sqrt(3): 4/3.
  const auto& h = method("A1", "H");
  EXPECT_EQ(h["runs"], 3);
  EXPECT_EQ(h["failed"], 1);
  EXPECT_NEAR(h["mean"][60].get<double>(), 26.0 / 3, 1e-12);
  EXPECT_NEAR(h["se"][60].get<double>(), 4.0 / 3, 1e-12);
  // At 30 s: 0, 4 and 0.
  EXPECT_NEAR(h["mean"][30].get<double>(), 4.0 / 3, 1e-12);
  EXPECT_EQ(h["mean"][0], 0.0);
  EXPECT_EQ(h["se"][0], 0.0);
  const auto& end = h["boxes_at_horizon"];
  EXPECT_NEAR(end["mean"].get<double>(), 26.0 / 3, 1e-12);
  EXPECT_NEAR(end["sd"].get<double>(), std::sqrt(16.0 / 3), 1e-12);
  EXPECT_NEAR(end["se"].get<double>(), 4.0 / 3, 1e-12);
  EXPECT_EQ(end["n"], 3);
  // Halfway (60 s) H is done.
  EXPECT_NEAR(h["boxes_at_half"]["mean"].get<double>(), 26.0 / 3, 1e-12);
  EXPECT_EQ(h["boxes_total"]["mean"], 10.0);
  EXPECT_EQ(h["wall_s"]["mean"], 30.0);
}

TEST(Summary, TheTimeTo90PercentIsTheMedianOverTheRunsThatGotThere) {
  // H: 60 s and 40 s, the third never got to 9 boxes; PLR: 50 s and 100 s.
  const auto& h = method("A1", "H")["robot_s_to_90_percent"];
  EXPECT_EQ(h["n"], 2);
  EXPECT_EQ(h["median"], 50.0);
  EXPECT_EQ(h["mean"], 50.0);
  EXPECT_EQ(method("A1", "PLR")["robot_s_to_90_percent"]["median"], 75.0);
}

TEST(Summary, WholeTrailerFiguresCountARunThatNeverGotThereAtTheHorizon) {
  // H empties two of three runs, at 60 s and 40 s; the third is counted at
  // the 120 s horizon: mean 220/3.
  const auto& h = method("A1", "H");
  const auto& empty = h["time_to_empty_s"];
  EXPECT_EQ(empty["reached"], 2);
  EXPECT_NEAR(empty["mean"].get<double>(), 220.0 / 3, 1e-12);
  EXPECT_EQ(empty["n"], 3);
  EXPECT_EQ(h["time_to_share_s"]["100"], empty);
  // Half of the boxes: at 60, 30 (4 of 10 is not half: 60) and 40 s.
  EXPECT_NEAR(h["time_to_share_s"]["50"]["mean"].get<double>(), (60.0 + 60 + 40) / 3, 1e-12);
  EXPECT_EQ(h["time_to_share_s"]["50"]["reached"], 3);
  // Boxes at the checkpoints past the horizon are those at its end.
  for (const char* t : {"300", "600", "1200"}) {
    EXPECT_NEAR(h["boxes_at"][t]["mean"].get<double>(), 26.0 / 3, 1e-12) << t;
    EXPECT_NEAR(h["boxes_at"][t]["se"].get<double>(), 4.0 / 3, 1e-12) << t;
  }
}

TEST(Summary, StopReasonsCountFailedRunsByTheirError) {
  const auto& stops = method("A1", "H")["stop_reasons"];
  EXPECT_EQ(stops["trailer empty"], 3);
  EXPECT_EQ(stops["timed out"], 1);
  EXPECT_DOUBLE_EQ(method("A1", "PLR")["library_action_share"]["mean"].get<double>(), 0.5);
  // No run of H on B1: the method is left out there.
  EXPECT_FALSE(summary()["environments"]["B1"]["methods"].contains("H"));
}

TEST(Summary, PlrAgainstHIsTheDifferenceOverItsStandardError) {
  // PLR 12 ± 0, H 26/3 ± 4/3: 10/3 boxes ahead, 2.5 standard errors.
  const nlohmann::json* versus = nullptr;
  for (const auto& f : summary()["findings"])
    if (f.value("kind", "") == "versus") versus = &f;
  ASSERT_NE(versus, nullptr);
  EXPECT_EQ((*versus)["a"], "PLR");
  EXPECT_EQ((*versus)["b"], "H");
  EXPECT_NEAR((*versus)["difference"].get<double>(), 10.0 / 3, 1e-12);
  EXPECT_NEAR((*versus)["z"].get<double>(), 2.5, 1e-12);
  EXPECT_EQ((*versus)["text"],
            "A1: PLR unloads 12.0 ± 0.0 boxes by 120 s, H 8.7 ± 1.3: ahead by +3.3 boxes (+2.5 "
            "standard errors)");
  const auto& claims = summary()["claims"];
  ASSERT_GE(claims.size(), 2u);
  // From 40 s to 50 s PLR has none of its boxes out and H 0, 4 and 10: H
  // is 14/3 ahead with a standard error of sqrt(76)/3, more than one.
  EXPECT_EQ(claims[0]["claim"], "PLR >= H on A1");
  EXPECT_EQ(claims[0]["holds"], false);
  EXPECT_NEAR(claims[0]["z"].get<double>(), -14 / std::sqrt(76.0), 1e-12);
  EXPECT_EQ(claims[0]["at_s"], 40.0);
  // By 600 s (past the horizon: the runs' last counts) PLR is 2.5 standard
  // errors ahead.
  EXPECT_EQ(claims[1]["claim"], "PLR > H on A1 at 600 s");
  EXPECT_EQ(claims[1]["holds"], true);
  EXPECT_NEAR(claims[1]["z"].get<double>(), 2.5, 1e-12);
  // Half of PLR's actions ran a library strategy (2 boxes in 10 s), the
  // other half H (1 in 10 s); H's runs moved 3 boxes in 10 s.
  const auto& why = claims[0]["why"];
  EXPECT_DOUBLE_EQ(why["library_action_share"].get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(why["library_boxes_per_s"].get<double>(), 0.2);
  EXPECT_DOUBLE_EQ(why["plr_hardcoded_boxes_per_s"].get<double>(), 0.1);
  EXPECT_DOUBLE_EQ(why["h_boxes_per_s"].get<double>(), 0.3);
}

TEST(Summary, TableOnePoolsThePlanningTimesOfAllTheTableMethodsRuns) {
  // PLR's three runs (both environments): 10, 20 and 0 queries of M2.
  const auto& t1 = summary()["table1"];
  EXPECT_EQ(t1["method"], "PLR");
  EXPECT_EQ(t1["runs"], 3);
  const auto& m2 = t1["modes"]["M2"];
  EXPECT_EQ(m2["name"], "M2");  // the last run has no M2: its key names it
  EXPECT_DOUBLE_EQ(m2["queries_per_run"].get<double>(), 10.0);
  EXPECT_DOUBLE_EQ(m2["queries_per_run_sd"].get<double>(), 10.0);
  // Failures over the runs that asked: 20 % and 0 %.
  EXPECT_DOUBLE_EQ(m2["failures_pct"].get<double>(), 10.0);
  EXPECT_NEAR(m2["failures_pct_sd"].get<double>(), std::sqrt(200.0), 1e-12);
  // 8 answers of 5 ± 1 ms and 20 of 2 ms: mean 80/28, sum of squares
  // 7 + 8 (5 - 80/28)^2 + 20 (2 - 80/28)^2 over 27.
  const double mean = 80.0 / 28;
  const double ss = 7 + 8 * (5 - mean) * (5 - mean) + 20 * (2 - mean) * (2 - mean);
  EXPECT_EQ(m2["answered"], 28.0);
  EXPECT_NEAR(m2["planning_ms"].get<double>(), mean, 1e-12);
  EXPECT_NEAR(m2["planning_ms_sd"].get<double>(), std::sqrt(ss / 27), 1e-12);
  EXPECT_EQ(t1["modes"]["M1"]["queries_per_run"], 0.0);
}

TEST(Summary, TableTwoAndTheSweepAgainstThePick) {
  const auto& t2 = summary()["table2"]["actions"];
  const auto& pick = t2["pick"];
  EXPECT_NEAR(pick["executions_per_run"].get<double>(), 4.0 / 3, 1e-12);
  EXPECT_DOUBLE_EQ(pick["plan_s"].get<double>(), 1.0);
  EXPECT_DOUBLE_EQ(pick["exec_s"].get<double>(), 9.0);
  EXPECT_DOUBLE_EQ(pick["boxes_per_s"].get<double>(), 0.1);  // over the runs that picked
  EXPECT_DOUBLE_EQ(pick["boxes_per_s_pooled"].get<double>(), 4.0 / 40);
  EXPECT_DOUBLE_EQ(t2["sweep"]["boxes_per_s_pooled"].get<double>(), 3.0 / 6);
  const auto& last = summary()["findings"].back();
  EXPECT_EQ(last["kind"], "actions");
  EXPECT_EQ(last["text"],
            "PLR runs: a sweep moves 0.500 boxes per robot-second, a pick 0.100 (1 sweeps, 4 picks "
            "in all): the sweep is faster");
  EXPECT_EQ(summary()["claims"].back()["holds"], true);
}

TEST(Summary, EveryRunIsIndexedAFailedOneWithItsError) {
  const auto& index = summary()["runs"];
  ASSERT_EQ(index.size(), testing::runs().size());
  EXPECT_EQ(index[1]["boxes_at_horizon"], 6.0);
  EXPECT_EQ(index[3]["stop_reason"], "timed out");
  EXPECT_EQ(index[3]["boxes_at_horizon"], 0.0);
  const auto& set = summary()["settings"];
  EXPECT_EQ(set["seeds"], 3);  // quick
  EXPECT_EQ(set["methods"], (nlohmann::json{"H", "PLR"}));
  EXPECT_EQ(summarize(testing::settings(), testing::runs(), false)["settings"]["seeds"], 10);
}

TEST(Summary, NnAgainstHComparesTheHalvesOfTheirUnloading) {
  // NN unloads 8 boxes by 60 s and none after; H 2 and then 6 more.
  EvaluationSettings s = testing::settings();
  s.methods = {Method::kHardcoded, Method::kNearest};
  const std::vector<nlohmann::json> runs = {testing::run("A1", "NN", 1, {{0, 0}, {30, 8}}),
                                            testing::run("A1", "H", 1, {{0, 0}, {50, 2}, {90, 8}})};
  const auto out = summarize(s, runs, false);
  const nlohmann::json* halves = nullptr;
  for (const auto& f : out["findings"])
    if (f.value("kind", "") == "halves") halves = &f;
  ASSERT_NE(halves, nullptr);
  EXPECT_EQ((*halves)["nn_first"], 8.0);
  EXPECT_EQ((*halves)["nn_second"], 0.0);
  EXPECT_EQ((*halves)["h_first"], 2.0);
  EXPECT_EQ((*halves)["h_second"], 6.0);
  bool degrades = false;
  for (const auto& c : out["claims"])
    if (c["claim"] == "NN degrades late on A1") degrades = c["holds"].get<bool>();
  EXPECT_TRUE(degrades);  // 0 % of NN's boxes late, 75 % of H's
}

// Below full fidelity, a seed's full-fidelity check stands beside its run
// and stays out of the method's figures.
TEST(Summary, AFullFidelityCheckIsReportedBesideItsRunNotAveragedIn) {
  EvaluationSettings s = testing::settings();
  s.fidelity = sim::Fidelity::kAdaptive;
  std::vector<nlohmann::json> runs = testing::runs();
  nlohmann::json check = testing::run("A1", "H", 1, {{0, 0}, {70, 9}});
  check["fidelity_check"] = true;
  check["ended"] = "cap";
  runs.push_back(check);
  const auto out = summarize(s, runs, false);
  // H on A1: the same three runs as without the check (10, 6 and 10 boxes).
  const auto& h = out["environments"]["A1"]["methods"]["H"];
  EXPECT_EQ(h["runs"], 3);
  EXPECT_NEAR(h["boxes_at_horizon"]["mean"].get<double>(), 26.0 / 3, 1e-12);
  const auto& c = out["fidelity_check"];
  EXPECT_EQ(c["level"], "adaptive");
  ASSERT_EQ(c["pairs"].size(), 1u) << c.dump(1);
  const auto& p = c["pairs"][0];
  EXPECT_EQ(p["seed"], 1);
  EXPECT_EQ(p["boxes_at_horizon"], 10.0);
  EXPECT_EQ(p["boxes_at_horizon_full"], 9.0);
  EXPECT_EQ(p["boxes_difference"], 1.0);
  EXPECT_EQ(p["robot_time_s_full"], 70.0);
  EXPECT_EQ(c["median_abs_boxes_difference"], 1.0);
  EXPECT_EQ(c["same_ending"], 0);
}

// The runs of an evaluation below full fidelity: every seed at its level,
// then the first fidelity_check_seeds seeds of each method again at full.
TEST(PlanRuns, BelowFullTheFirstSeedsRunAgainAtFull) {
  EvaluationSettings s = testing::settings();
  s.methods = {Method::kHardcoded, Method::kOpenLoop};  // open-loop: A1 (training) only
  const auto full = plan_runs(s, 3);
  EXPECT_EQ(full.size(), 9u);  // H on A1 and B1, open-loop on A1
  for (const auto& r : full) EXPECT_FALSE(r.full_check);

  s.fidelity = sim::Fidelity::kFast;
  s.fidelity_check_seeds = 2;
  const auto fast = plan_runs(s, 3);
  ASSERT_EQ(fast.size(), 9u + 6u);
  std::vector<std::string> checks;
  for (const auto& r : fast)
    if (r.full_check) checks.push_back(run_key(s, r));
  EXPECT_EQ(checks, (std::vector<std::string>{"A1_H_seed1_full", "A1_H_seed2_full",
                                              "A1_open-loop_seed1_full", "A1_open-loop_seed2_full",
                                              "B1_H_seed1_full", "B1_H_seed2_full"}));
}

}  // namespace
}  // namespace plr::evaluation
