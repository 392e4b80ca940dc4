#include "plr/actions/action_model.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <future>
#include <optional>
#include <unordered_map>
#include <unordered_set>

namespace plr::actions {

using planning::PlanMode;
using planning::PlanStatus;
using sim::JointVector;

double PlanTimeModel::seconds(PlanMode mode, std::uint64_t expansions) const {
  const auto m = static_cast<std::size_t>(mode);
  if (m >= per_query_s.size()) return 0.0;
  return per_query_s[m] + per_expansion_s[m] * static_cast<double>(expansions);
}

namespace {

// How many boxes of `after` moved more than `shift` (m) or turned more than
// `turn` (rad) from their pose in `before`; those not in `before` are
// counted in `unknown`.
std::uint32_t boxes_moved(const sim::World& before, const sim::World& after, double shift,
                          double turn, std::uint32_t* unknown = nullptr) {
  std::unordered_map<std::uint32_t, const sim::Box*> was;
  for (const auto& b : before.boxes) was.emplace(b.id, &b);
  std::uint32_t n = 0;
  for (const auto& b : after.boxes) {
    const auto it = was.find(b.id);
    if (it == was.end()) {
      if (unknown) ++*unknown;
      continue;
    }
    const Eigen::AngleAxisd turned(it->second->pose.linear().transpose() * b.pose.linear());
    if ((b.pose.translation() - it->second->pose.translation()).norm() > shift ||
        std::abs(turned.angle()) > turn)
      ++n;
  }
  return n;
}

}  // namespace

std::uint32_t boxes_shifted(const sim::World& before, const sim::World& after) {
  return boxes_moved(before, after, 0.05, 0.2);  // m, rad
}

bool PlanAhead::same_state(const Perceived& predicted, const Perceived& observed) {
  if ((predicted.q - observed.q).cwiseAbs().maxCoeff() > kJoints) return false;
  auto held_p = predicted.held, held_o = observed.held;
  std::sort(held_p.begin(), held_p.end());
  std::sort(held_o.begin(), held_o.end());
  if (held_p != held_o || predicted.world.boxes.size() != observed.world.boxes.size()) return false;
  std::uint32_t unknown = 0;
  return boxes_moved(predicted.world, observed.world, kBoxShift, kBoxTurn, &unknown) == 0 &&
         unknown == 0;
}

plr::Status ActionOptions::check() const {
  if (auto ok = observation.check(); !ok) return ok;
  auto bad = [](const char* what) { return plr::make_error(PLR_ERR_INVALID, what); };
  if (!(plan_timeout_s > 0)) return bad("param 'plan_timeout_s': must be > 0");
  if (plan_expansions == 0) return bad("param 'plan_expansions': must be >= 1");
  for (double e : plan_epsilons)
    if (!(e >= 1.0)) return bad("param 'plan_epsilons': each must be >= 1");
  if (plan_epsilons.empty()) return bad("param 'plan_epsilons': needs at least one value");
  if (pick_candidates == 0) return bad("param 'pick_candidates': must be >= 1");
  if (grip_attempts < 1) return bad("param 'grip_attempts': must be >= 1");
  if (!(settle_s >= 0)) return bad("param 'settle_s': must be >= 0");
  if (!(retreat_m >= 0) || !(dropoff_backoff_m >= 0))
    return bad("params 'retreat_m', 'dropoff_backoff_m': must be >= 0");
  return {};
}

namespace {

using Clock = std::chrono::steady_clock;

// Unwinds an action when its backend fails in a way that ends it; run()
// turns it back into the error.
struct Aborted {
  plr::Error error;
};

bool ends_the_action(const plr::Error& e) {
  return e.code == PLR_ERR_UNAVAILABLE || e.code == PLR_ERR_TIMEOUT || e.code == PLR_ERR_CANCELLED;
}

// A goal for a step: joint values for the mode's joints, or a plate pose.
// `then`: the straight plate moves that follow a pose goal; its IK solutions
// must carry the arm through them on one branch.
struct Goal {
  std::vector<std::pair<int, double>> joints;
  std::optional<sim::PlateTarget> pose;
  std::vector<sim::PlateTarget> then;
};

struct Planned {
  bool ok = false;
  std::string message;
  PlanStatus status = PlanStatus::kSolved;
  std::vector<planning::TimedPoint> points;
};

bool same_goal(const Goal& a, const Goal& b) {
  auto same = [](const sim::PlateTarget& x, const sim::PlateTarget& y) {
    return x.position == y.position && x.yaw == y.yaw;
  };
  return a.joints == b.joints && a.pose.has_value() == b.pose.has_value() &&
         (!a.pose || same(*a.pose, *b.pose)) && a.then.size() == b.then.size() &&
         std::equal(a.then.begin(), a.then.end(), b.then.begin(), same);
}

// One step of an action: a motion planned to a goal, the suction before and
// after it, the boxes its planning leaves out, the cups it opens.
struct Step {
  Step(std::string what, PlanMode mode, Goal goal, Suction before = Suction::kKeep,
       Suction after = Suction::kKeep, std::vector<std::uint32_t> leave_out = {},
       std::vector<bool> cups_open = {})
      : what(std::move(what)),
        mode(mode),
        goal(std::move(goal)),
        before(before),
        after(after),
        leave_out(std::move(leave_out)),
        cups_open(std::move(cups_open)) {}
  std::string what;
  PlanMode mode;
  Goal goal;
  Suction before, after;
  std::vector<std::uint32_t> leave_out;
  std::vector<bool> cups_open;
};

// Whether two steps ask the same of the planner.
bool same_query(const Step& a, const Step& b) {
  return a.what == b.what && a.mode == b.mode && same_goal(a.goal, b.goal) &&
         a.leave_out == b.leave_out;
}

// What planning a step took: its answer, the queries asked, the modelled
// seconds the robot would wait for them, and an error that ends the action.
struct Attempt {
  Planned plan;
  std::vector<QueryRecord> queries;
  double model_s = 0.0;
  double wall_s = 0.0;
  std::optional<plr::Error> abort;
};

// Turns a step's goal into planning queries and asks the backend. It
// touches nothing but the backend: a plan made while moving runs it on
// another thread, concurrently with the backend's execute().
class Asker {
 public:
  Asker(const sim::RobotModel& robot, const ActionOptions& o, Backend& backend)
      : robot_(&robot), o_(&o), backend_(&backend) {}

  Attempt once(PlanMode mode, const Perceived& w, const Goal& goal,
               const std::vector<std::uint32_t>& leave_out) const {
    Attempt a;
    ask(a, mode, w, goal, leave_out);
    return a;
  }

  // Free-space arm moves (M1, M2) go to joint goals from the arm's
  // closed-form IK, nearest solution first: the lattice reaches a joint
  // goal far sooner than it snaps onto a pose. A goal in collision tries
  // the next solution.
  Attempt goal(PlanMode mode, const Perceived& w, const Goal& goal,
               const std::vector<std::uint32_t>& leave_out) const {
    if (!goal.pose || (mode != PlanMode::kArm && mode != PlanMode::kArmBase))
      return once(mode, w, goal, leave_out);
    auto solutions = robot_->arm_ik(*goal.pose, w.q);
    std::erase_if(solutions,
                  [&](const JointVector& q) { return !follows_lines(*robot_, q, goal.then); });
    Attempt a;
    a.plan.message = goal.then.empty() ? "no arm IK solution for the goal pose"
                                       : "no arm IK solution for the goal pose from which the "
                                         "straight moves after it stay on one IK branch";
    a.plan.status = PlanStatus::kGoalInvalid;
    for (std::size_t i = 0; i < solutions.size() && i < 3; ++i) {
      Goal g;
      for (int j : {sim::kArm1, sim::kArm2, sim::kArm3, sim::kArm4})
        g.joints.emplace_back(j, solutions[i][j]);
      ask(a, mode, w, g, leave_out);
      if (a.abort || a.plan.ok || a.plan.status != PlanStatus::kGoalInvalid) break;
    }
    return a;
  }

 private:
  void ask(Attempt& a, PlanMode mode, const Perceived& w, const Goal& goal,
           const std::vector<std::uint32_t>& leave_out) const {
    const ActionOptions& o = *o_;
    planning::PlanQuery q;
    q.mode = mode;
    q.start = w.q;
    if (goal.pose) {
      q.goal = planning::PoseGoal{*goal.pose};
    } else if (mode != PlanMode::kEscape) {
      JointVector g = w.q;
      for (auto [j, v] : goal.joints) g[j] = v;
      q.goal = planning::JointGoal{g};
    }
    q.time_limit_s = o.plan_timeout_s;
    q.max_expansions = o.plan_expansions;
    q.eps_initial = o.plan_epsilons.front();
    q.eps_final = o.plan_epsilons.back();
    q.eps_decrement = o.plan_epsilons.size() > 1
                          ? std::max(1e-3, (q.eps_initial - q.eps_final) /
                                               static_cast<double>(o.plan_epsilons.size() - 1))
                          : 1.0;
    q.ignored_boxes = leave_out;
    for (const sim::Box& b : w.world.boxes)
      if (std::find(w.held.begin(), w.held.end(), b.id) != w.held.end()) q.held_boxes.push_back(b);
    const auto t0 = Clock::now();
    auto r = backend_->plan(q, w.world);
    a.wall_s += std::chrono::duration<double>(Clock::now() - t0).count();
    QueryRecord rec;
    rec.mode = mode;
    Planned& p = a.plan;
    p = Planned{};
    if (!r) {
      if (r.error().code == PLR_ERR_CANCELLED) {
        a.abort = r.error();
        return;
      }
      a.queries.push_back(rec);
      p.message = "plan: " + r.error().message;
      p.status = PlanStatus::kTimeout;
      return;
    }
    if (r->stats.time_limit_hit) {
      // Fewer expansions on a busier machine: the outcome and its modelled
      // planning time would depend on the load. Not PLR_ERR_TIMEOUT: the
      // executor takes that for a lost simulator and repeats the action.
      a.abort = plr::make_error(
          PLR_ERR_INVALID,
          fmt::format("plan: {} ended by the {} s safety net before its budget of {} expansions "
                      "({} done); raise plan_timeout_s",
                      planning::to_string(mode), o.plan_timeout_s, o.plan_expansions,
                      r->stats.expansions));
      return;
    }
    rec.answered = true;
    rec.status = r->status;
    rec.planner = r->planner;
    rec.expansions = r->stats.expansions;
    rec.planning_ms = 1e3 * r->stats.planning_time_s;
    rec.escaped = r->stats.escaped;
    rec.escape_ms = 1e3 * r->stats.escape_time_s;
    a.queries.push_back(rec);
    a.model_s += o.plan_time.seconds(mode, r->stats.expansions);
    p.status = r->status;
    if (r->status != PlanStatus::kSolved || r->points.empty()) {
      p.message = std::string(planning::to_string(r->status)) +
                  (r->message.empty() ? "" : ": " + r->message);
      return;
    }
    p.ok = true;
    p.points = std::move(r->points);
  }

  const sim::RobotModel* robot_;
  const ActionOptions* o_;
  Backend* backend_;
};

// A plan made while a motion runs, for the step after it, from the state
// the motion is predicted to end in.
struct Ahead {
  Step step;
  std::vector<std::uint32_t> ignored;  // sorted
  Perceived predicted;
  std::future<Attempt> attempt;
  bool moved = false;      // the motion it was made during has run
  double overlap_s = 0.0;  // that motion's duration
};

std::vector<std::uint32_t> sorted(std::vector<std::uint32_t> v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
  return v;
}

// Sets a value for a scope, then puts the old one back (the trajectories'
// time scale while a box is carried).
class Slowed {
 public:
  Slowed(double& value, double scale) : value_(value), old_(value) { value_ = scale; }
  ~Slowed() { value_ = old_; }
  Slowed(const Slowed&) = delete;
  Slowed& operator=(const Slowed&) = delete;

 private:
  double& value_;
  const double old_;
};

enum class Delivery { kDelivered, kNoPlace, kLost };

// Boxes that are not part of the scene in front of the robot: those lying
// on it that a shake has not been tried for yet (one a shake left where it
// was is most likely leaning on the robot from the pile it belongs to), and
// those behind it (B2 s2: sweeps and picks planned the base back behind
// such a box and found no path).
std::vector<std::uint32_t> set_aside(const Perceived& w, const Memory& memory,
                                     const sim::RobotModel& robot) {
  auto out = boxes_on_robot(w.world, robot, w.q, w.held);
  std::erase_if(out, [&](std::uint32_t id) { return memory.shaken.count(id) > 0; });
  for (const auto& box : w.world.boxes)
    if (behind_robot(box, w.q) && std::find(out.begin(), out.end(), box.id) == out.end())
      out.push_back(box.id);
  return out;
}

// One action being run: its backend, memory and what it has cost so far.
class Run {
 public:
  Run(const sim::RobotModel& robot, const ActionOptions& o, Backend& backend, Memory& memory,
      const Reporter& reporter, sim::Action action)
      : robot_(robot),
        o_(o),
        g_(o.geometry),
        backend_(backend),
        memory_(memory),
        reporter_(reporter),
        action_(action),
        asker_(robot, o, backend) {}

  Outcome go() {
    Perceived w0 = observe();
    const sim::World start = w0.world;
    unloaded_at_start_ = w0.unloaded;
    if (!w0.held.empty()) {
      let_go();
      w0 = observe();
    }
    if (const auto riding = on_robot(w0);
        std::any_of(riding.begin(), riding.end(),
                    [&](std::uint32_t id) { return !memory_.shaken.count(id); })) {
      clear_robot(riding);
      memory_.shaken.insert(riding.begin(), riding.end());
      w0 = observe();
    }
    if (sim::kind(action_) == sim::ActionKind::kPick)
      pick(w0);
    else
      sweep(w0);
    drop_ahead();
    const Perceived end = observe();
    out_.boxes = end.unloaded - unloaded_at_start_;
    out_.shifted = boxes_shifted(start, end.world);
    if (end.sim_time_s > 0) out_.sim_time_s = end.sim_time_s;
    if (!out_.applicable) out_.exec_s = o_.not_applicable_s;
    out_.robot_time_s = out_.exec_s + out_.plan_model_s;
    if (out_.boxes > 0) {  // the world changed: worth another try
      memory_.ungripped.clear();
      memory_.unreached.clear();
    }
    return std::move(out_);
  }

 private:
  void note(const std::string& line) const {
    if (reporter_.note) reporter_.note(line);
  }

  void not_applicable(std::string why) {
    note("not applicable: " + why);
    out_.applicable = false;
    out_.why = std::move(why);
  }

  Perceived observe() {
    auto w = backend_.observe();
    if (!w) throw Aborted{w.error()};
    return std::move(*w);
  }

  // ---- Planning and execution ---------------------------------------------

  // What an attempt cost goes into the outcome; an error that ends the
  // action ends it here.
  Planned apply(Attempt a) {
    if (a.abort) throw Aborted{*a.abort};
    out_.queries.insert(out_.queries.end(), a.queries.begin(), a.queries.end());
    out_.plan_model_s += a.model_s;
    out_.plan_wall_s += a.wall_s;
    return std::move(a.plan);
  }

  // Any planning but the plan made ahead waits for it: the backend plans
  // one query at a time.
  Planned plan_once(PlanMode mode, const Perceived& w, const Goal& goal,
                    const std::vector<std::uint32_t>& leave_out) {
    drop_ahead();
    return apply(asker_.once(mode, w, goal, leave_out));
  }

  // A step's plan: the one made while the last motion ran when it was made
  // for this step, its query is the one this step asks, and the state
  // observed is the predicted one (the robot waits only for the modelled
  // planning that motion did not cover); otherwise planned from `w`.
  Planned plan_step(const Step& s, const Perceived& w, const std::vector<std::uint32_t>& ignored) {
    if (ahead_) {
      Ahead a = std::move(*ahead_);
      ahead_.reset();
      Attempt made = a.attempt.get();
      if (!made.abort && a.moved && same_query(a.step, s) && a.ignored == sorted(ignored) &&
          PlanAhead::same_state(a.predicted, w)) {
        ++out_.plans_ahead_used;
        const double hidden = std::min(made.model_s, a.overlap_s);
        out_.plan_hidden_s += hidden;
        made.model_s -= hidden;
        for (auto& q : made.queries) q.planned_ahead = true;
        return apply(std::move(made));
      }
    }
    return apply(asker_.goal(s.mode, w, s.goal, ignored));
  }

  // The state a motion from `w` to `q` is predicted to end in: the world as
  // it was, the boxes held carried by the plate.
  Perceived predict(const Perceived& w, const JointVector& q) const {
    Perceived p = w;
    p.q = q;
    const Eigen::Isometry3d carry = robot_.plate_pose(q) * robot_.plate_pose(w.q).inverse();
    for (auto& b : p.world.boxes)
      if (std::find(w.held.begin(), w.held.end(), b.id) != w.held.end()) b.pose = carry * b.pose;
    return p;
  }

  // Starts planning, on another thread, the first of `next` that has to
  // move from the state the motion `s` (from `w` along `points`) is
  // predicted to end in. Not after a release: what falls cannot be predicted.
  void plan_ahead(std::initializer_list<const Step*> next, const Step& s, const Perceived& w,
                  const std::vector<planning::TimedPoint>& points) {
    drop_ahead();
    if (!o_.plan_while_moving || points.empty() || s.before == Suction::kOff ||
        s.after == Suction::kOff)
      return;
    const Perceived predicted = predict(w, points.back().position);
    for (const Step* n : next) {
      if (already_there(*n, predicted)) continue;
      auto ignored = ignored_for(*n, predicted);
      auto attempt = std::async(std::launch::async, [asker = asker_, n = *n, predicted, ignored] {
        return asker.goal(n.mode, predicted, n.goal, ignored);
      });
      ahead_.emplace(Ahead{*n, sorted(std::move(ignored)), predicted, std::move(attempt)});
      ++out_.plans_ahead;
      return;
    }
  }

  // A plan made ahead that no step took: waited for (the backend plans one
  // query at a time), then dropped.
  void drop_ahead() {
    if (!ahead_) return;
    ahead_->attempt.wait();
    ahead_.reset();
  }

  // Runs a trajectory; the outcome, or nullopt when the robot refused it.
  std::optional<Executed> execute(std::vector<planning::TimedPoint> points, Suction before,
                                  Suction after, const std::vector<bool>& cups_open = {}) {
    // A robot goes straight on to its next move; only a grip or a release
    // waits for what it moved to come to rest.
    Motion m;
    m.settle_s = before != Suction::kKeep || after != Suction::kKeep ? o_.settle_s : 0.0;
    // A uniform time scaling: the same path, accelerations divided by its square.
    for (auto& p : points) {
      p.time_s *= time_scale_;
      p.velocity /= time_scale_;
    }
    // A motion other than the one a plan was made ahead during: that plan's
    // predicted state will not be seen.
    if (ahead_ && ahead_->moved) drop_ahead();
    m.points = std::move(points);
    m.before = before;
    m.after = after;
    m.cups_open = cups_open;
    auto r = backend_.execute(m);
    if (!r) {
      if (ends_the_action(r.error())) throw Aborted{r.error()};
      note("execute: " + r.error().message);
      return std::nullopt;
    }
    if (r->stalled)
      note(fmt::format(
          "the base stalled {:.1f} s into the move: the boxes pushed back with {:.0f} N",
          r->stall_after_s, r->stall_force));
    const double duration = (m.points.empty() ? 0.0 : m.points.back().time_s) + m.settle_s;
    // A box the belt carries out after the robot stopped is counted by the
    // time the robot goes on.
    for (double t : r->unloaded_after_s)
      out_.unloaded_at_s.push_back(out_.exec_s + out_.plan_model_s + std::clamp(t, 0.0, duration));
    out_.exec_s += duration;
    out_.robot_trailer_contacts += r->robot_trailer_contacts;
    if (r->sim_time_s > 0) out_.sim_time_s = r->sim_time_s;
    for (const auto& e : r->suction) {
      note(fmt::format("box {} {}: the cups had to hold {:.0f} N, can hold {:.0f} N", e.box_id,
                       e.kind == sim::SuctionEvent::Kind::kDropped ? "dropped" : "not gripped",
                       e.load, e.capacity));
    }
    return std::move(*r);
  }

  bool step(const std::string& what, PlanMode mode, const Goal& goal, Suction before, Suction after,
            const std::vector<std::uint32_t>& leave_out = {},
            const std::vector<bool>& cups_open = {}) {
    return step(Step{what, mode, goal, before, after, leave_out, cups_open});
  }

  // Whether `s` has nothing to do from `w`: its joints are there, and it
  // neither grips nor releases.
  static bool already_there(const Step& s, const Perceived& w) {
    if (s.goal.pose || s.goal.joints.empty() || s.before != Suction::kKeep ||
        s.after != Suction::kKeep)
      return false;
    for (auto [j, v] : s.goal.joints)
      if (!(std::abs(w.q[j] - v) < 0.01)) return false;
    return true;
  }

  // The boxes a step's planning leaves out in state `w`.
  std::vector<std::uint32_t> ignored_for(const Step& s, const Perceived& w) const {
    // Boxes lying on the robot or on its load ride along with it (or fall
    // off it): they are not obstacles to its moves, nor, to nose and base
    // moves, are those the nose pushes.
    // The planner only tests membership: a box named twice does no harm.
    std::vector<std::uint32_t> ignored = s.leave_out;
    const auto riding = on_robot(w);
    ignored.insert(ignored.end(), riding.begin(), riding.end());
    const auto on_load = boxes_on_load(w.world, w.held);
    ignored.insert(ignored.end(), on_load.begin(), on_load.end());
    if (s.mode == PlanMode::kNose || s.mode == PlanMode::kBaseLine) {
      const auto pushed = boxes_on_nose(w);
      ignored.insert(ignored.end(), pushed.begin(), pushed.end());
    }
    // What lies behind the robot (fallen beside or behind the base) does not
    // keep the base from backing up: its rear pushes it towards the door, as
    // hard as the drive can (B2 s2, s4: a box beside the base's rear end
    // refused every move back).
    if (s.mode == PlanMode::kBaseLine) {
      for (const auto& box : w.world.boxes)
        if (behind_robot(box, w.q)) ignored.push_back(box.id);
    }
    // A box against the base is no obstacle to moves the base makes along
    // the trailer when it lies against its flank, in a side lane (the flank
    // slides past it), nor to moves that leave the base where it stands when
    // it lies behind the front edge (nothing else goes there). A2 s9: a box
    // the belt dropped beside the base refused every move ("start in
    // collision: base_link - box 18").
    const bool base_moves = s.mode == PlanMode::kBaseLine || s.mode == PlanMode::kArmBase;
    const auto against_base = boxes_touching(w.world, robot_, w.q, {"base_link"});
    for (const auto& box : w.world.boxes) {
      if (std::find(against_base.begin(), against_base.end(), box.id) == against_base.end())
        continue;
      const sim::Bounds b = sim::bounds(box);
      const bool flank =
          b.y0 > g_.base_half_width - kFlankOverlap || b.y1 < -g_.base_half_width + kFlankOverlap;
      if (base_moves ? flank : behind_robot(box, w.q)) ignored.push_back(box.id);
    }
    return ignored;
  }

  // One step: observe, plan (asking for M6 when the planner reports a start
  // in collision it did not leave), execute. False when it could not be done.
  // `next`: the steps that may follow it, in order; while it moves, the
  // first of them that has to move is planned (plan_ahead).
  bool step(const Step& s, std::initializer_list<const Step*> next = {}) {
    if (reporter_.progress) reporter_.progress(s.what);
    Perceived w = observe();
    if (already_there(s, w)) return true;
    const auto ignored = ignored_for(s, w);
    Planned p = plan_step(s, w, ignored);
    if (!p.ok && p.status == PlanStatus::kStartInvalid) {
      Planned escape = plan_once(PlanMode::kEscape, w, {}, {});
      if (escape.ok && execute(std::move(escape.points), Suction::kKeep, Suction::kKeep)) {
        w = observe();
        p = plan_step(s, w, ignored);
      }
    }
    if (!p.ok) {
      note(fmt::format("{} not planned: {}", s.what, p.message));
      step_failure_ = s.what + " not planned: " + p.message;
      return false;
    }
    plan_ahead(next, s, w, p.points);
    const double exec_before = out_.exec_s;
    auto done = execute(std::move(p.points), s.before, s.after, s.cups_open);
    if (ahead_) {
      ahead_->moved = done.has_value();
      ahead_->overlap_s = out_.exec_s - exec_before;
    }
    if (!done) {
      step_failure_ = s.what + " not executed";
      return false;
    }
    last_held_ = done->held;
    // Backing away, the base is held only by what the nose pins to the
    // floor (a box wedged under it): lifted, the nose lets go, and the base
    // tries once more.
    if (done->stalled && s.mode == PlanMode::kBaseLine && !freeing_ && backwards(s.goal, w)) {
      freeing_ = true;
      const bool freed =
          step("nose up to free the base", PlanMode::kNose, nose({g_.nose_lift_max, 0.0, 0.0}),
               Suction::kKeep, Suction::kKeep) &&
          step(Step{s.what, s.mode, s.goal, Suction::kKeep, Suction::kKeep, s.leave_out});
      freeing_ = false;
      return freed;
    }
    return true;
  }

  static bool backwards(const Goal& goal, const Perceived& from) {
    for (auto [j, v] : goal.joints)
      if (j == sim::kBaseX) return v < from.q[sim::kBaseX];
    return false;
  }

  // Boxes touching the conveyor or the scoop.
  std::vector<std::uint32_t> boxes_on_nose(const Perceived& w) const {
    return boxes_touching(w.world, robot_, w.q, {"nose_conveyor", "nose_scoop"});
  }

  std::vector<std::uint32_t> on_robot(const Perceived& w) const {
    return boxes_on_robot(w.world, robot_, w.q, w.held);
  }
  std::vector<std::uint32_t> set_aside(const Perceived& w, const Memory& memory) const {
    return actions::set_aside(w, memory, robot_);
  }

  // Boxes lying on the robot (fallen onto the arm, or onto the nose and not
  // carried off) hide what is in front and keep its moves from being
  // planned: they are shaken off first. The arm folds, so that what lies on
  // it falls; the nose tips its scoop up, so that what lies on it slides
  // onto the belt, and goes home.
  void clear_robot(const std::vector<std::uint32_t>& riding) {
    note(fmt::format("{} on the robot: shaking {} off", fmt::join(riding, ", "),
                     riding.size() == 1 ? "it" : "them"));
    step("arm clear", PlanMode::kArm, arm_clear(), Suction::kKeep, Suction::kKeep);
    step("nose up", PlanMode::kNose, nose(o_.nose_shake), Suction::kKeep, Suction::kKeep);
    step("nose home", PlanMode::kNose, nose(o_.nose_home), Suction::kKeep, Suction::kKeep);
  }

  static Goal joints(std::initializer_list<std::pair<int, double>> j) {
    return Goal{j, std::nullopt, {}};
  }
  static Goal nose(const std::array<double, 3>& n, double lift = 0.0) {
    return Goal{
        {{sim::kNose1, n[0] + lift}, {sim::kNose2, n[1]}, {sim::kNose3, n[2]}}, std::nullopt, {}};
  }
  Goal arm_clear() const {
    const auto& a = o_.arm_clear;
    return joints({{sim::kArm1, a[0]}, {sim::kArm2, a[1]}, {sim::kArm3, a[2]}, {sim::kArm4, a[3]}});
  }
  static Goal pose(const sim::PlateTarget& t, std::vector<sim::PlateTarget> then = {}) {
    return Goal{{}, t, std::move(then)};
  }

  // ---- Pick ----------------------------------------------------------------

  void pick(const Perceived& seen) {
    retry_where_a_neighbour_left(seen.world);
    Perceived w0 = seen;
    w0.world = without(seen.world, set_aside(seen, memory_));
    const auto scene = sim::analyse(w0.world, o_.observation);
    std::unordered_set<std::uint32_t> failed;
    std::size_t given_up = 0;
    for (const auto& [id, h] : memory_.grips) {
      failed.insert(id);
      given_up += h.given_up ? 1 : 0;
    }
    // Boxes given up, and those no motion could be planned to since the last
    // box left (the same queries would fail the same way, each at the cost
    // of a search's whole budget), still come out of pick_candidates: ask
    // for as many more.
    std::vector<PickCandidate> candidates;
    std::vector<PickRejection> rejected;
    for (auto& c : pick_candidates(w0.world, scene, action_, o_.observation, robot_, g_, w0.q,
                                   o_.pick_candidates + given_up + memory_.unreached.size(), failed,
                                   &rejected)) {
      if (const auto u = memory_.unreached.find(c.box); u != memory_.unreached.end())
        rejected.push_back({c.box, "not planned since the last box left: " + u->second});
      else if (candidates.size() < o_.pick_candidates && worth_another_grip(c, w0.world))
        candidates.push_back(std::move(c));
    }
    // A box the cups did not hold is tried again only after the others.
    std::stable_partition(candidates.begin(), candidates.end(),
                          [&](const PickCandidate& c) { return !memory_.ungripped.count(c.box); });
    if (candidates.empty()) {
      // The first few boxes of the region, and what keeps each in place.
      std::string why;
      for (std::size_t k = 0; k < std::min<std::size_t>(rejected.size(), 3); ++k)
        why += fmt::format("{} {}: {}", k == 0 ? ":" : ";", rejected[k].box, rejected[k].why);
      if (rejected.size() > 3) why += fmt::format("; {} more", rejected.size() - 3);
      not_applicable(fmt::format("no box {} {} in front can be picked{}",
                                 sim::to_string(sim::height(action_)),
                                 sim::to_string(sim::side(action_)), why));
      return;
    }
    const PickCandidate* chosen = nullptr;
    bool delivered = false;
    for (const auto& c : candidates) {
      // Nose down before anything else in reach of the boxes moves; a pile in
      // front may leave only a lifted nose possible. While each motion runs,
      // the next one is planned: the pre-grasp (the long search) while the
      // nose goes down, or while the base drives when the nose is down
      // already.
      const Step to_pick{"base to pick point", PlanMode::kBaseLine,
                         joints({{sim::kBaseX, c.base_x}})};
      const Step down{"nose down", PlanMode::kNose, nose(o_.nose_down)};
      const Step down_lifted{"nose down (lifted)", PlanMode::kNose, nose(o_.nose_down, 0.15)};
      // From the arm left over the belt by the last delivery, a pre-grasp in
      // a far corner can be out of the search's budget; from the folded arm
      // it is a shorter search.
      const Goal to_pregrasp = pose(c.pregrasp, {c.grasp, c.lift, c.retract});
      const Step pregrasp{"pre-grasp",    PlanMode::kArmBase, to_pregrasp,
                          Suction::kKeep, Suction::kOn,       {},
                          c.cups_open};
      const Step fold{"arm clear", PlanMode::kArm, arm_clear()};
      const Step pregrasp_folded{"pre-grasp (arm folded)",
                                 PlanMode::kArmBase,
                                 to_pregrasp,
                                 Suction::kKeep,
                                 Suction::kOn,
                                 {},
                                 c.cups_open};
      // The plate ends touching the box (a settled box may lean a little).
      const Step approach{
          "approach", PlanMode::kArmCartesian, pose(c.grasp), Suction::kKeep, Suction::kOn, c.boxes,
          c.cups_open};
      if (!step(to_pick, {&down, &pregrasp})) {
        memory_.unreached[c.box] = step_failure_;
        continue;
      }
      if (!step(down, {&pregrasp}) && !step(down_lifted, {&pregrasp})) {
        memory_.unreached[c.box] = step_failure_;
        continue;
      }
      if (!step(pregrasp, {&approach}) &&
          !(step(fold, {&pregrasp_folded}) && step(pregrasp_folded, {&approach}))) {
        memory_.unreached[c.box] = step_failure_;
        continue;
      }
      if (!step(approach)) {
        memory_.unreached[c.box] = step_failure_;
        continue;
      }
      chosen = &c;
      break;
    }
    if (chosen != nullptr) {
      const bool gripped = !last_held_.empty();
      if (!gripped) {
        out_.failed_grasp = true;
        memory_.ungripped.insert(chosen->boxes.begin(), chosen->boxes.end());
        note(fmt::format("grasp of box {} failed (nothing held)", chosen->box));
      }
      // A box dropped before is carried slower: half the speed, a quarter of
      // the acceleration, for each drop.
      const auto history = memory_.grips.find(chosen->box);
      const int drops = history == memory_.grips.end() ? 0 : history->second.drops;
      const double scale = std::pow(2.0, drops);
      if (history != memory_.grips.end())
        note(
            fmt::format("box {} again (attempt {} of {}): {} cups{}", chosen->box,
                        history->second.failures + 1, o_.grip_attempts, chosen->cups,
                        drops > 0 ? fmt::format(", carried at 1/{:.0f} of the speed", scale) : ""));
      const Slowed slowed(time_scale_, scale);
      auto leaning = leaning_on(observe().world, chosen->boxes);
      leaning.insert(leaning.end(), chosen->riders.begin(), chosen->riders.end());
      const Step retract{"retract",      PlanMode::kArmCartesian, pose(chosen->retract),
                         Suction::kKeep, Suction::kKeep,          leaning};
      step(Step{"lift", PlanMode::kArmCartesian, pose(chosen->lift), Suction::kKeep, Suction::kKeep,
                leaning},
           {&retract});
      const bool out = step(retract);
      if (!out) {
        const std::string why = "not pulled out: " + step_failure_;
        // Still in the wall: no drop-off can be planned from here. Set the
        // box down where it was and withdraw; it is tried after the others.
        step("put back", PlanMode::kArmCartesian, pose(chosen->grasp), Suction::kKeep,
             Suction::kOff, chosen->boxes);
        step("withdraw", PlanMode::kArmCartesian, pose(chosen->pregrasp), Suction::kKeep,
             Suction::kKeep, chosen->boxes);
        memory_.ungripped.insert(chosen->boxes.begin(), chosen->boxes.end());
        // The same pull would fail the same way: it counts as an attempt
        // (after grip_attempts the box is given up), and the next one takes
        // the box alone.
        for (auto id : chosen->boxes) {
          auto& h = memory_.grips[id];
          ++h.failures;
          h.last = why;
        }
      }
      const Perceived w = observe();
      if (!w.held.empty() && last_held_.empty()) out_.failed_grasp = false;
      if (!gripped && w.held.empty()) grip_failed(*chosen, false, "not held after the approach");
      if (out && w.held.empty() && gripped) {
        out_.failed_grasp = true;
        ++out_.drops;
        note(fmt::format("box {} dropped while retracting", chosen->box));
        grip_failed(*chosen, true, "dropped while lifted or retracted");
      }
      if (!w.held.empty()) {
        const Delivery d = drop_off(w);
        delivered = d == Delivery::kDelivered;
        if (d == Delivery::kLost) {
          out_.failed_grasp = true;
          ++out_.drops;
          grip_failed(*chosen, true, "dropped while carried to the nose");
        }
        if (d == Delivery::kNoPlace) let_go();
      }
    }
    // After a delivered box the robot stays as it is, nose down and the arm
    // over the belt: the next pick starts from there (its nose-down step is
    // then already done). Otherwise it stows and backs away, so that the next
    // action starts from a known, clear pose.
    if (delivered) return;
    stow();
    const Perceived w = observe();
    step("base back", PlanMode::kBaseLine, joints({{sim::kBaseX, w.q[sim::kBaseX] - o_.retreat_m}}),
         Suction::kKeep, Suction::kKeep);
  }

  // A grip that failed: the next attempt at that box must change what failed
  // (more cups on its face; after a drop, a slower carry too).
  // Every box of the group is remembered: taken with others, its cups
  // shared the pump, so any pose that takes it alone covers more (cups 0).
  void grip_failed(const PickCandidate& c, bool dropped, const char* what) {
    for (std::size_t k = 0; k < c.boxes.size(); ++k) {
      auto& h = memory_.grips[c.boxes[k]];
      const int cups = c.boxes.size() > 1 ? 0 : c.box_cups[k];
      h.last = fmt::format(
          "{} ({} cups{}{})", what, c.box_cups[k],
          c.boxes.size() > 1 ? fmt::format(", with {} other boxes", c.boxes.size() - 1) : "",
          h.drops > 0 ? fmt::format(", 1/{:.0f} speed", std::pow(2.0, h.drops)) : "");
      ++h.failures;
      h.drops += dropped ? 1 : 0;
      h.cups = cups;
    }
  }

  // Whether a box whose grip failed before is worth another attempt from
  // this candidate; gives it up when not: after grip_attempts failures, or
  // when the cups refused its weight and no plate pose covers more of them.
  bool worth_another_grip(const PickCandidate& c, const sim::World& world) {
    const auto it = memory_.grips.find(c.box);
    if (it == memory_.grips.end()) return true;
    GripHistory& h = it->second;
    if (h.given_up) return false;
    if (h.failures >= o_.grip_attempts)
      h.why = fmt::format("{} grips failed, the last {}", h.failures, h.last);
    else if (h.drops == 0 && c.cups <= h.cups)
      h.why = fmt::format("{}, and no plate pose covers more cups", h.last);
    else
      return true;
    h.given_up = true;
    h.neighbours = neighbours_of(world, c.box);
    note(fmt::format("box {} given up: {}", c.box, h.why));
    return false;
  }

  // The boxes within kNear of a box's bounds.
  static std::set<std::uint32_t> neighbours_of(const sim::World& world, std::uint32_t id) {
    constexpr double kNear = 0.3;  // m
    const auto it = std::find_if(world.boxes.begin(), world.boxes.end(),
                                 [&](const sim::Box& b) { return b.id == id; });
    std::set<std::uint32_t> out;
    if (it == world.boxes.end()) return out;
    const sim::Bounds a = sim::bounds(*it);
    for (const auto& box : world.boxes)
      if (box.id != id && sim::within(a, sim::bounds(box), kNear)) out.insert(box.id);
    return out;
  }

  void retry_where_a_neighbour_left(const sim::World& world) {
    std::unordered_set<std::uint32_t> present;
    for (const auto& b : world.boxes) present.insert(b.id);
    std::erase_if(memory_.grips, [&](const auto& entry) {
      const GripHistory& h = entry.second;
      const bool retry =
          h.given_up && std::any_of(h.neighbours.begin(), h.neighbours.end(),
                                    [&](std::uint32_t n) { return !present.count(n); });
      if (retry) note(fmt::format("box {} tried afresh: a box beside it has left", entry.first));
      return retry;
    });
  }

  // A load the plate could not bring to the nose is let go where it is (it
  // falls onto the nose or the floor in front): held on, it would ride into
  // every later action.
  void let_go() {
    const Perceived w = observe();
    if (w.held.empty()) return;
    note(fmt::format("letting go of {}", fmt::join(w.held, ", ")));
    execute({}, Suction::kKeep, Suction::kOff);
  }

  // The folded arm leaves the belt free, and the nose room to rise.
  void stow() {
    const Step home{"nose home", PlanMode::kNose, nose(o_.nose_home)};
    step(Step{"arm clear", PlanMode::kArm, arm_clear()}, {&home});
    step(home);
  }

  // Releases what the plate holds over the nose's conveyor: kNoPlace when no
  // drop-off place could be reached, kLost when the load fell on the way.
  Delivery drop_off(const Perceived& w) {
    // Room for the arm to swing the box down to the nose: back away from
    // the structure first.
    step("back off", PlanMode::kBaseLine,
         joints({{sim::kBaseX, w.q[sim::kBaseX] - o_.dropoff_backoff_m}}), Suction::kKeep,
         Suction::kKeep);
    // From a high pick the elbow is up near the ceiling, and folding the arm
    // straight towards the nose would raise it further: lower the load
    // first, on a straight line.
    {
      const Perceived now = observe();
      const sim::PlateTarget p = robot_.plate_target(now.q);
      if (p.position.z() > o_.carry_height_m)
        step("lower", PlanMode::kArmCartesian,
             pose({{p.position.x(), p.position.y(), o_.carry_height_m}, p.yaw}), Suction::kKeep,
             Suction::kKeep);
    }
    // A place the arm reaches may still fold it into itself: try the next.
    const Perceived at = observe();
    if (at.held.empty()) {
      note("the load fell while carried to the nose");
      return Delivery::kLost;
    }
    for (const auto& drop :
         dropoff_targets(at.world, at.held, robot_, g_, at.q, o_.pick_candidates)) {
      if (step("drop-off", PlanMode::kArm, pose(drop), Suction::kKeep, Suction::kOff))
        return Delivery::kDelivered;
    }
    note("no drop-off pose could be planned");
    return Delivery::kNoPlace;
  }

  // ---- Sweep ---------------------------------------------------------------

  void sweep(const Perceived& seen) {
    Perceived w0 = seen;
    w0.world = without(seen.world, set_aside(seen, memory_));
    const auto scene = sim::analyse(w0.world, o_.observation);
    const auto plan = sweep_plan(w0.world, scene, action_, g_, o_.nose_sweep[2]);
    if (!plan && sim::height(action_) == sim::Height::kLow && scene.front_pile.empty() &&
        scene.first_wall.empty()) {
      std::optional<sim::Bounds> nearest_behind;
      for (const auto& b : seen.world.boxes) {
        const sim::Bounds bb = sim::bounds(b);
        if (behind_robot(b, seen.q) && (!nearest_behind || bb.x0 < nearest_behind->x0))
          nearest_behind = bb;
      }
      if (nearest_behind) {
        back_out(*nearest_behind);
        return;
      }
    }
    if (!plan) {
      not_applicable(
          fmt::format("nothing in front for a {} sweep", sim::to_string(sim::height(action_))));
      return;
    }
    // A pick may have left the arm over the belt: fold it before the scoop
    // brings boxes up.
    const Step approach{"approach", PlanMode::kBaseLine,
                        joints({{sim::kBaseX, plan->start_base_x}})};
    const Step to_sweep{"nose to sweep", PlanMode::kNose, nose(o_.nose_sweep, plan->lift)};
    step(Step{"arm clear", PlanMode::kArm, arm_clear()}, {&approach, &to_sweep});
    if (step(approach, {&to_sweep}) && step(to_sweep)) {
      // The scoop goes under (or into) what it sweeps: the planner must not
      // treat those boxes as obstacles. A drive the boxes stall stops there.
      step("sweep forward", PlanMode::kBaseLine, joints({{sim::kBaseX, plan->end_base_x}}),
           Suction::kKeep, Suction::kKeep, plan->swept);
      if (plan->lower_at_end)
        step("pull down", PlanMode::kNose, nose(o_.nose_sweep), Suction::kKeep, Suction::kKeep,
             plan->swept);
      // What was scooped may still lie on the scoop: it rides along.
      step("back up", PlanMode::kBaseLine, joints({{sim::kBaseX, plan->start_base_x}}),
           Suction::kKeep, Suction::kKeep, plan->swept);
    }
    step("nose home", PlanMode::kNose, nose(o_.nose_home), Suction::kKeep, Suction::kKeep,
         plan->swept);
  }

  // Nothing left in front, and boxes behind the robot (fallen beside or
  // behind the base, `nearest` the nearest to the door): the base backs out
  // to the door. Its rear pushes what lies behind it out of the trailer, and
  // what lay beside it is in front of it again. A box in a side lane against
  // the nose's rear edge is pushed ahead of it instead: with such a box
  // within the base's length of the door, the base backs out until the box
  // would be past the door (backed out only to where it stood, A2 s1 pushed
  // it by its depth each time and stopped with it 22 cm inside the door).
  void back_out(const sim::Bounds& nearest) {
    note("nothing in front, boxes behind: backing out to the door");
    step("arm clear", PlanMode::kArm, arm_clear(), Suction::kKeep, Suction::kKeep);
    step("nose home", PlanMode::kNose, nose(o_.nose_home), Suction::kKeep, Suction::kKeep);
    const double to = nearest.x0 < g_.base_length ? -(nearest.x1 - nearest.x0) - kBackOutMargin
                                                  : g_.base_length - kBackOutMargin;
    step("back out", PlanMode::kBaseLine, joints({{sim::kBaseX, to}}), Suction::kKeep,
         Suction::kKeep);
  }
  static constexpr double kBackOutMargin = 0.03;  // m past the door, or past the box
  // m a box against the base's flank may reach in under its side (contact, tilt)
  static constexpr double kFlankOverlap = 0.02;

  const sim::RobotModel& robot_;
  const ActionOptions& o_;
  const Geometry& g_;
  Backend& backend_;
  Memory& memory_;
  const Reporter& reporter_;
  const sim::Action action_;
  Outcome out_;
  std::uint32_t unloaded_at_start_ = 0;
  std::vector<std::uint32_t> last_held_;
  std::string step_failure_;  // why the last step that failed did
  bool freeing_ = false;      // lifting the nose to free a stalled base
  double time_scale_ = 1.0;   // of the trajectories executed: > 1 carries a dropped box slower
  const Asker asker_;
  // Last: destroyed first, its thread joined while what it uses still lives.
  std::optional<Ahead> ahead_;
};

}  // namespace

ActionModel::ActionModel(const sim::RobotModel& robot, ActionOptions options)
    : robot_(&robot), options_(std::move(options)) {}

sim::SceneAnalysis ActionModel::scene(const Perceived& w, const Memory& memory) const {
  auto a = sim::analyse(without(w.world, set_aside(w, memory, *robot_)), options_.observation);
  return a.observation || w.world.boxes.empty() ? a : sim::analyse(w.world, options_.observation);
}

plr::Expected<Outcome> ActionModel::run(sim::Action action, Backend& backend, Memory& memory,
                                        const Reporter& reporter) const {
  try {
    return Run(*robot_, options_, backend, memory, reporter, action).go();
  } catch (const Aborted& a) {
    return a.error;
  }
}

}  // namespace plr::actions
