// Collision checker setup per planning query, three ways side by side:
//   fresh    a checker built per query on a new octree (what PlannerNode did
//            before: FCL octree object, occupied-voxel prefix sums, boxes,
//            robot shapes), built and destroyed;
//   shared   a checker built per query on the same octree: the trailer part
//            comes from the cache, boxes and robot shapes are built;
//   kept     one checker kept over the queries, given each query's world
//            with set_world (what PlannerNode does now).
// Worlds: generated A1 walls and B1 piles (plr::sim::generate_world); per
// scene, the executor's sequence of states (front box taken out, a third of
// the others settling by up to 4 mm), several queries per state. The three
// are interleaved query by query, so load on the machine hits them alike.
//   bench_collision [--quick] [--json] [--seed N]
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench_cli.hpp"
#include "plr/sim/collision.hpp"
#include "plr/sim/generators.hpp"
#include "plr/sim/octree.hpp"

using namespace plr::sim;

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const double idx = p * (v.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(idx)),
             hi = static_cast<std::size_t>(std::ceil(idx));
  return v[lo] + (idx - lo) * (v[hi] - v[lo]);
}

// The same octree under a new owner: the cache does not know it, as it did
// not know a request's freshly parsed octree before plan_messages kept one.
std::shared_ptr<const octomap::OcTree> new_owner(const std::shared_ptr<const octomap::OcTree>& t) {
  return {std::make_shared<std::shared_ptr<const octomap::OcTree>>(t), t.get()};
}

struct Row {
  std::vector<double> fresh, shared, kept, boxes;
  std::uint64_t fresh_builds = 0, shared_builds = 0, kept_builds = 0;
};

}  // namespace

int main(int argc, char** argv) {
  bool quick = false, json = false;
  std::uint64_t seed = 1;
  CLI::App app{"Collision checker setup per planning query: fresh, shared octree, kept"};
  plr::bench::add_quick_flag(app, quick, "2 walls and 1 pile, 8 states each");
  plr::bench::add_json_flag(app, json);
  app.add_option("--seed", seed, "Random seed (worlds, settling, queries)")->capture_default_str();
  plr::bench::parse_or_exit(app, argc, argv);
  const RobotModel robot = load_robot().value();
  const int walls = quick ? 2 : 6, piles = quick ? 1 : 3, states = quick ? 8 : 20,
            queries_per_state = 3;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);

  std::map<std::string, Row> rows;
  for (int i = 0; i < walls + piles; ++i) {
    const bool wall = i < walls;
    World w = generate_world(wall ? EnvFamily::kA1 : EnvFamily::kB1, seed * 100 + i);
    const std::shared_ptr<const octomap::OcTree> tree = build_trailer_octree(w.trailer);
    Row& row = rows[wall ? "A1" : "B1"];
    CollisionChecker kept(robot, w, tree);
    for (int s = 0; s < states && !w.boxes.empty(); ++s) {
      w.boxes.erase(
          std::min_element(w.boxes.begin(), w.boxes.end(), [](const Box& a, const Box& b) {
            return a.pose.translation().x() < b.pose.translation().x();
          }));
      for (Box& b : w.boxes)
        if (u(rng) < 0.3) b.pose.translation().z() -= 0.004 * u(rng);
      for (int q = 0; q < queries_per_state; ++q) {
        row.boxes.push_back(static_cast<double>(w.boxes.size()));
        const auto other_owner = new_owner(tree);
        std::uint64_t n = CollisionChecker::trailer_builds();
        Clock::time_point t0 = Clock::now();
        { const CollisionChecker fresh(robot, w, other_owner); }
        row.fresh.push_back(ms_since(t0));
        row.fresh_builds += CollisionChecker::trailer_builds() - n;

        n = CollisionChecker::trailer_builds();
        t0 = Clock::now();
        { const CollisionChecker shared(robot, w, tree); }
        row.shared.push_back(ms_since(t0));
        row.shared_builds += CollisionChecker::trailer_builds() - n;

        n = CollisionChecker::trailer_builds();
        t0 = Clock::now();
        kept.set_world(w, tree);
        row.kept.push_back(ms_since(t0));
        row.kept_builds += CollisionChecker::trailer_builds() - n;
      }
    }
  }
  Row& all = rows["all"];
  for (const auto& [name, r] : rows) {
    if (name == "all") continue;
    for (auto [from, to] : {std::pair{&r.fresh, &all.fresh}, std::pair{&r.shared, &all.shared},
                            std::pair{&r.kept, &all.kept}, std::pair{&r.boxes, &all.boxes}})
      to->insert(to->end(), from->begin(), from->end());
    all.fresh_builds += r.fresh_builds;
    all.shared_builds += r.shared_builds;
    all.kept_builds += r.kept_builds;
  }

  nlohmann::json out = nlohmann::json::array();
  if (!json) {
    std::printf("collision checker setup per query, ms (median / p95); seed %llu%s\n",
                static_cast<unsigned long long>(seed), quick ? ", quick" : "");
    std::printf("%-6s %7s %6s %17s %17s %17s %12s %12s\n", "worlds", "queries", "boxes", "fresh",
                "shared trailer", "kept+set_world", "fresh/kept", "builds f/s/k");
  }
  for (const auto& [name, r] : rows) {
    const double fm = percentile(r.fresh, 0.5), sm = percentile(r.shared, 0.5),
                 km = percentile(r.kept, 0.5);
    if (json) {
      out.push_back(
          {{"worlds", name},
           {"queries", r.fresh.size()},
           {"boxes_median", percentile(r.boxes, 0.5)},
           {"fresh_ms", {{"median", fm}, {"p95", percentile(r.fresh, 0.95)}}},
           {"shared_ms", {{"median", sm}, {"p95", percentile(r.shared, 0.95)}}},
           {"kept_ms", {{"median", km}, {"p95", percentile(r.kept, 0.95)}}},
           {"fresh_over_kept", fm / km},
           {"fresh_over_shared", fm / sm},
           {"trailer_builds",
            {{"fresh", r.fresh_builds}, {"shared", r.shared_builds}, {"kept", r.kept_builds}}}});
    } else {
      std::printf(
          "%-6s %7zu %6.0f %8.3f / %6.3f %8.3f / %6.3f %8.3f / %6.3f %11.0fx %4llu/%llu/%llu\n",
          name.c_str(), r.fresh.size(), percentile(r.boxes, 0.5), fm, percentile(r.fresh, 0.95), sm,
          percentile(r.shared, 0.95), km, percentile(r.kept, 0.95), fm / km,
          static_cast<unsigned long long>(r.fresh_builds),
          static_cast<unsigned long long>(r.shared_builds),
          static_cast<unsigned long long>(r.kept_builds));
    }
  }
  if (json) std::printf("%s\n", nlohmann::json{{"rows", out}}.dump().c_str());
  return 0;
}
