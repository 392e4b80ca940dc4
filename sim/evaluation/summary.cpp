#include "plr/evaluation/summary.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <map>

#include "plr/actions/run_stats.hpp"

namespace plr::evaluation {

namespace {

struct MeanSd {
  double mean = 0, sd = 0, se = 0;
  std::size_t n = 0;
};

MeanSd mean_sd(const std::vector<double>& v) {
  MeanSd m;
  m.n = v.size();
  if (v.empty()) return m;
  for (double x : v) m.mean += x;
  m.mean /= static_cast<double>(v.size());
  if (v.size() > 1) {
    double ss = 0;
    for (double x : v) ss += (x - m.mean) * (x - m.mean);
    m.sd = std::sqrt(ss / static_cast<double>(v.size() - 1));
    m.se = m.sd / std::sqrt(static_cast<double>(v.size()));
  }
  return m;
}

nlohmann::json to_json(const MeanSd& m) {
  return {{"mean", m.mean}, {"sd", m.sd}, {"se", m.se}, {"n", m.n}};
}

// Pools groups given as (n, mean, sd) into the mean and sd of all samples.
struct Pool {
  double n = 0, mean = 0, m2 = 0;
  void add(double gn, double gmean, double gsd) {
    if (gn <= 0) return;
    const double total = n + gn;
    const double d = gmean - mean;
    m2 += gsd * gsd * (gn - 1) + d * d * n * gn / total;
    mean += d * gn / total;
    n = total;
  }
  double sd() const { return n > 1 ? std::sqrt(m2 / (n - 1)) : 0.0; }
};

// run[a][b], or an empty object where the run's file lacks it.
const nlohmann::json& field(const nlohmann::json& run, const char* a, const std::string& b) {
  static const nlohmann::json kEmpty = nlohmann::json::object();
  if (!run.contains(a) || !run[a].is_object() || !run[a].contains(b) || !run[a][b].is_object())
    return kEmpty;
  return run[a][b];
}

bool ok(const nlohmann::json& run) {
  return !run.contains("error") && run.contains("curve") && run["curve"].is_array();
}

bool fidelity_check(const nlohmann::json& run) {
  return run.value("fidelity_check", false);
}

// Standard errors between two means: the difference over its standard error.
double z_score(const nlohmann::json& a, const nlohmann::json& b) {
  const double se = std::hypot(a["se"].get<double>(), b["se"].get<double>());
  const double d = a["mean"].get<double>() - b["mean"].get<double>();
  if (se > 0) return d / se;
  return d == 0 ? 0.0 : std::copysign(INFINITY, d);
}

// A z for report.json, which holds no infinity: one side has no spread.
double reported(double z) {
  return std::isfinite(z) ? z : (z > 0 ? 1e9 : -1e9);
}

std::string compare_words(double z) {
  if (z >= 2) return "ahead";
  if (z <= -2) return "behind";
  return "level (within 2 standard errors)";
}

// The method Table I and II are computed from: PLR, the paper's; else the
// first method run.
Method table_method(const EvaluationSettings& s) {
  for (Method m : s.methods)
    if (m == Method::kPlr) return m;
  return s.methods.front();
}

nlohmann::json table1(const std::vector<const nlohmann::json*>& runs) {
  nlohmann::json modes = nlohmann::json::object();
  for (int m = 1; m <= 6; ++m) {
    const std::string key = "M" + std::to_string(m);
    std::vector<double> queries, failures_pct;
    Pool ms;
    std::string name;
    for (const nlohmann::json* r : runs) {
      const auto& mode = field(*r, "planner_modes", key);
      name = mode.value("name", key);
      const double q = mode.value("queries", 0.0);
      queries.push_back(q);
      if (q > 0) failures_pct.push_back(100.0 * mode.value("failures", 0.0) / q);
      ms.add(mode.value("ms_samples", 0.0), mode.value("mean_ms", 0.0), mode.value("sd_ms", 0.0));
    }
    const MeanSd q = mean_sd(queries), f = mean_sd(failures_pct);
    modes[key] = {{"name", name},
                  {"dof", actions::plan_mode_dof(m)},
                  {"queries_per_run", q.mean},
                  {"queries_per_run_sd", q.sd},
                  {"planning_ms", ms.mean},
                  {"planning_ms_sd", ms.sd()},
                  {"answered", ms.n},
                  {"failures_pct", f.mean},
                  {"failures_pct_sd", f.sd}};
  }
  return modes;
}

nlohmann::json table2(const std::vector<const nlohmann::json*>& runs) {
  nlohmann::json out = nlohmann::json::object();
  for (const char* kind : {"pick", "sweep"}) {
    std::vector<double> executions, rates;
    Pool plan, exec;
    double boxes = 0, seconds = 0;
    for (const nlohmann::json* r : runs) {
      const auto& a = field(*r, "action_stats", kind);
      const double n = a.value("executions", 0.0);
      executions.push_back(n);
      if (n > 0) rates.push_back(a.value("boxes_per_s", 0.0));
      plan.add(n, a.value("plan_s", 0.0), a.value("plan_s_sd", 0.0));
      exec.add(n, a.value("exec_s", 0.0), a.value("exec_s_sd", 0.0));
      boxes += a.value("boxes", 0.0);
      seconds += n * (a.value("plan_s", 0.0) + a.value("exec_s", 0.0));
    }
    const MeanSd e = mean_sd(executions), rate = mean_sd(rates);
    out[kind] = {{"executions_per_run", e.mean},
                 {"executions_per_run_sd", e.sd},
                 {"plan_s", plan.mean},
                 {"plan_s_sd", plan.sd()},
                 {"exec_s", exec.mean},
                 {"exec_s_sd", exec.sd()},
                 {"boxes_per_s", rate.mean},
                 {"boxes_per_s_sd", rate.sd},
                 {"boxes", boxes},
                 {"boxes_per_s_pooled", seconds > 0 ? boxes / seconds : 0.0}};
  }
  return out;
}

// How PLR's actions split between library strategies and H, and what each
// unloaded per robot-second, over a method's runs: the data behind a PLR
// that is only level with H (it can beat H only where it runs library
// strategies, and only by as much as they beat H's actions).
struct SourceSplit {
  double library_actions = 0, actions = 0;
  double library_boxes = 0, library_s = 0, hardcoded_boxes = 0, hardcoded_s = 0;
};

SourceSplit source_split(const std::vector<const nlohmann::json*>& runs) {
  SourceSplit out;
  for (const nlohmann::json* r : runs) {
    if (!r->contains("steps") || !(*r)["steps"].is_array()) continue;
    for (const auto& step : (*r)["steps"]) {
      // A run file edited by hand may hold anything: such a step counts as
      // nothing.
      if (!step.is_object() || !step.contains("source") || !step["source"].is_string() ||
          !step.contains("boxes") || !step["boxes"].is_number() || !step.contains("robot_time_s") ||
          !step["robot_time_s"].is_number())
        continue;
      const bool library = step["source"].get<std::string>().rfind("library:", 0) == 0;
      const double boxes = step["boxes"].get<double>();
      const double seconds = step["robot_time_s"].get<double>();
      out.actions += 1;
      if (library) {
        out.library_actions += 1;
        out.library_boxes += boxes;
        out.library_s += seconds;
      } else {
        out.hardcoded_boxes += boxes;
        out.hardcoded_s += seconds;
      }
    }
  }
  return out;
}

double rate(double boxes, double seconds) {
  return seconds > 0 ? boxes / seconds : 0.0;
}

nlohmann::json explain_plr(const SourceSplit& plr, const SourceSplit& h) {
  const double share = plr.actions > 0 ? plr.library_actions / plr.actions : 0.0;
  const double lib = rate(plr.library_boxes, plr.library_s);
  const double own = rate(plr.hardcoded_boxes, plr.hardcoded_s);
  const double hr = rate(h.hardcoded_boxes + h.library_boxes, h.hardcoded_s + h.library_s);
  return {{"library_action_share", share},
          {"library_boxes_per_s", lib},
          {"plr_hardcoded_boxes_per_s", own},
          {"h_boxes_per_s", hr},
          {"text", fmt::format("PLR ran library strategies for {:.0f} % of its actions, which "
                               "unloaded {:.3f} boxes per robot-second, and H for the rest "
                               "({:.3f}); H's own runs unloaded {:.3f}",
                               100 * share, lib, own, hr)}};
}

// Robot seconds by which a run had unloaded `share` of its boxes; a run
// that never got there counts as the horizon (a lower bound: the run was
// cut there or stopped unable to go on), and `reached` says how many did.
nlohmann::json time_to_share(const std::vector<const nlohmann::json*>& runs, double share,
                             double horizon) {
  std::vector<double> t;
  std::size_t reached = 0;
  for (const auto* r : runs) {
    const auto at =
        actions::robot_time_to_share((*r)["curve"], r->value("boxes_total", 0.0), share);
    if (at && *at <= horizon) ++reached;
    t.push_back(at ? std::min(*at, horizon) : horizon);
  }
  nlohmann::json out = to_json(mean_sd(t));
  out["reached"] = reached;
  return out;
}

// The checkpoints the whole-trailer figures are read at (robot seconds).
constexpr double kCheckpoints[] = {300, 600, 1200};

}  // namespace

double boxes_at(const nlohmann::json& curve, double t) {
  double boxes = 0;
  for (const auto& p : curve) {
    if (p[0].get<double>() > t) break;
    boxes = p[1].get<double>();
  }
  return boxes;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t h = v.size() / 2;
  return v.size() % 2 ? v[h] : (v[h - 1] + v[h]) / 2;
}

namespace {

// Each full-fidelity check beside the same run at the evaluation's level:
// boxes by the horizon, robot time, how it ended, and their differences.
nlohmann::json fidelity_checks(const EvaluationSettings& s, const std::vector<nlohmann::json>& runs,
                               double horizon) {
  nlohmann::json pairs = nlohmann::json::array();
  std::vector<double> box_diffs;
  std::size_t same_ending = 0;
  for (const auto& full : runs) {
    if (!fidelity_check(full) || !ok(full)) continue;
    const auto level = std::find_if(runs.begin(), runs.end(), [&](const nlohmann::json& r) {
      return !fidelity_check(r) && ok(r) && r.value("environment", "") == full["environment"] &&
             r.value("method", "") == full["method"] && r.value("seed", 0) == full["seed"];
    });
    if (level == runs.end()) continue;
    const double at_level = boxes_at((*level)["curve"], horizon);
    const double at_full = boxes_at(full["curve"], horizon);
    box_diffs.push_back(std::abs(at_level - at_full));
    same_ending += level->value("ended", "") == full.value("ended", "");
    pairs.push_back({{"environment", full["environment"]},
                     {"method", full["method"]},
                     {"seed", full["seed"]},
                     {"boxes_at_horizon", at_level},
                     {"boxes_at_horizon_full", at_full},
                     {"boxes_difference", at_level - at_full},
                     {"robot_time_s", level->value("robot_time_s", 0.0)},
                     {"robot_time_s_full", full.value("robot_time_s", 0.0)},
                     {"ended", level->value("ended", "")},
                     {"ended_full", full.value("ended", "")},
                     {"wall_s", level->value("wall_s", 0.0)},
                     {"wall_s_full", full.value("wall_s", 0.0)}});
  }
  return {{"level", sim::to_string(s.fidelity)},
          {"pairs", pairs},
          {"median_abs_boxes_difference", median(box_diffs)},
          {"max_abs_boxes_difference",
           box_diffs.empty() ? 0.0 : *std::max_element(box_diffs.begin(), box_diffs.end())},
          {"same_ending", same_ending}};
}

}  // namespace

nlohmann::json summarize(const EvaluationSettings& s, const std::vector<nlohmann::json>& runs,
                         bool quick) {
  const double horizon = s.max_robot_time_s;
  std::vector<double> grid;
  for (int i = 0; i < kGridPoints; ++i) grid.push_back(horizon * i / (kGridPoints - 1));

  nlohmann::json envs = nlohmann::json::object();
  nlohmann::json findings = nlohmann::json::array();
  nlohmann::json claims = nlohmann::json::array();
  for (const Environment& env : s.environments) {
    nlohmann::json methods = nlohmann::json::object();
    std::map<std::string, std::vector<const nlohmann::json*>> runs_of;
    for (const Method m : s.methods) {
      std::vector<const nlohmann::json*> mine;
      std::size_t failed = 0;
      std::map<std::string, int> stops;
      for (const auto& r : runs) {
        if (r.value("environment", "") != env.name || r.value("method", "") != to_string(m) ||
            fidelity_check(r))
          continue;
        if (!ok(r)) {
          ++failed;
          ++stops[r.value("error", r.value("stop_reason", "failed"))];
          continue;
        }
        mine.push_back(&r);
        ++stops[r.value("stop_reason", "?")];
      }
      if (mine.empty() && failed == 0) continue;
      runs_of[to_string(m)] = mine;
      nlohmann::json mean = nlohmann::json::array(), se = nlohmann::json::array();
      for (double t : grid) {
        std::vector<double> v;
        for (const auto* r : mine) v.push_back(boxes_at((*r)["curve"], t));
        const MeanSd ms = mean_sd(v);
        mean.push_back(ms.mean);
        se.push_back(ms.se);
      }
      std::vector<double> at_end, at_half, totals, walls, library_share, to_90;
      for (const auto* r : mine) {
        if (const auto t =
                actions::robot_time_to_share((*r)["curve"], r->value("boxes_total", 0.0), 0.9))
          to_90.push_back(*t);
        at_end.push_back(boxes_at((*r)["curve"], horizon));
        at_half.push_back(boxes_at((*r)["curve"], horizon / 2));
        totals.push_back(r->value("boxes_total", 0.0));
        walls.push_back(r->value("wall_s", 0.0));
        const double actions = r->value("actions", 0.0);
        if (actions > 0) library_share.push_back(r->value("library_actions", 0.0) / actions);
      }
      nlohmann::json to_share = nlohmann::json::object(), at_checkpoints = nlohmann::json::object();
      for (const double share : {0.5, 0.9, 1.0})
        to_share[fmt::format("{:g}", 100 * share)] = time_to_share(mine, share, horizon);
      for (const double t : kCheckpoints) {
        std::vector<double> v;
        for (const auto* r : mine) v.push_back(boxes_at((*r)["curve"], t));
        at_checkpoints[fmt::format("{:g}", t)] = to_json(mean_sd(v));
      }
      methods[to_string(m)] = {
          {"runs", mine.size()},
          {"failed", failed},
          {"mean", mean},
          {"se", se},
          {"boxes_at_horizon", to_json(mean_sd(at_end))},
          {"boxes_at_half", to_json(mean_sd(at_half))},
          {"boxes_total", to_json(mean_sd(totals))},
          // Over the runs that got there (`n` of `runs`).
          {"robot_s_to_90_percent",
           {{"median", median(to_90)}, {"mean", mean_sd(to_90).mean}, {"n", to_90.size()}}},
          {"library_action_share", to_json(mean_sd(library_share))},
          // Whole-trailer figures: a run cut at the horizon counts the
          // horizon as its time (`reached` says how many got there); boxes
          // at a checkpoint past the horizon are those at the horizon.
          {"time_to_empty_s", to_share["100"]},
          {"time_to_share_s", to_share},
          {"boxes_at", at_checkpoints},
          {"wall_s", to_json(mean_sd(walls))},
          {"stop_reasons", stops}};
    }
    // Findings: each method against H at the horizon, PLR against NN, and
    // how NN's and H's unloading split between the two halves.
    auto has = [&](const char* m) {
      return methods.contains(m) && methods[m]["runs"].get<std::size_t>() > 0;
    };
    auto at = [&](const char* m) -> const nlohmann::json& {
      return methods[m]["boxes_at_horizon"];
    };
    auto line = [&](const char* a, const char* b) {
      const double z = z_score(at(a), at(b));
      const double d = at(a)["mean"].get<double>() - at(b)["mean"].get<double>();
      findings.push_back(
          {{"environment", env.name},
           {"kind", "versus"},
           {"a", a},
           {"b", b},
           {"difference", d},
           {"z", reported(z)},
           {"text",
            fmt::format("{}: {} unloads {:.1f} ± {:.1f} boxes by {:g} s, {} {:.1f} ± {:.1f}: "
                        "{} by {:+.1f} boxes ({:+.1f} standard errors)",
                        env.name, a, at(a)["mean"].get<double>(), at(a)["se"].get<double>(),
                        horizon, b, at(b)["mean"].get<double>(), at(b)["se"].get<double>(),
                        compare_words(z), d, std::isfinite(z) ? z : 0.0)}});
      return z;
    };
    if (has("H")) {
      for (const char* m : {"PLR", "NN", "open-loop", "expected-offline"})
        if (has(m)) {
          line(m, "H");
          if (std::string(m) == "PLR") {
            const nlohmann::json why =
                explain_plr(source_split(runs_of[m]), source_split(runs_of["H"]));
            // PLR is at least H's equal when it is never behind by more than
            // one standard error, at any time of the run: z is the worst.
            const auto& plr = methods["PLR"];
            const auto& h = methods["H"];
            double worst = INFINITY, worst_t = 0;
            for (std::size_t i = 0; i < grid.size(); ++i) {
              const double zi = z_score({{"mean", plr["mean"][i]}, {"se", plr["se"][i]}},
                                        {{"mean", h["mean"][i]}, {"se", h["se"][i]}});
              if (zi < worst) {
                worst = zi;
                worst_t = grid[i];
              }
            }
            claims.push_back({{"claim", fmt::format("PLR >= H on {}", env.name)},
                              {"holds", worst >= -1},
                              {"z", reported(worst)},
                              {"at_s", worst_t},
                              {"why", why}});
            const double z600 = z_score(plr["boxes_at"]["600"], h["boxes_at"]["600"]);
            claims.push_back({{"claim", fmt::format("PLR > H on {} at 600 s", env.name)},
                              {"holds", z600 >= 2},
                              {"z", reported(z600)},
                              {"why", why}});
          }
        }
    }
    if (has("PLR") && has("NN")) line("PLR", "NN");
    if (has("open-loop") && has("expected-offline")) line("open-loop", "expected-offline");
    if (has("open-loop") && has("PLR")) {
      const double z = line("open-loop", "PLR");
      claims.push_back({{"claim", fmt::format("open-loop poor on {} (behind PLR)", env.name)},
                        {"holds", z <= -2},
                        {"z", std::isfinite(z) ? z : 0.0}});
    }
    if (has("NN") && has("H")) {
      auto halves = [&](const char* m) {
        const double half = methods[m]["boxes_at_half"]["mean"].get<double>();
        const double end = at(m)["mean"].get<double>();
        return std::pair{half, end - half};
      };
      const auto [nn1, nn2] = halves("NN");
      const auto [h1, h2] = halves("H");
      // Late degradation: NN's share of its boxes in the second half below H's.
      const double nn_late = nn1 + nn2 > 0 ? nn2 / (nn1 + nn2) : 0.0;
      const double h_late = h1 + h2 > 0 ? h2 / (h1 + h2) : 0.0;
      const bool degrades = nn_late < h_late;
      findings.push_back(
          {{"environment", env.name},
           {"kind", "halves"},
           {"nn_first", nn1},
           {"nn_second", nn2},
           {"h_first", h1},
           {"h_second", h2},
           {"text",
            fmt::format(
                "{}: NN unloads {:.1f} boxes in the first {:g} s and {:.1f} in the "
                "second ({:.0f} % late), H {:.1f} and {:.1f} ({:.0f} % late): NN {}",
                env.name, nn1, horizon / 2, nn2, 100 * nn_late, h1, h2, 100 * h_late,
                degrades ? "slows down later than H does" : "does not slow down more than H")}});
      claims.push_back({{"claim", fmt::format("NN degrades late on {}", env.name)},
                        {"holds", degrades},
                        {"z", 0.0}});
    }
    envs[env.name] = {{"training", env.training},
                      {"family", std::string(sim::to_string(env.family))},
                      {"methods", methods},
                      {"plot_svg", env.name + ".svg"},
                      {"plot_png", env.name + ".png"}};
  }

  const Method tm = table_method(s);
  std::vector<const nlohmann::json*> table_runs;
  for (const auto& r : runs)
    if (ok(r) && !fidelity_check(r) && r.value("method", "") == to_string(tm))
      table_runs.push_back(&r);
  const nlohmann::json t2 = table2(table_runs);
  {
    const double pick = t2["pick"]["boxes_per_s_pooled"].get<double>();
    const double sweep = t2["sweep"]["boxes_per_s_pooled"].get<double>();
    const bool faster = sweep > pick;
    findings.push_back(
        {{"kind", "actions"},
         {"text", fmt::format("{} runs: a sweep moves {:.3f} boxes per robot-second, a pick {:.3f}"
                              " ({} sweeps, {} picks in all): the sweep is {}",
                              to_string(tm), sweep, pick,
                              t2["sweep"]["executions_per_run"].get<double>() * table_runs.size(),
                              t2["pick"]["executions_per_run"].get<double>() * table_runs.size(),
                              faster ? "faster" : "not faster")}});
    claims.push_back(
        {{"claim", "a sweep moves boxes faster than a pick"}, {"holds", faster}, {"z", 0.0}});
  }

  nlohmann::json index = nlohmann::json::array();
  for (const auto& r : runs) {
    index.push_back({{"environment", r.value("environment", "")},
                     {"method", r.value("method", "")},
                     {"seed", r.value("seed", 0)},
                     {"world", r.value("world", "")},
                     {"boxes_total", r.value("boxes_total", 0)},
                     {"boxes_unloaded", r.value("boxes_unloaded", 0)},
                     {"boxes_at_horizon", ok(r) ? boxes_at(r["curve"], horizon) : 0.0},
                     {"robot_time_s", r.value("robot_time_s", 0.0)},
                     {"actions", r.value("actions", 0)},
                     {"stop_reason", r.value("error", r.value("stop_reason", ""))},
                     {"fidelity", r.value("fidelity", "full")},
                     {"fidelity_check", fidelity_check(r)},
                     {"wall_s", r.value("wall_s", 0.0)}});
  }
  nlohmann::json env_names = nlohmann::json::array(), method_names = nlohmann::json::array();
  for (const auto& e : s.environments) env_names.push_back(e.name);
  for (const auto m : s.methods) method_names.push_back(to_string(m));
  return {{"settings",
           {{"library", s.library.string()},
            {"model", s.model.string()},
            {"environments", env_names},
            {"methods", method_names},
            {"first_seed", s.first_seed},
            {"seeds", quick ? s.quick_seeds : s.seeds},
            {"quick", quick},
            {"max_robot_time_s", horizon},
            {"max_actions", s.max_actions},
            {"fidelity", sim::to_string(s.fidelity)}}},
          {"fidelity_check", fidelity_checks(s, runs, horizon)},
          {"grid_s", grid},
          {"environments", envs},
          {"table1",
           {{"method", to_string(tm)}, {"runs", table_runs.size()}, {"modes", table1(table_runs)}}},
          {"table2", {{"method", to_string(tm)}, {"runs", table_runs.size()}, {"actions", t2}}},
          {"findings", findings},
          {"claims", claims},
          {"runs", index}};
}

}  // namespace plr::evaluation
