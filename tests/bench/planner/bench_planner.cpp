// Planner benchmark: seeded queries per mode, drawn from what the strategy
// executor asks for during Pick and Sweep actions on generated walls (A1) and
// piles (B1); ARA* lattice planner and RRTConnect side by side.
//   bench_planner [--quick] [--json] [--seed N] [--mode 1-6] [--budget N]
//                 [--primitives FILE] [--failing FILE] [--recurring FILE]... [--verbose]
// --budget sets every query's max_expansions (deterministic planning);
// --primitives another lattice file than the shipped one. --failing: a
// query set (plr/planning/query_set.hpp) of queries that spent their whole
// budget in bench_unload runs (default: the recorded one,
// tests/bench/planner/data); infeasible_refused_share is the share of them
// the ARA* planner refuses within 100 expansions (judged unsolvable, not
// out of budget). --recurring: query sets of one trailer's M1 and M2
// queries each, in the order a bench_unload run asked them (default: the
// recorded ones); each is answered in order by a planner that keeps its
// experience through the trailer and by one that plans every query from
// scratch. On the recurring queries (those asked once the mode has
// experience) experience_speedup is the median CPU time of a query from
// scratch over the median with experience, experience_cost_ratio the
// median over queries both solved of the path's execution time with
// experience over from scratch. --quick replays the first 40 queries of each.
#include <time.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "bench_cli.hpp"
#include "plr/planning/lattice_planner.hpp"
#include "plr/planning/ompl_planner.hpp"
#include "plr/planning/query_set.hpp"
#include "plr/sim/collision.hpp"
#include "plr/sim/generators.hpp"
#include "plr/sim/octree.hpp"
#include "plr/sim/shipped_files.hpp"

using namespace plr::sim;
using namespace plr::planning;

namespace {

// Paper's Table I: mean time to the first solution (ms) per mode.
const std::map<PlanMode, double> kPaperMs = {
    {PlanMode::kArm, 90.9},         {PlanMode::kArmBase, 1104.8}, {PlanMode::kNose, 374.6},
    {PlanMode::kArmCartesian, 6.1}, {PlanMode::kBaseLine, 2.8},   {PlanMode::kEscape, 70.9}};

std::map<std::string, int> g_skipped;  // pick queries not generated, by reason

JointVector home(double base) {
  JointVector q;
  q << base, 0.0, -1.0, 2.0, 0.0, 0.5, 0.0, 0.0;
  return q;
}

JointVector with_nose(JointVector q, double lift, double pitch, double ext) {
  q[kNose1] = lift;
  q[kNose2] = pitch;
  q[kNose3] = ext;
  return q;
}

struct Scene {
  std::string name;
  World world;
  std::unique_ptr<CollisionChecker> checker;
  std::vector<PlanQuery> queries;
};

Eigen::AlignedBox3d aabb(const Box& b) {
  Eigen::AlignedBox3d out;
  for (int i = 0; i < 8; ++i) {
    const Eigen::Vector3d c((i & 1 ? 0.5 : -0.5) * b.size.x(), (i & 2 ? 0.5 : -0.5) * b.size.y(),
                            (i & 4 ? 0.5 : -0.5) * b.size.z());
    out.extend(b.pose * c);
  }
  return out;
}

PlanQuery pose_query(PlanMode mode, const JointVector& start, const Eigen::Vector3d& p,
                     double yaw) {
  PlanQuery q;
  q.mode = mode;
  q.start = start;
  PoseGoal g;
  g.target = {p, yaw};
  q.goal = g;
  return q;
}

PlanQuery joint_query(PlanMode mode, const JointVector& start, const JointVector& goal) {
  PlanQuery q;
  q.mode = mode;
  q.start = start;
  JointGoal g;
  g.q = goal;
  q.goal = g;
  return q;
}

// First collision-free IK solution (with held/ignored boxes of `scope_q`).
bool solve_ik(CollisionChecker& cc, const PlanQuery& scope_q, const PlateTarget& t,
              const JointVector& seed, JointVector& out) {
  const QueryScope scope(cc, scope_q);
  for (const JointVector& q : cc.robot().arm_ik(t, seed)) {
    if (cc.is_valid(q)) {
      out = q;
      return true;
    }
  }
  return false;
}

bool start_valid(CollisionChecker& cc, const PlanQuery& q) {
  const QueryScope scope(cc, q);
  return cc.is_valid(q.start);
}

// Executor-like queries for one scene: picks of front boxes and a sweep.
void make_queries(Scene& s, std::mt19937_64& rng, int picks) {
  CollisionChecker& cc = *s.checker;
  double front = s.world.trailer.depth;
  for (const Box& b : s.world.boxes) front = std::min(front, aabb(b).min().x());
  const double b0 = front - 1.35;
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const JointVector nose_down = with_nose(home(b0), 0.0, 0.05, 0.3);

  // Boxes whose front face is exposed: nothing in front of them.
  std::vector<const Box*> exposed;
  for (const Box& b : s.world.boxes) {
    const auto bb = aabb(b);
    bool hidden = false;
    for (const Box& o : s.world.boxes) {
      const auto ob = aabb(o);
      if (&o != &b && ob.max().x() < bb.min().x() + 0.02 && ob.max().y() > bb.center().y() &&
          ob.min().y() < bb.center().y() && ob.max().z() > bb.center().z() &&
          ob.min().z() < bb.center().z()) {
        hidden = true;
        break;
      }
    }
    if (!hidden && bb.min().x() < front + 1.0) exposed.push_back(&b);
  }
  if (exposed.empty()) return;

  // Nose and base moves of Pick and Sweep.
  s.queries.push_back(joint_query(PlanMode::kNose, home(b0), nose_down));
  s.queries.push_back(joint_query(PlanMode::kNose, nose_down, home(b0)));
  s.queries.push_back(joint_query(PlanMode::kNose, home(b0 - 0.5),
                                  with_nose(home(b0 - 0.5), 0.1 * u(rng), 0.05, 0.5)));
  s.queries.push_back(joint_query(PlanMode::kBaseLine, home(b0), home(b0 - 0.4 - 0.8 * u(rng))));
  s.queries.push_back(joint_query(PlanMode::kBaseLine, home(b0 - 1.0), home(b0 - 0.05 * u(rng))));
  s.queries.push_back(
      joint_query(PlanMode::kBaseLine, nose_down, with_nose(home(b0 - 1.5), 0.0, 0.05, 0.3)));

  for (int k = 0; k < picks; ++k) {
    const Box& box = *exposed[static_cast<std::size_t>(u(rng) * exposed.size()) % exposed.size()];
    const auto bb = aabb(box);
    const Eigen::Vector3d face(bb.min().x(), bb.center().y(), bb.center().z());
    const double far = b0 - 0.3 - 0.7 * u(rng);
    PlanQuery scope;  // target box ignored while approaching
    scope.ignored_boxes = {box.id};
    JointVector pre, contact, back;
    // The wrist turns the plate square to the face: stop it 1.2 cm short.
    const Eigen::Vector3d touch = face - Eigen::Vector3d(0.012, 0, 0);
    const PlateTarget pre_t{touch - Eigen::Vector3d(0.15, 0, 0), 0.0};
    if (!solve_ik(cc, PlanQuery{}, pre_t, nose_down, pre)) {
      ++g_skipped["pre-grasp IK"];
      continue;
    }
    if (!solve_ik(cc, scope, {touch, 0.0}, pre, contact)) {
      ++g_skipped["contact IK"];
      continue;
    }
    // M2: from home (further back, nose down) to the pre-grasp pose.
    s.queries.push_back(
        pose_query(PlanMode::kArmBase, with_nose(home(far), 0.0, 0.05, 0.3), pre_t.position, 0.0));
    // M1: arm alone to the pre-grasp pose.
    s.queries.push_back(pose_query(PlanMode::kArm, nose_down, pre_t.position, 0.0));
    // M4 approach (target ignored) and retract holding it.
    PlanQuery approach = pose_query(PlanMode::kArmCartesian, pre, touch, 0.0);
    approach.ignored_boxes = {box.id};
    s.queries.push_back(approach);
    PlanQuery held_scope;
    held_scope.held_boxes = {box};
    held_scope.start = contact;
    const Eigen::Vector3d back_p = touch - Eigen::Vector3d(0.35, 0, 0);
    if (!solve_ik(cc, held_scope, {back_p, 0.0}, contact, back)) {
      ++g_skipped["retract IK"];
      continue;
    }
    PlanQuery retract = pose_query(PlanMode::kArmCartesian, contact, back_p, 0.0);
    retract.held_boxes = {box};
    if (start_valid(cc, retract)) s.queries.push_back(retract);
    // M1: drop-off over the nose, holding the box in front of the plate.
    const Eigen::Vector3d drop_p(b0 + 0.6 - bb.sizes().x() / 2, 0.0, 0.55 + bb.sizes().z() / 2);
    PlanQuery drop = pose_query(PlanMode::kArm, back, drop_p, 0.0);
    drop.held_boxes = {box};
    drop.start = back;
    JointVector drop_q;
    if (solve_ik(cc, drop, {drop_p, 0.0}, back, drop_q)) s.queries.push_back(drop);
    // M1: back home from the drop-off.
    JointVector dropped;
    held_scope.start = back;
    if (solve_ik(cc, PlanQuery{}, {drop_p, 0.0}, back, dropped)) {
      s.queries.push_back(joint_query(PlanMode::kArm, dropped, nose_down));
    }
    // M6: drive forward from the pre-grasp pose until the first contact,
    // then 8 mm further (light contact): an escape, and an M1 query that has
    // to escape first.
    JointVector pressed = pre;
    while (cc.is_valid(pressed) && pressed[kBaseX] < pre[kBaseX] + 0.3) pressed[kBaseX] += 0.002;
    pressed[kBaseX] += 0.008;
    if (!cc.is_valid(pressed)) {
      PlanQuery esc;
      esc.mode = PlanMode::kEscape;
      esc.start = pressed;
      s.queries.push_back(esc);
      PlanQuery home_from_contact = joint_query(PlanMode::kArm, pressed, nose_down);
      s.queries.push_back(home_from_contact);
    }
  }
}

struct Row {
  std::vector<double> first_ms, first_cpu_ms, exec_s;
  double expansions = 0, checks = 0;
  int queries = 0, failures = 0;
  std::map<std::string, int> why;
};

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const double idx = p * (v.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(idx)),
             hi = static_cast<std::size_t>(std::ceil(idx));
  return v[lo] + (idx - lo) * (v[hi] - v[lo]);
}

double mean(const std::vector<double>& v) {
  double sum = 0.0;
  for (double x : v) sum += x;
  return v.empty() ? NAN : sum / static_cast<double>(v.size());
}

// The recorded failing set: how many of its queries the planner refuses
// within kRefuseWithin expansions, and why each of the others went on.
constexpr std::uint64_t kRefuseWithin = 100;

struct FailingSet {
  std::size_t queries = 0, refused = 0;
  std::map<std::string, int> answers;  // "M2 arm+base refused: goal invalid", ...
  double share() const { return queries ? static_cast<double>(refused) / queries : NAN; }
};

FailingSet run_failing_set(const std::vector<RecordedQuery>& set, Planner& planner,
                           const RobotModel& robot, bool verbose) {
  FailingSet out;
  for (const RecordedQuery& rq : set) {
    PlanQuery q = rq.query;
    // One more than the bound: a search still going at kRefuseWithin ends
    // with its budget spent, not refused.
    q.max_expansions = kRefuseWithin + 1;
    CollisionChecker checker(robot, rq.world);
    const PlanResult r = planner.plan(q, checker);
    const bool refused = r.status != PlanStatus::kSolved && !r.stats.budget_exhausted &&
                         !r.stats.time_limit_hit && r.stats.expansions <= kRefuseWithin;
    ++out.queries;
    out.refused += refused ? 1 : 0;
    ++out.answers[std::string(to_string(q.mode)) + (refused ? " refused: " : " not refused: ") +
                  (r.status == PlanStatus::kSolved ? "solved" : to_string(r.status))];
    if (verbose)
      std::fprintf(stderr, "failing set %s: %s after %zu expansions: %s\n", to_string(q.mode),
                   to_string(r.status), r.stats.expansions, r.message.c_str());
  }
  return out;
}

double thread_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// Recorded trailers replayed with and without experience.
struct Recurring {
  std::size_t trailers = 0, queries = 0, recurring = 0, solved_both = 0, solved_scratch = 0,
              solved_experience = 0, used_experience = 0;
  std::vector<double> scratch_ms, experience_ms;  // recurring, CPU time of the whole query
  std::vector<double> scratch_exp, experience_exp;
  // The recurring queries a search from scratch needed more than one
  // expansion for (the others are a direct move either way).
  std::vector<double> search_scratch_ms, search_experience_ms;
  std::vector<double> cost_ratio, time_ratio;  // solved by both
  // From scratch with the heuristic inflated as much as h_E may be (ε w_E):
  // what experience gains beyond a greedier search.
  std::size_t solved_inflated = 0;
  std::vector<double> inflated_ms, inflated_exp;
  double speedup() const { return percentile(scratch_ms, 0.5) / percentile(experience_ms, 0.5); }
  double search_speedup() const {
    return percentile(search_scratch_ms, 0.5) / percentile(search_experience_ms, 0.5);
  }
};

Recurring run_recurring(const std::vector<std::string>& files, const LatticeConfig& config,
                        const RobotModel& robot, std::size_t limit, bool verbose) {
  Recurring out;
  for (const std::string& file : files) {
    const auto set = load_query_set(file);
    if (!set) {
      std::fprintf(stderr, "bench_planner: %s\n", set.error().message.c_str());
      std::exit(2);
    }
    // One trailer: experience starts empty.
    LatticePlanner scratch(config), inflated(config), experience(config);
    scratch.set_experience(false);
    inflated.set_experience(false);
    experience.set_experience(true);
    ++out.trailers;
    for (std::size_t i = 0; i < set->size() && i < limit; ++i) {
      const RecordedQuery& rq = (*set)[i];
      ++out.queries;
      const bool recurring = experience.experience_paths(rq.query.mode) > 0;
      CollisionChecker c0(robot, rq.world), c1(robot, rq.world);
      double t0 = thread_cpu_s();
      const PlanResult a = scratch.plan(rq.query, c0);
      const double ms_a = 1e3 * (thread_cpu_s() - t0);
      t0 = thread_cpu_s();
      const PlanResult b = experience.plan(rq.query, c1);
      const double ms_b = 1e3 * (thread_cpu_s() - t0);
      if (verbose)
        std::fprintf(stderr,
                     "recurring %s %s: scratch %s %zu exp %.1f ms, experience %s %zu exp "
                     "(%zu from experience) %.1f ms\n",
                     to_string(rq.query.mode), recurring ? "again" : "first", to_string(a.status),
                     a.stats.expansions, ms_a, to_string(b.status), b.stats.expansions,
                     b.stats.experience_edges, ms_b);
      if (!recurring) continue;
      PlanQuery greedy = rq.query;
      greedy.eps_initial *= config.experience.weight;
      greedy.eps_final *= config.experience.weight;
      CollisionChecker c2(robot, rq.world);
      t0 = thread_cpu_s();
      const PlanResult g = inflated.plan(greedy, c2);
      out.inflated_ms.push_back(1e3 * (thread_cpu_s() - t0));
      out.inflated_exp.push_back(static_cast<double>(g.stats.expansions));
      out.solved_inflated += g.status == PlanStatus::kSolved ? 1 : 0;
      if (verbose)
        std::fprintf(stderr, "recurring %s inflated: %s %zu exp %.1f ms\n",
                     to_string(rq.query.mode), to_string(g.status), g.stats.expansions,
                     out.inflated_ms.back());
      ++out.recurring;
      const bool sa = a.status == PlanStatus::kSolved, sb = b.status == PlanStatus::kSolved;
      out.solved_scratch += sa ? 1 : 0;
      out.solved_experience += sb ? 1 : 0;
      out.used_experience += b.stats.experience_edges > 0 ? 1 : 0;
      out.scratch_ms.push_back(ms_a);
      out.experience_ms.push_back(ms_b);
      out.scratch_exp.push_back(static_cast<double>(a.stats.expansions));
      out.experience_exp.push_back(static_cast<double>(b.stats.expansions));
      if (a.stats.expansions > 1) {
        out.search_scratch_ms.push_back(ms_a);
        out.search_experience_ms.push_back(ms_b);
      }
      if (sa && sb) {
        ++out.solved_both;
        if (a.trajectory.duration() > 0)
          out.cost_ratio.push_back(b.trajectory.duration() / a.trajectory.duration());
        out.time_ratio.push_back(ms_a / std::max(ms_b, 1e-6));
      }
    }
  }
  return out;
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false, json = false, verbose = false;
  int only_mode = 0;
  std::uint64_t seed = 1, budget = 0;
  std::string primitives = shipped_file("robots/unloader_lattice.yaml").value().string();
  std::string failing = PLR_PLANNER_FAILING_SET;
  std::vector<std::string> recurring_sets = {PLR_PLANNER_RECURRING_A1, PLR_PLANNER_RECURRING_B2};
  CLI::App app{
      "Seeded planning queries per mode from Pick and Sweep actions on A1 walls and B1 "
      "piles: ARA* lattice planner and RRTConnect side by side"};
  plr::bench::add_quick_flag(
      app, quick, "2 walls and 1 pile, 3 picks each; 40 queries of each recorded trailer");
  plr::bench::add_json_flag(app, json);
  app.add_option("--seed", seed, "Random seed (worlds and queries)")->capture_default_str();
  app.add_option("--mode", only_mode, "Only the queries of this planning mode (0: all)")
      ->check(CLI::Range(0, 6))
      ->capture_default_str();
  app.add_option("--budget", budget, "Every query's max_expansions (0: none; deterministic)")
      ->capture_default_str();
  app.add_option("--primitives", primitives, "Lattice file instead of the shipped one")
      ->check(CLI::ExistingFile);
  app.add_option("--failing", failing,
                 "Query set of queries that spent their whole budget in bench_unload runs")
      ->check(CLI::ExistingFile)
      ->capture_default_str();
  app.add_option("--recurring", recurring_sets,
                 "Query sets of one trailer's M1 and M2 queries each, in the order asked")
      ->check(CLI::ExistingFile);
  double experience_weight = 0.0;
  app.add_option("--experience-weight", experience_weight,
                 "w_E of the recurring replay (default: the lattice file's)")
      ->check(CLI::Range(1.0, 100.0));
  app.add_flag("--verbose", verbose, "A line per query on stderr");
  plr::bench::parse_or_exit(app, argc, argv);
  const RobotModel robot = load_robot().value();
  auto lattice = LatticeConfig::from_file(primitives);
  if (!lattice) {
    std::fprintf(stderr, "bench_planner: %s\n", lattice.error().message.c_str());
    return 2;
  }
  LatticeConfig config = *lattice;
  if (experience_weight > 0) config.experience.weight = experience_weight;
  LatticePlanner arastar(std::move(*lattice));
  // Independent queries: each from scratch (experience has its own part).
  arastar.set_experience(false);
  plr::ompl_planner::OmplPlanner rrt({0.0, static_cast<std::uint32_t>(seed)});

  std::mt19937_64 rng(seed);
  std::vector<Scene> scenes;
  const int walls = quick ? 2 : 6, piles = quick ? 1 : 3, picks = quick ? 3 : 6;
  for (int i = 0; i < walls + piles; ++i) {
    Scene s;
    const bool wall = i < walls;
    s.world = generate_world(wall ? EnvFamily::kA1 : EnvFamily::kB1, seed * 100 + i);
    s.name = std::string(wall ? "A1" : "B1") + "/" + std::to_string(seed * 100 + i);
    std::shared_ptr<const octomap::OcTree> tree = build_trailer_octree(s.world.trailer);
    s.checker = std::make_unique<CollisionChecker>(robot, s.world, tree);
    make_queries(s, rng, picks);
    scenes.push_back(std::move(s));
  }

  std::map<PlanMode, std::map<std::string, Row>> rows;
  std::map<PlanMode, std::vector<double>> exec_ratio;  // ARA* / RRTConnect, both solved
  for (Scene& s : scenes) {
    for (PlanQuery& q : s.queries) {
      if (only_mode != 0 && static_cast<int>(q.mode) != only_mode) continue;
      q.max_expansions = budget;
      double exec[2] = {NAN, NAN};
      for (int p = 0; p < 2; ++p) {
        if (p == 1 && (q.mode == PlanMode::kEscape || !start_valid(*s.checker, q))) continue;
        const PlanResult r = p == 0 ? arastar.plan(q, *s.checker) : rrt.plan(q, *s.checker);
        if (verbose) {
          std::fprintf(stderr,
                       "%s %s %-10s %s: first %.2f ms cpu %.2f ms, %zu exp, %llu checks, %zu wp, "
                       "exec %.2f s %s\n",
                       s.name.c_str(), to_string(q.mode), p == 0 ? "ARA*" : "RRTConnect",
                       to_string(r.status), 1e3 * r.stats.first_solution_s,
                       1e3 * r.stats.first_solution_cpu_s, r.stats.expansions,
                       static_cast<unsigned long long>(r.stats.collision_checks), r.path.size(),
                       r.trajectory.duration(), r.message.c_str());
        }
        // M6 inside another mode counts for M6: its escape time.
        Row& row = rows[q.mode][p == 0 ? "ARA*" : "RRTConnect"];
        ++row.queries;
        if (r.status != PlanStatus::kSolved) {
          ++row.failures;
          ++row.why[std::string(to_string(r.status)) + ": " + r.message.substr(0, 60)];
          continue;
        }
        if (p == 0 && r.stats.escaped && q.mode != PlanMode::kEscape) {
          rows[PlanMode::kEscape]["ARA* (in other modes)"].first_ms.push_back(
              1e3 * r.stats.escape_time_s);
          rows[PlanMode::kEscape]["ARA* (in other modes)"].first_cpu_ms.push_back(
              1e3 * r.stats.escape_cpu_s);
          ++rows[PlanMode::kEscape]["ARA* (in other modes)"].queries;
        }
        row.first_ms.push_back(1e3 * r.stats.first_solution_s);
        row.first_cpu_ms.push_back(1e3 * r.stats.first_solution_cpu_s);
        row.expansions += r.stats.expansions;
        row.checks += r.stats.collision_checks;
        row.exec_s.push_back(r.trajectory.duration());
        exec[p] = r.trajectory.duration();
      }
      if (std::isfinite(exec[0]) && std::isfinite(exec[1]) && exec[1] > 0) {
        exec_ratio[q.mode].push_back(exec[0] / exec[1]);
      }
    }
  }

  nlohmann::json out = nlohmann::json::array();
  if (!json) {
    std::printf("%zu scenes (A1 walls, B1 piles), seed %llu%s, expansion budget %llu\n",
                scenes.size(), static_cast<unsigned long long>(seed), quick ? ", quick" : "",
                static_cast<unsigned long long>(budget));
    for (const auto& [why, n] : g_skipped)
      std::printf("picks not generated (%s): %d\n", why.c_str(), n);
    std::printf("first-solution times in ms; wall clock and this thread's CPU time\n");
    std::printf("%-13s %-22s %7s %5s %9s %9s %9s %9s %8s %8s %8s %8s %9s %9s\n", "mode", "planner",
                "queries", "fail", "wall_med", "wall_p95", "cpu_med", "cpu_p95", "p95/med",
                "exec_s", "expand", "checks", "paper_ms", "target");
  }
  for (auto& [mode, by_planner] : rows) {
    for (auto& [planner, row] : by_planner) {
      const double med = percentile(row.first_ms, 0.5), p95 = percentile(row.first_ms, 0.95);
      const double cmed = percentile(row.first_cpu_ms, 0.5),
                   cp95 = percentile(row.first_cpu_ms, 0.95);
      double exec = 0.0;
      for (double e : row.exec_s) exec += e;
      exec = row.exec_s.empty() ? NAN : exec / row.exec_s.size();
      const double paper = kPaperMs.at(mode);
      if (json) {
        out.push_back(
            {{"mode", to_string(mode)},
             {"planner", planner},
             {"queries", row.queries},
             {"failures", row.failures},
             {"median_ms", med},
             {"p95_ms", p95},
             {"cpu_median_ms", cmed},
             {"cpu_p95_ms", cp95},
             {"mean_exec_s", exec},
             {"mean_expansions", row.expansions / std::max<double>(1.0, row.first_ms.size())},
             {"paper_ms", paper},
             {"target_ms", paper / 10.0},
             {"cpu_median_meets_target", cmed <= paper / 10.0},
             {"failure_reasons", row.why}});
      } else {
        const double n = std::max<double>(1.0, row.first_ms.size());
        std::printf(
            "%-13s %-22s %7d %5d %9.3f %9.3f %9.3f %9.3f %8.2f %8.2f %8.0f %8.0f %9.1f %9.2f\n",
            to_string(mode), planner.c_str(), row.queries, row.failures, med, p95, cmed, cp95,
            cp95 / cmed, exec, row.expansions / n, row.checks / n, paper, paper / 10.0);
        for (const auto& [w, n] : row.why) std::printf("%38s %dx %s\n", "", n, w.c_str());
      }
    }
  }
  nlohmann::json ratios;
  for (auto& [mode, v] : exec_ratio) {
    const double med = percentile(v, 0.5), worst = *std::max_element(v.begin(), v.end());
    if (json) {
      ratios[to_string(mode)] = {{"median", med}, {"max", worst}, {"pairs", v.size()}};
    } else {
      std::printf("exec time ARA*/RRTConnect %-13s median %.2f  max %.2f  (%zu pairs)\n",
                  to_string(mode), med, worst, v.size());
    }
  }
  const auto set = load_query_set(failing);
  if (!set) {
    std::fprintf(stderr, "bench_planner: %s\n", set.error().message.c_str());
    return 2;
  }
  const FailingSet f = run_failing_set(*set, arastar, robot, verbose);
  // --quick: the first 40 queries of each trailer (a few picks).
  const Recurring rec =
      run_recurring(recurring_sets, config, robot, quick ? 40 : SIZE_MAX, verbose);
  if (json) {
    std::printf("%s\n",
                nlohmann::json{{"rows", out},
                               {"exec_ratio", ratios},
                               {"infeasible_refused_share", f.share()},
                               {"experience_speedup", rec.speedup()},
                               {"experience_cost_ratio", percentile(rec.cost_ratio, 0.5)},
                               {"recurring_set",
                                {{"files", recurring_sets},
                                 {"trailers", rec.trailers},
                                 {"queries", rec.queries},
                                 {"recurring", rec.recurring},
                                 {"solved_scratch", rec.solved_scratch},
                                 {"solved_experience", rec.solved_experience},
                                 {"used_experience", rec.used_experience},
                                 {"scratch_median_ms", percentile(rec.scratch_ms, 0.5)},
                                 {"experience_median_ms", percentile(rec.experience_ms, 0.5)},
                                 {"scratch_mean_expansions", mean(rec.scratch_exp)},
                                 {"experience_mean_expansions", mean(rec.experience_exp)},
                                 {"speedup_per_query_median", percentile(rec.time_ratio, 0.5)},
                                 {"cost_ratio_p95", percentile(rec.cost_ratio, 0.95)},
                                 {"searches", rec.search_scratch_ms.size()},
                                 {"searches_speedup", rec.search_speedup()},
                                 {"inflated_solved", rec.solved_inflated},
                                 {"inflated_median_ms", percentile(rec.inflated_ms, 0.5)},
                                 {"inflated_mean_expansions", mean(rec.inflated_exp)},
                                 {"cost_ratio_max", percentile(rec.cost_ratio, 1.0)}}},
                               {"failing_set",
                                {{"file", failing},
                                 {"queries", f.queries},
                                 {"refused", f.refused},
                                 {"refuse_within_expansions", kRefuseWithin},
                                 {"answers", f.answers}}}}
                    .dump()
                    .c_str());
  } else {
    std::printf("\nrecorded failing set (%s): %zu queries, %zu refused within %llu expansions\n",
                failing.c_str(), f.queries, f.refused,
                static_cast<unsigned long long>(kRefuseWithin));
    for (const auto& [what, n] : f.answers) std::printf("  %4d %s\n", n, what.c_str());
    std::printf("infeasible_refused_share %.2f (issue 46 target >= 0.90)\n", f.share());
    std::printf(
        "\nrecurring pick queries (%zu trailers, %zu M1/M2 queries, %zu asked with experience):\n"
        "  solved from scratch %zu, with experience %zu; experience used in %zu\n"
        "  CPU ms per query, median: from scratch %.2f, with experience %.2f; expansions, "
        "mean: %.1f, %.1f\n"
        "  per-query speedup median %.2f; cost ratio p95 %.2f, max %.2f (%zu solved by both)\n",
        rec.trailers, rec.queries, rec.recurring, rec.solved_scratch, rec.solved_experience,
        rec.used_experience, percentile(rec.scratch_ms, 0.5), percentile(rec.experience_ms, 0.5),
        mean(rec.scratch_exp), mean(rec.experience_exp), percentile(rec.time_ratio, 0.5),
        percentile(rec.cost_ratio, 0.95), percentile(rec.cost_ratio, 1.0), rec.solved_both);
    std::printf(
        "  the %zu that needed a search from scratch (> 1 expansion): CPU ms median %.2f "
        "from scratch, %.2f with experience: speedup %.2f\n",
        rec.search_scratch_ms.size(), percentile(rec.search_scratch_ms, 0.5),
        percentile(rec.search_experience_ms, 0.5), rec.search_speedup());
    std::printf(
        "  from scratch at eps x w_E (no experience): solved %zu, CPU ms median %.2f, "
        "expansions mean %.1f\n",
        rec.solved_inflated, percentile(rec.inflated_ms, 0.5), mean(rec.inflated_exp));
    std::printf(
        "experience_speedup %.2f (issue 46 target >= 10), experience_cost_ratio %.2f "
        "(<= 1.5)\n",
        rec.speedup(), percentile(rec.cost_ratio, 0.5));
  }
  return 0;
}
