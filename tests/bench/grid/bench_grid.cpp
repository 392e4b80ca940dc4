// Runs the search core on a Moving AI grid benchmark and compares path
// lengths with the published optima.
//   bench_grid MAP SCEN [--json] [--weight W]
#include <chrono>
#include <cmath>
#include <cstdio>
#include <exception>
#include <string>

#include <nlohmann/json.hpp>

#include "plr/search/arastar.hpp"
#include "plr/search/grid.hpp"

#include "bench_cli.hpp"

int main(int argc, char** argv) {
  std::string map_path, scen_path;
  bool json = false;
  double weight = 1.0;
  CLI::App app{"The search core on a Moving AI grid benchmark, against the published optima"};
  app.add_option("map", map_path, "Moving AI map (.map)")->required()->check(CLI::ExistingFile);
  app.add_option("scen", scen_path, "Its scenario (.scen)")->required()->check(CLI::ExistingFile);
  plr::bench::add_json_flag(app, json);
  app.add_option("--weight", weight, "ARA* heuristic weight (1: optimal)")
      ->check(CLI::Range(1.0, 1e9))
      ->capture_default_str();
  plr::bench::parse_or_exit(app, argc, argv);
  try {
    const auto map = plr::search::load_grid_map(map_path);
    const auto queries = plr::search::load_scenario(scen_path);
    plr::search::GridGraph graph(map);
    plr::search::OctileHeuristic h(map);
    plr::search::AraStar search;
    plr::search::SearchOptions opt;
    opt.eps_initial = opt.eps_final = weight;
    std::size_t solved = 0, mismatches = 0, expansions = 0;
    double worst_ratio = 1.0;
    const auto t0 = std::chrono::steady_clock::now();
    for (const auto& q : queries) {
      graph.set_goal(q.goal_x, q.goal_y);
      h.set_goal(q.goal_x, q.goal_y);
      const auto r = search.search(graph, h, graph.id(q.start_x, q.start_y), opt);
      expansions += r.expansions;
      if (r.status != plr::search::SearchStatus::kSolved) continue;
      ++solved;
      if (std::abs(r.cost - q.optimal) > 0.01) ++mismatches;
      if (q.optimal > 0) worst_ratio = std::max(worst_ratio, r.cost / q.optimal);
    }
    const double secs =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (json) {
      nlohmann::json j{{"map", map_path},
                       {"scenario", scen_path},
                       {"weight", weight},
                       {"queries", queries.size()},
                       {"solved", solved},
                       {"mismatches", mismatches},
                       {"worst_cost_ratio", worst_ratio},
                       {"expansions", expansions},
                       {"time_s", secs}};
      std::printf("%s\n", j.dump().c_str());
    } else {
      std::printf("map %s (%dx%d), weight %.2f\n", map_path.c_str(), map.width, map.height, weight);
      std::printf("queries %zu, solved %zu, mismatches vs published optimum (tol 0.01) %zu\n",
                  queries.size(), solved, mismatches);
      std::printf("worst cost / optimum %.4f, expansions %zu, time %.3f s (%.3f ms/query)\n",
                  worst_ratio, expansions, secs,
                  queries.empty() ? 0.0 : 1e3 * secs / queries.size());
    }
    return solved == queries.size() && (weight > 1.0 || mismatches == 0) ? 0 : 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_grid: %s\n", e.what());
    return 2;
  }
}
