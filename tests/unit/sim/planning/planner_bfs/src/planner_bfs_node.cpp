// A breadth-first planner: from the start, steps of 0.1 (rad or m) of one
// joint of the mode at a time, until a straight move reaches the goal. Few
// lines, no optimality: what the planner contract takes care of (query
// checks, judging the goal, the M6 escape, timing the path, the service)
// it does not repeat.
#include <plr/interface.hpp>
#include <plr/messages.hpp>
#include <plr/plugin.hpp>

#include <array>
#include <chrono>
#include <deque>
#include <map>

#include "plr/planning/planner_node.hpp"
#include "plr/planning/shortcut.hpp"

namespace {

using plr::planning::JointGoal;
using plr::planning::PlanMode;
using plr::planning::PlanQuery;
using plr::planning::PlanResult;
using plr::planning::PlanStatus;
using plr::planning::PoseGoal;
using plr::sim::JointVector;

class BfsPlanner final : public plr::planning::Planner {
 public:
  std::string name() const override { return "bfs"; }
  std::vector<PlanMode> modes() const override {
    return {PlanMode::kArm, PlanMode::kNose, PlanMode::kBaseLine};
  }

 protected:
  PlanResult do_plan(const PlanQuery& q, plr::sim::CollisionChecker& checker) override {
    const auto joints = plr::planning::planned_joints(q.mode);
    // The goal as a configuration: the first collision-free IK solution of a pose.
    std::vector<JointVector> goals;
    if (const auto* jg = std::get_if<JointGoal>(&q.goal)) {
      JointVector g = q.start;
      for (int j : joints) g[j] = jg->q[j];
      goals.push_back(g);
    } else {
      for (const JointVector& g :
           checker.robot().arm_ik(std::get<PoseGoal>(q.goal).target, q.start))
        if (checker.is_valid(g)) goals.push_back(g);
    }
    const auto deadline = std::chrono::steady_clock::now() +
                          std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                              std::chrono::duration<double>(q.time_limit_s));
    using Key = std::array<int, 8>;
    std::map<Key, Key> parent;  // visited, with where each came from
    std::deque<Key> open{Key{}};
    parent[Key{}] = Key{};
    auto config = [&](const Key& k) {
      JointVector c = q.start;
      for (std::size_t i = 0; i < joints.size(); ++i) c[joints[i]] += 0.1 * k[i];
      return c;
    };
    PlanResult r;
    while (!open.empty()) {
      if (q.max_expansions != 0 && r.stats.expansions >= q.max_expansions) {
        r.status = PlanStatus::kTimeout;
        r.stats.budget_exhausted = true;
        return r;
      }
      if (std::chrono::steady_clock::now() > deadline) {
        r.status = PlanStatus::kTimeout;
        r.stats.time_limit_hit = true;
        r.message = "no solution within the time limit";
        return r;
      }
      const Key k = open.front();
      open.pop_front();
      ++r.stats.expansions;
      const JointVector here = config(k);
      for (const JointVector& g : goals) {
        if (!checker.is_motion_valid(here, g)) continue;
        r.path = {g};
        for (Key at = k;; at = parent[at]) {
          r.path.insert(r.path.begin(), config(at));
          if (at == Key{}) break;
        }
        r.path = plr::planning::shortcut_path(r.path, checker);
        r.status = PlanStatus::kSolved;
        return r;
      }
      for (std::size_t i = 0; i < joints.size(); ++i) {
        for (int step : {1, -1}) {
          Key next = k;
          next[i] += step;
          if (parent.count(next)) continue;
          const JointVector c = config(next);
          if (!checker.is_valid(c) || !checker.is_motion_valid(here, c, false)) continue;
          parent[next] = k;
          open.push_back(next);
        }
      }
    }
    r.status = PlanStatus::kNoPath;
    r.message = "no path on the 0.1 grid";
    return r;
  }
};

class PlannerBfsNode final : public plr::planning::PlannerNode {
 public:
  using PlannerNode::PlannerNode;

 protected:
  plr::Expected<std::unique_ptr<plr::planning::Planner>> make_planner() override {
    return std::unique_ptr<plr::planning::Planner>(std::make_unique<BfsPlanner>());
  }
};

}  // namespace

PLR_PLUGIN(PlannerBfsNode, "planner_bfs", "0.1.0", PLR_KIND_PLANNER,
           "breadth-first motion planner (M1, M3, M5) serving `plan`")
PLR_INTERFACE(plr::service<plr::msg::PlanRequest, plr::msg::PlanResponse>("plan"))
