#include "plr/pomdp/evaluate.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <mutex>
#include <optional>
#include <thread>

namespace plr::pomdp {
namespace {

double t_quantile_975(std::size_t dof) {
  // Two-sided 95 % quantiles of Student's t; 1.96 beyond the table.
  static const double table[] = {12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306,
                                 2.262,  2.228, 2.201, 2.179, 2.160, 2.145, 2.131, 2.120,
                                 2.110,  2.101, 2.093, 2.086, 2.080, 2.074, 2.069, 2.064,
                                 2.060,  2.056, 2.052, 2.048, 2.045, 2.042};
  if (dof == 0) return 0.0;
  if (dof <= 30) return table[dof - 1];
  if (dof <= 60) return 2.000;
  if (dof <= 120) return 1.980;
  return 1.960;
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const std::size_t mid = v.size() / 2;
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid), v.end());
  const double hi = v[mid];
  if (v.size() % 2 == 1) return hi;
  return (hi + *std::max_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(mid))) / 2.0;
}

}  // namespace

void summarize(Evaluation& e) {
  const auto n = e.returns.size();
  if (n == 0) return;
  double sum = 0.0;
  for (double r : e.returns) sum += r;
  e.mean = sum / static_cast<double>(n);
  double ss = 0.0;
  for (double r : e.returns) ss += (r - e.mean) * (r - e.mean);
  e.stddev = n > 1 ? std::sqrt(ss / static_cast<double>(n - 1)) : 0.0;
  e.ci95 = t_quantile_975(n - 1) * e.stddev / std::sqrt(static_cast<double>(n));
}

void summarize_with_control(Evaluation& e, double control_mean) {
  // Linear-regression estimator: Y = a + beta (X - mean X); the estimate is
  // the line at the known mean of X, its standard error the line's there.
  const auto plain = [&e] {
    e.cv_beta = 0.0;
    e.cv_mean = e.mean;
    e.cv_ci95 = e.ci95;
  };
  const std::size_t n = e.returns.size();
  if (n < 3 || e.controls.size() != n) return plain();
  const auto count = static_cast<double>(n);
  double mx = 0.0, my = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    mx += e.controls[i];
    my += e.returns[i];
  }
  mx /= count;
  my /= count;
  double sxx = 0.0, sxy = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    sxx += (e.controls[i] - mx) * (e.controls[i] - mx);
    sxy += (e.controls[i] - mx) * (e.returns[i] - my);
  }
  // A control that (up to rounding) does not vary carries no information:
  // the plain estimate stands (in Tiger both states have the same MDP value).
  if (sxx <= 1e-18 * count * (1.0 + mx * mx)) return plain();
  e.cv_beta = sxy / sxx;
  e.cv_mean = my - e.cv_beta * (mx - control_mean);
  double sse = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double r = e.returns[i] - my - e.cv_beta * (e.controls[i] - mx);
    sse += r * r;
  }
  const double s2 = sse / (count - 2.0);
  const double leverage = (mx - control_mean) * (mx - control_mean) / sxx;
  e.cv_ci95 = t_quantile_975(n - 2) * std::sqrt(s2 * (1.0 / count + leverage));
}

int default_max_steps(const GenerativeModel& model) {
  const double g = model.discount();
  if (g >= 1.0) return 200;
  if (g <= 0.0) return 1;
  const double scale = std::max({1e-9, std::abs(model.max_reward()), std::abs(model.min_reward())});
  const double steps = std::log(1e-3 * (1.0 - g) / scale) / std::log(g);
  return static_cast<int>(std::clamp(std::ceil(steps), 1.0, 100000.0));
}

namespace {

// What one worker saw over its episodes.
struct Tally {
  std::vector<double> step_seconds;
  double iterations = 0.0, steps = 0.0;
  std::size_t max_nodes = 0, max_memory_bytes = 0;
  int lost_beliefs = 0;
  std::optional<PlanStats> first_step;  // episode 0's, if this worker ran it
};

struct Episode {
  double ret = 0.0;      // discounted return
  double control = 0.0;  // the control's value at the start state
};

Episode run_episode(const GenerativeModel& model, OnlinePlanner& planner,
                    const EvaluationOptions& options, int max_steps, int ep, Tally& tally) {
  std::seed_seq seq{static_cast<std::uint32_t>(options.seed),
                    static_cast<std::uint32_t>(options.seed >> 32), static_cast<std::uint32_t>(ep)};
  Rng rng(seq);
  Belief belief = model.initial_belief();
  StateId s = sample_state(belief, rng);
  Episode out;
  if (options.control) out.control = options.control(s);
  planner.reset(belief);
  double g = 1.0;
  for (int t = 0; t < max_steps && !model.is_terminal(s); ++t) {
    const ActionId a = planner.plan(options.per_step);
    const PlanStats& st = planner.last_stats();
    if (ep == 0 && t == 0) tally.first_step = st;
    tally.step_seconds.push_back(st.seconds);
    tally.iterations += static_cast<double>(st.iterations);
    tally.max_nodes = std::max(tally.max_nodes, st.nodes);
    tally.max_memory_bytes = std::max(tally.max_memory_bytes, st.memory_bytes);
    const Step step = model.step(s, a, rng);
    out.ret += g * step.reward;
    g *= model.discount();
    s = step.next;
    tally.steps += 1.0;
    if (step.terminal) break;
    Belief next = update_belief(model, belief, a, step.observation, rng);
    if (next.empty()) {
      ++tally.lost_beliefs;
      break;
    }
    belief = std::move(next);
    planner.advance(a, step.observation, belief);
  }
  return out;
}

Evaluation evaluate_on(const GenerativeModel& model, const std::vector<OnlinePlanner*>& planners,
                       const EvaluationOptions& options) {
  using Clock = std::chrono::steady_clock;
  const auto t0 = Clock::now();
  const int max_steps = options.max_steps > 0 ? options.max_steps : default_max_steps(model);
  const int total = std::max(0, options.episodes);
  std::vector<double> returns(static_cast<std::size_t>(total));
  std::vector<double> controls(options.control ? returns.size() : 0);
  std::vector<Tally> tallies(planners.size());
  std::mutex mutex;
  int next = 0, done = 0;
  const auto work = [&](std::size_t w) {
    for (;;) {
      int ep = 0;
      {
        const std::lock_guard<std::mutex> lock(mutex);
        if (next >= total || (next > 0 && std::chrono::duration<double>(Clock::now() - t0).count() >
                                              options.max_seconds)) {
          return;
        }
        ep = next++;
      }
      const Episode e = run_episode(model, *planners[w], options, max_steps, ep, tallies[w]);
      const std::lock_guard<std::mutex> lock(mutex);
      returns[static_cast<std::size_t>(ep)] = e.ret;
      if (options.control) controls[static_cast<std::size_t>(ep)] = e.control;
      if (options.progress) options.progress(++done, total);
    }
  };
  std::vector<std::thread> threads;
  for (std::size_t w = 1; w < planners.size(); ++w) threads.emplace_back(work, w);
  work(0);
  for (std::thread& t : threads) t.join();

  // Every episode handed out has finished, so the first `next` are all there.
  Evaluation out;
  returns.resize(static_cast<std::size_t>(next));
  out.returns = std::move(returns);
  summarize(out);
  if (options.control) {
    controls.resize(out.returns.size());
    out.controls = std::move(controls);
    double mean = 0.0;
    const Belief initial = model.initial_belief();
    for (const Particle& p : initial.particles()) {
      mean += p.weight * options.control(p.state);
    }
    summarize_with_control(out, mean);
  }
  std::vector<double> step_seconds;
  double iterations = 0.0, steps = 0.0;
  for (const Tally& t : tallies) {
    step_seconds.insert(step_seconds.end(), t.step_seconds.begin(), t.step_seconds.end());
    iterations += t.iterations;
    steps += t.steps;
    out.max_nodes = std::max(out.max_nodes, t.max_nodes);
    out.max_memory_bytes = std::max(out.max_memory_bytes, t.max_memory_bytes);
    out.lost_beliefs += t.lost_beliefs;
    if (t.first_step) out.first_step = *t.first_step;
  }
  out.mean_steps = out.returns.empty() ? 0.0 : steps / static_cast<double>(out.returns.size());
  out.max_step_seconds =
      step_seconds.empty() ? 0.0 : *std::max_element(step_seconds.begin(), step_seconds.end());
  out.median_step_seconds = median(std::move(step_seconds));
  out.mean_iterations_per_step = steps > 0 ? iterations / steps : 0.0;
  out.seconds = std::chrono::duration<double>(Clock::now() - t0).count();
  return out;
}

}  // namespace

Evaluation evaluate(const GenerativeModel& model, const PlannerFactory& make_planner,
                    const EvaluationOptions& options) {
  std::vector<std::unique_ptr<OnlinePlanner>> owned;
  std::vector<OnlinePlanner*> planners;
  for (int w = 0; w < std::max(1, options.workers); ++w) {
    owned.push_back(make_planner(w));
    planners.push_back(owned.back().get());
  }
  return evaluate_on(model, planners, options);
}

Evaluation evaluate(const GenerativeModel& model, OnlinePlanner& planner,
                    const EvaluationOptions& options) {
  return evaluate_on(model, {&planner}, options);
}

Evaluation evaluate_tree(const GenerativeModel& model, const PolicyTree& tree,
                         const EvaluationOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  Evaluation out;
  Rng rng(options.seed);
  double steps = 0.0;
  for (int ep = 0; ep < options.episodes && !tree.nodes.empty(); ++ep) {
    StateId s = sample_state(model.initial_belief(), rng);
    std::optional<std::uint32_t> node = tree.root;
    double ret = 0.0, g = 1.0;
    while (node && !model.is_terminal(s)) {
      const Step step = model.step(s, tree.nodes[*node].action, rng);
      ret += g * step.reward;
      g *= model.discount();
      s = step.next;
      steps += 1.0;
      node = tree.next(*node, step.observation);
    }
    out.returns.push_back(ret);
    if (options.progress) options.progress(ep + 1, options.episodes);
  }
  summarize(out);
  out.mean_steps = options.episodes > 0 ? steps / options.episodes : 0.0;
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return out;
}

}  // namespace plr::pomdp
