// plr evaluate end to end on a tiny configuration: two environments of the
// small world (one a training world of a library made here, one held out),
// the five methods, 2 seeds, a short horizon. The plots must be valid SVG
// and PNG, the HTML tables must hold report.json's numbers, and a rerun
// must run only what is missing.
#include <expat.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <string>

#include <nlohmann/json.hpp>

#include "plr/actions/rig.hpp"
#include "plr/actions/run_stats.hpp"
#include "plr/chooser/features.hpp"
#include "plr/chooser/model.hpp"
#include "plr/chooser/nearest.hpp"
#include "plr/evaluation/run.hpp"
#include "plr/evaluation/summary.hpp"
#include "plr/jobs/store.hpp"
#include "plr/sim/generators.hpp"
#include "plr/sim/hardcoded_strategy.hpp"
#include "plr/sim/library.hpp"
#include "plr/sim/world_io.hpp"
#include "small_evaluation.hpp"

namespace fs = std::filesystem;

namespace {

std::string read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

int run(const std::string& command, std::string* output = nullptr) {
  FILE* pipe = ::popen((command + " 2>&1").c_str(), "r");
  std::string text;
  char buf[4096];
  while (std::fgets(buf, sizeof buf, pipe) != nullptr) text += buf;
  const int status = ::pclose(pipe);
  if (output) *output = text;
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

// A run's JSON as the result store under the report holds it.
nlohmann::json run_result(const fs::path& report, const std::string& key) {
  auto store = plr::jobs::Store::open(report / "runs");
  if (!store) return {};
  const auto r = store->load(key);
  if (!r || !r->ok) return {};
  return nlohmann::json::parse(plr::jobs::to_text(r->output));
}

// Each result file of the store and when it was written.
std::map<std::string, fs::file_time_type> result_files(const fs::path& report) {
  std::map<std::string, fs::file_time_type> out;
  for (const auto& f : fs::directory_iterator(report / "runs" / "results"))
    out[f.path().filename().string()] = f.last_write_time();
  return out;
}

bool well_formed_xml(const std::string& text) {
  XML_Parser p = XML_ParserCreate(nullptr);
  const bool ok = XML_Parse(p, text.data(), static_cast<int>(text.size()), 1) == XML_STATUS_OK;
  XML_ParserFree(p);
  return ok;
}

// The cells of the table row <tr data-row="key"> of table `id`.
std::vector<std::string> row(const std::string& html, const std::string& id,
                             const std::string& key) {
  const auto table = html.find("<table id=\"" + id + "\">");
  const auto end = html.find("</table>", table);
  const auto start = html.find("<tr data-row=\"" + key + "\">", table);
  if (table == std::string::npos || start == std::string::npos || start > end) return {};
  const std::string tr = html.substr(start, html.find("</tr>", start) - start);
  std::vector<std::string> cells;
  static const std::regex cell("<td[^>]*>([^<]*)</td>");
  for (std::sregex_iterator it(tr.begin(), tr.end(), cell), e; it != e; ++it)
    cells.push_back((*it)[1]);
  return cells;
}

// "12.3 ± 4.5" against mean and sd, to the digits shown.
void expect_pm(const std::string& cell, double mean, double sd, double digits_unit) {
  const auto pm = cell.find(" ± ");
  ASSERT_NE(pm, std::string::npos) << cell;
  EXPECT_NEAR(std::stod(cell.substr(0, pm)), mean, digits_unit / 2 + 1e-9) << cell;
  EXPECT_NEAR(std::stod(cell.substr(pm + 4)), sd, digits_unit / 2 + 1e-9) << cell;
}

class EvaluationTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("plr_evaluation_test_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    const std::string error = plr::evaluation_test::write_small_evaluation(
        dir_, "[H, NN, open-loop, expected-offline, PLR]");
    ASSERT_TRUE(error.empty()) << error;
  }
  void TearDown() override {
    if (!HasFailure()) fs::remove_all(dir_);
  }

  std::string evaluate(int expect_code = 0) {
    std::string out;
    const int code = run(std::string(PLR_EVALUATE) + " " + (dir_ / "evaluate.yaml").string() +
                             " --report " + (dir_ / "report").string(),
                         &out);
    EXPECT_EQ(code, expect_code) << out;
    return out;
  }

  fs::path dir_;
};

TEST_F(EvaluationTest, ReportHoldsPlotsAndTablesOfItsRuns) {
  evaluate();
  const fs::path report = dir_ / "report";
  // S: 5 methods x 2 seeds; T (held out): H, NN, PLR x 2 seeds.
  const auto files = result_files(report);
  EXPECT_EQ(files.size(), 16u);
  EXPECT_EQ(files.count("T_open-loop_seed1.result"), 0u);
  const auto j = nlohmann::json::parse(read(report / "report.json"));
  for (const char* env : {"S", "T"}) {
    const std::string svg = read(report / (std::string(env) + ".svg"));
    EXPECT_TRUE(well_formed_xml(svg)) << env;
    EXPECT_NE(svg.find("<svg"), std::string::npos);
    EXPECT_NE(svg.find("<polygon"), std::string::npos);  // the standard-error bands
    const std::string png = read(report / (std::string(env) + ".png"));
    ASSERT_GT(png.size(), 24u);
    EXPECT_EQ(png.substr(0, 8), std::string("\x89PNG\r\n\x1a\n", 8));
    EXPECT_EQ(png.substr(12, 4), "IHDR");
    for (const auto& [m, d] : j["environments"][env]["methods"].items()) {
      EXPECT_EQ(d["runs"].get<int>(), 2) << env << " " << m;
      EXPECT_EQ(d["failed"].get<int>(), 0) << env << " " << m;
      EXPECT_EQ(d["mean"].size(), static_cast<std::size_t>(plr::evaluation::kGridPoints));
    }
  }
  // Every run moved boxes within 60 s but H's (its first action on this wall).
  for (const auto& r : j["runs"])
    EXPECT_EQ(r["stop_reason"].get<std::string>().find("process"), std::string::npos);
  EXPECT_GT(j["environments"]["S"]["methods"]["H"]["boxes_at_horizon"]["mean"].get<double>(), 0);

  const std::string html = read(report / "report.html");
  EXPECT_TRUE(well_formed_xml(html.substr(html.find("<html>"))));
  const auto& t1 = j["table1"]["modes"];
  double queries = 0;
  for (const auto& [key, m] : t1.items()) queries += m["queries_per_run"].get<double>();
  EXPECT_GT(queries, 0);
  for (const auto& [key, m] : t1.items()) {
    const auto cells = row(html, "table1", key);
    ASSERT_EQ(cells.size(), 5u) << key;
    EXPECT_EQ(std::stoi(cells[1]), m["dof"].get<int>());
    expect_pm(cells[2], m["queries_per_run"], m["queries_per_run_sd"], 0.1);
    expect_pm(cells[3], m["planning_ms"], m["planning_ms_sd"], 0.1);
    expect_pm(cells[4], m["failures_pct"], m["failures_pct_sd"], 0.1);
  }
  for (const auto& [key, a] : j["table2"]["actions"].items()) {
    const auto cells = row(html, "table2", key);
    ASSERT_EQ(cells.size(), 5u) << key;
    expect_pm(cells[1], a["executions_per_run"], a["executions_per_run_sd"], 0.1);
    expect_pm(cells[2], a["plan_s"], a["plan_s_sd"], 0.01);
    expect_pm(cells[3], a["exec_s"], a["exec_s_sd"], 0.01);
    expect_pm(cells[4], a["boxes_per_s"], a["boxes_per_s_sd"], 0.001);
  }
  for (const auto& [env, e] : j["environments"].items())
    for (const auto& [m, d] : e["methods"].items()) {
      const auto cells = row(html, "methods", env + "/" + m);
      ASSERT_EQ(cells.size(), 7u) << env << "/" << m;
      EXPECT_EQ(std::stoi(cells[2]), d["runs"].get<int>());
      const auto& b = d["boxes_at_horizon"];
      expect_pm(cells[3], b["mean"], b["se"], 0.1);
    }
  EXPECT_FALSE(j["findings"].empty());
  EXPECT_FALSE(j["claims"].empty());
  // PLR against H carries its data: the share of library actions, as the
  // run files have it, and the same sentence in the HTML.
  for (const char* env : {"S", "T"}) {
    double library = 0, actions = 0;
    for (int seed : {1, 2}) {
      const auto run = run_result(report, std::string(env) + "_PLR_seed" + std::to_string(seed));
      for (const auto& step : run["steps"]) {
        actions += 1;
        library += step["source"].get<std::string>().rfind("library:", 0) == 0;
      }
    }
    ASSERT_GT(actions, 0) << env;
    const std::string claim = std::string("PLR >= H on ") + env;
    const auto c = std::find_if(j["claims"].begin(), j["claims"].end(),
                                [&](const auto& x) { return x["claim"] == claim; });
    ASSERT_NE(c, j["claims"].end()) << claim;
    EXPECT_NEAR((*c)["why"]["library_action_share"].get<double>(), library / actions, 1e-9);
    const auto cells = row(html, "claims", std::string("PLR &gt;= H on ") + env);
    ASSERT_EQ(cells.size(), 4u) << claim;
    EXPECT_EQ(cells[3], (*c)["why"]["text"].get<std::string>());
  }

  // Run again: nothing runs, no result file is written again, the report
  // is the same. Without one result, only that run, and it ends as before
  // (robot time is deterministic).
  const std::string report_json = read(report / "report.json");
  const std::string finished = evaluate();
  EXPECT_NE(finished.find("16 of 16 runs already"), std::string::npos) << finished;
  EXPECT_EQ(result_files(report), files);
  EXPECT_EQ(read(report / "report.json"), report_json);
  const auto before = run_result(report, "S_PLR_seed2");
  ASSERT_TRUE(before.is_object());
  fs::remove(report / "runs" / "results" / "S_PLR_seed2.result");
  const std::string again = evaluate();
  EXPECT_NE(again.find("15 of 16 runs already"), std::string::npos) << again;
  const auto after_files = result_files(report);
  for (const auto& [name, written] : files) {
    if (name == "S_PLR_seed2.result") continue;
    EXPECT_EQ(after_files.at(name), written) << name;
  }
  const auto after = run_result(report, "S_PLR_seed2");
  EXPECT_EQ(after["boxes_unloaded"], before["boxes_unloaded"]);
  EXPECT_DOUBLE_EQ(after["robot_time_s"].get<double>(), before["robot_time_s"].get<double>());

  // Each run says how it ended: a 30-box trailer is not emptied in 60 s.
  for (const auto& [name, written] : files) {
    const auto r = run_result(report, name.substr(0, name.size() - std::string(".result").size()));
    const bool cut = r["robot_time_s"].get<double>() >= 60;
    EXPECT_EQ(r["ended"], cut ? "cap" : "stuck") << name << ": " << r["stop_reason"];
  }
  // The same report folder with another cap is refused: its runs are not
  // those runs.
  std::string out;
  EXPECT_EQ(run(std::string(PLR_EVALUATE) + " " + (dir_ / "evaluate.yaml").string() + " --report " +
                    report.string() + " --set max_robot_time_s=30",
                &out),
            2);
  EXPECT_NE(out.find("made under other conditions (max_robot_time_s 60.0 there, 30.0 now)"),
            std::string::npos)
      << out;
  EXPECT_EQ(result_files(report).size(), files.size());
}

TEST_F(EvaluationTest, MissingModelIsOneLineNamingTheCommand) {
  fs::remove(dir_ / "model.plrm");
  const std::string out = evaluate(2);
  EXPECT_NE(out.find("model.plrm: no chooser model; train it with `plr chooser train"),
            std::string::npos)
      << out;
  EXPECT_EQ(std::count(out.begin(), out.end(), '\n'), 1) << out;
}

TEST(EvaluationSummary, MeanAndStandardErrorOfTheCurves) {
  plr::evaluation::EvaluationSettings s;
  s.environments.push_back({"E", plr::sim::EnvFamily::kB1, false, {}});
  s.methods = {plr::evaluation::Method::kHardcoded};
  s.max_robot_time_s = 100;
  auto result = [](int seed, nlohmann::json curve) {
    nlohmann::json modes = nlohmann::json::object();
    return nlohmann::json{
        {"environment", "E"},
        {"method", "H"},
        {"seed", seed},
        {"curve", curve},
        {"planner_modes", modes},
        {"action_stats",
         {{"pick", nlohmann::json::object()}, {"sweep", nlohmann::json::object()}}}};
  };
  // Boxes at 100 s: 10 and 20; at 50 s: 4 and 0. 90 % of 10 boxes at 90 s;
  // the second run never gets to 90 % of its 30.
  auto first = result(1, {{0, 0}, {40, 4}, {90, 10}}), second = result(2, {{0, 0}, {60, 20}});
  first["boxes_total"] = 10;
  second["boxes_total"] = 30;
  const auto j = plr::evaluation::summarize(s, {first, second}, false);
  const auto& h = j["environments"]["E"]["methods"]["H"];
  EXPECT_DOUBLE_EQ(h["boxes_at_horizon"]["mean"].get<double>(), 15.0);
  EXPECT_NEAR(h["boxes_at_horizon"]["se"].get<double>(), 5.0, 1e-12);
  EXPECT_DOUBLE_EQ(h["boxes_at_half"]["mean"].get<double>(), 2.0);
  EXPECT_DOUBLE_EQ(h["mean"].back().get<double>(), 15.0);
  EXPECT_DOUBLE_EQ(h["robot_s_to_90_percent"]["median"].get<double>(), 90.0);
  EXPECT_EQ(h["robot_s_to_90_percent"]["n"].get<int>(), 1);
  // A run file edited by hand: points that are not numbers are skipped.
  EXPECT_EQ(plr::actions::robot_time_to_share(
                nlohmann::json::parse(R"([[0, 0], ["x", 9], [7, 9]])"), 10, 0.9),
            7.0);
  EXPECT_DOUBLE_EQ(plr::evaluation::boxes_at(nlohmann::json::array({{0, 0}, {5, 3}}), 4.99), 0.0);
}

// PLR against H carries the split of PLR's actions between library
// strategies and H, and each part's boxes per robot-second.
TEST(EvaluationSummary, PlrAgainstHSaysHowItsActionsSplit) {
  plr::evaluation::EvaluationSettings s;
  s.environments.push_back({"E", plr::sim::EnvFamily::kB1, false, {}});
  s.methods = {plr::evaluation::Method::kHardcoded, plr::evaluation::Method::kPlr};
  s.max_robot_time_s = 100;
  auto result = [](const char* method, nlohmann::json steps) {
    return nlohmann::json{
        {"environment", "E"},
        {"method", method},
        {"seed", 1},
        {"curve", {{0, 0}, {20, 7}}},
        {"boxes_total", 10},
        {"steps", steps},
        {"planner_modes", nlohmann::json::object()},
        {"action_stats",
         {{"pick", nlohmann::json::object()}, {"sweep", nlohmann::json::object()}}}};
  };
  const auto plr = result("PLR", nlohmann::json::parse(R"([
        {"source": "library:B1-1", "boxes": 6, "robot_time_s": 10},
        {"source": "hardcoded", "boxes": 1, "robot_time_s": 10},
        {"source": 5, "boxes": 40, "robot_time_s": 1},
        {"source": "library:B1-1", "boxes": "x", "robot_time_s": 1}])"));
  const auto h = result("H", nlohmann::json::parse(R"([
        {"source": "hardcoded", "boxes": 2, "robot_time_s": 10}])"));
  const auto j = plr::evaluation::summarize(s, {h, plr}, false);
  const auto c = std::find_if(j["claims"].begin(), j["claims"].end(),
                              [](const auto& x) { return x["claim"] == "PLR > H on E at 600 s"; });
  ASSERT_NE(c, j["claims"].end()) << j["claims"].dump();
  const auto& why = (*c)["why"];
  EXPECT_DOUBLE_EQ(why["library_action_share"].get<double>(), 0.5);
  EXPECT_DOUBLE_EQ(why["library_boxes_per_s"].get<double>(), 0.6);
  EXPECT_DOUBLE_EQ(why["plr_hardcoded_boxes_per_s"].get<double>(), 0.1);
  EXPECT_DOUBLE_EQ(why["h_boxes_per_s"].get<double>(), 0.2);
  EXPECT_NE(why["text"].get<std::string>().find("50 %"), std::string::npos) << why["text"];
}

}  // namespace

// Open-loop runs the paper's sequence of precomputed strategies: where the
// training world's strategy ends, the continuation made for the leaf the run
// reached (by the observations it saw) goes on. The strategy here is one
// action; it has a continuation of one action at each of its 18 leaves, so
// whatever the first action shows, the run crosses into one.
TEST(EvaluationChain, OpenLoopFollowsTheContinuationOfTheLeafItReaches) {
  const fs::path dir =
      fs::temp_directory_path() / ("plr_evaluation_chain_" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  auto world = plr::sim::load_world(SMALL_WORLD);
  ASSERT_TRUE(world) << world.error().message;
  plr::sim::LibraryEntry root;
  root.name = "S-1";
  root.family = "A1";
  root.world_seed = 1;
  root.world = plr::sim::without_masses(*world);
  root.observation_json = "{}";
  root.provenance.seed = 1;
  root.provenance.particles = 2;
  root.strategy =
      plr::sim::single_action(plr::sim::hardcoded_action(plr::sim::analyse(root.world), {}), "S-1");
  plr::sim::Library library;
  library.entries.push_back(root);
  const plr::sim::Action next = plr::sim::make_sweep(plr::sim::Height::kHigh);
  for (int o = 0; o < plr::sim::kNumObservations; ++o) {
    plr::sim::LibraryEntry c = root;
    c.name = "S-1." + std::to_string(o);
    c.parent = "S-1";
    c.leaf = {static_cast<plr::sim::Observation>(o)};
    c.start = {{0, 1, 1}};
    c.strategy = plr::sim::single_action(next, c.name);
    library.entries.push_back(c);
  }
  ASSERT_TRUE(plr::sim::save_library(library, dir / "library.plrl"));

  plr::evaluation::EvaluationSettings settings;
  settings.library = dir / "library.plrl";
  settings.environments = {{"S", plr::sim::EnvFamily::kA1, true, {}}};
  settings.methods = {plr::evaluation::Method::kOpenLoop};
  settings.max_robot_time_s = 120;
  auto resources = plr::evaluation::load_resources(settings);
  ASSERT_TRUE(resources) << resources.error().message;
  plr::actions::ActionOptions options;
  options.observation = settings.observation;
  auto rig = plr::actions::Rig::create(options);
  ASSERT_TRUE(rig) << rig.error().message;
  // Seed 2 would be the second training world if continuations were
  // training worlds; they start mid-trailer, so S-1 is the only one.
  const nlohmann::json run = plr::evaluation::run_one(**rig, settings, *resources,
                                                      {0, plr::evaluation::Method::kOpenLoop, 2});
  ASSERT_FALSE(run.contains("error")) << run.dump();
  EXPECT_EQ(run["world"], "S-1, masses of seed 2");
  const auto& steps = run["steps"];
  ASSERT_EQ(steps.size(), 2u) << run.dump();
  EXPECT_EQ(steps[0]["link"], "S-1");
  // The observation seen before the second action is the leaf's.
  const auto seen = plr::sim::parse_observation(steps[1]["observation"].get<std::string>());
  ASSERT_TRUE(seen);
  EXPECT_EQ(steps[1]["link"], "S-1." + std::to_string(static_cast<int>(*seen)));
  EXPECT_EQ(steps[1]["action"], plr::sim::to_string(next));
  EXPECT_EQ(steps[1]["source"], "library:S-1");
  EXPECT_EQ(run["links_run"], 2);

  // Without its continuations, the run ends where the strategy does.
  library.entries.resize(1);
  ASSERT_TRUE(plr::sim::save_library(library, dir / "library.plrl"));
  auto alone = plr::evaluation::load_resources(settings);
  ASSERT_TRUE(alone) << alone.error().message;
  const nlohmann::json single =
      plr::evaluation::run_one(**rig, settings, *alone, {0, plr::evaluation::Method::kOpenLoop, 2});
  EXPECT_EQ(single["steps"].size(), 1u) << single.dump();
  fs::remove_all(dir);
}
