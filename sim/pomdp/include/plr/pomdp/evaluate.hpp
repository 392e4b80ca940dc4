// Policy evaluation by simulation: episodes from states drawn from the
// initial belief, the planner replanning from the exact (or particle) belief
// at every step; mean discounted return with a 95 % confidence interval.
#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <vector>

#include "plr/pomdp/model.hpp"
#include "plr/pomdp/planner.hpp"
#include "plr/pomdp/policy_tree.hpp"

namespace plr::pomdp {

struct EvaluationOptions {
  int episodes = 100;
  // Steps per episode; 0: until gamma^t times the largest reward is below 1e-3
  // (200 for goal-directed models). Terminal states end an episode earlier.
  int max_steps = 0;
  Budget per_step;
  std::uint64_t seed = 1;
  // No episode starts after this many seconds (at least one runs).
  double max_seconds = std::numeric_limits<double>::infinity();
  // A control variate: a number for every start state whose mean under the
  // initial belief is known exactly (the state's MDP value, say). Returns
  // that follow it vary less around the regression line than around their
  // mean, so the same episodes give a narrower interval. Empty: none.
  std::function<double(StateId)> control;
  // Episodes run side by side on this many threads, each with its own
  // planner (evaluate() with a factory; one planner means one worker).
  int workers = 1;
  // Called after every episode with (done, total), one call at a time.
  std::function<void(int, int)> progress;
};

struct Evaluation {
  std::vector<double> returns;  // discounted return per episode
  double mean = 0.0;
  double ci95 = 0.0;  // half-width of the 95 % confidence interval of the mean
  double stddev = 0.0;
  double mean_steps = 0.0;
  // Over all plan() calls.
  double median_step_seconds = 0.0;
  double max_step_seconds = 0.0;
  double mean_iterations_per_step = 0.0;
  std::size_t max_nodes = 0;
  std::size_t max_memory_bytes = 0;
  // The first plan() call of the first episode: the root's bounds and effort.
  PlanStats first_step;
  // With a control: its value per episode, and the regression estimate of
  // the same mean (returns adjusted by beta times the control's deviation
  // from its known mean) with its 95 % half-width.
  std::vector<double> controls;
  double cv_mean = 0.0, cv_ci95 = 0.0, cv_beta = 0.0;
  int lost_beliefs = 0;  // episodes cut short: an observation the belief ruled out
  double seconds = 0.0;
};

// Mean and 95 % half-width (Student's t for small samples).
void summarize(Evaluation& e);
// The control-variate estimate from e.returns and e.controls, whose mean
// over the initial belief is `control_mean`; after summarize(e), whose
// estimate it keeps when there is nothing to regress on (fewer than three
// episodes, or a control that does not vary).
void summarize_with_control(Evaluation& e, double control_mean);
int default_max_steps(const GenerativeModel& model);

// Makes the planner of one worker (0, 1, ...); each episode starts it from
// the initial belief with reset(), so every episode is a fresh search.
using PlannerFactory = std::function<std::unique_ptr<OnlinePlanner>(int worker)>;

// Episode i draws its states and observations from a generator seeded by
// (seed, i), so which worker runs it does not change what happens in it
// (only the wall-clock budget of its searches).
Evaluation evaluate(const GenerativeModel& model, const PlannerFactory& make_planner,
                    const EvaluationOptions& options);
// One worker, on the given planner.
Evaluation evaluate(const GenerativeModel& model, OnlinePlanner& planner,
                    const EvaluationOptions& options);

// Follows a fixed tree; an episode stops earning where the tree ends
// (a finite-horizon value).
Evaluation evaluate_tree(const GenerativeModel& model, const PolicyTree& tree,
                         const EvaluationOptions& options);

}  // namespace plr::pomdp
