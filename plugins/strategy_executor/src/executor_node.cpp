// The strategy executor: walks strategies from their root, observing the
// world between actions, and turns each abstract action into planner queries
// (`plan`) and trajectories for the simulator (`sim/execute`). See
// docs/executor.md for the sequence of each action and the recovery rules.
#include <unistd.h>

#include <plr/messages.hpp>
#include <plr/node.hpp>
#include <plr/plugin.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <cstdio>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>
#include <set>
#include <thread>
#include <unordered_set>

#include "instantiate.hpp"
#include "plr/planning/plan_query.hpp"
#include "plr/sim/observation.hpp"
#include "plr/sim/render.hpp"
#include "plr/sim/robot_model.hpp"
#include "plr/sim/strategy.hpp"
#include "plr/sim/world_io.hpp"
#include "report.hpp"

namespace plr::executor {
namespace {

using namespace std::chrono_literals;
using Clock = std::chrono::steady_clock;
using msg::Suction;
using planning::PlanMode;

// Unwinds the worker when the node is deactivated.
struct Stopped {};
// The simulator's host went away (sim/* answered PLR_ERR_UNAVAILABLE).
struct SimulatorLost {
  std::string what;
};

double seconds_since(Clock::time_point t0) {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

struct Observed {
  Message<msg::WorldState> message;
  msg::WorldStateT state;
  sim::World world;
  sim::JointVector q = sim::JointVector::Zero();
  std::vector<std::uint32_t> held;
  std::uint32_t unloaded = 0;
};

// A goal for a sub-action: joint values for the mode's joints, or a plate
// pose. `then`: the straight plate moves that follow a pose goal; its IK
// solutions must carry the arm through them on one branch.
struct Goal {
  std::vector<std::pair<int, double>> joints;
  std::optional<sim::PlateTarget> pose;
  std::vector<sim::PlateTarget> then;
};

struct PlanResult {
  bool ok = false;
  std::string message;
  std::unique_ptr<msg::TrajectoryT> trajectory;
};

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

// A box whose grip failed in this run, and what the next attempt changes.
struct GripHistory {
  int failures = 0;
  int drops = 0;  // held, then lost while carried: the load, not the weight alone
  int cups = 0;   // cups the last failed grasp pose covered
  bool given_up = false;
  std::string last, why;  // the last failure; why no more attempts are made
};

// What one action cost, committed to the statistics only when it completes
// (an action interrupted by a simulator crash is repeated, not counted twice).
struct ActionRun {
  double plan_s = 0;
  double exec_s = 0;
  std::uint64_t contacts = 0;
  double sim_time_s = 0;
  bool failed_grasp = false;
  // When boxes left the trailer, in robot seconds after the action's start.
  std::vector<double> unloaded_at_s;
};

class ExecutorNode : public plr::Node {
 public:
  using Node::Node;

 protected:
  plr::Status on_configure() override {
    params().allow_only({"report_dir",
                         "env",
                         "seed",
                         "world_file",
                         "urdf",
                         "h_pile",
                         "wall_depth",
                         "min_pile_depth",
                         "pile_mid",
                         "pile_high",
                         "wall_mid",
                         "wall_high",
                         "plan_timeout_s",
                         "plan_expansions",
                         "plan_epsilons",
                         "execute_timeout_s",
                         "service_wait_s",
                         "retry_ms",
                         "max_idle_actions",
                         "max_actions",
                         "pick_candidates",
                         "grip_attempts",
                         "settle_s",
                         "nose_home",
                         "nose_down",
                         "nose_sweep",
                         "arm_clear",
                         "retreat_m",
                         "dropoff_backoff_m",
                         "carry_height_m",
                         "progress"});
    report_dir_ = params().get<std::string>("report_dir", "report");
    env_ = params().get<std::string>("env", "");
    seed_ = params().get<std::uint64_t>("seed", 1);
    world_file_ = params().get<std::string>("world_file", "");
    obs_.h_pile = params().get<double>("h_pile", obs_.h_pile);
    obs_.wall_depth = params().get<double>("wall_depth", obs_.wall_depth);
    obs_.min_pile_depth = params().get<double>("min_pile_depth", obs_.min_pile_depth);
    obs_.pile_mid = params().get<double>("pile_mid", obs_.pile_mid);
    obs_.pile_high = params().get<double>("pile_high", obs_.pile_high);
    obs_.wall_mid = params().get<double>("wall_mid", obs_.wall_mid);
    obs_.wall_high = params().get<double>("wall_high", obs_.wall_high);
    if (auto ok = obs_.check(); !ok) return ok;
    plan_timeout_s_ = params().get<double>("plan_timeout_s", 5.0);
    plan_expansions_ = params().get<std::uint64_t>("plan_expansions", plan_expansions_);
    plan_epsilons_ = params().get<std::vector<double>>("plan_epsilons", plan_epsilons_);
    for (double e : plan_epsilons_)
      if (!(e >= 1.0))
        return make_error(PLR_ERR_INVALID, "param 'plan_epsilons': each must be >= 1");
    execute_timeout_s_ = params().get<double>("execute_timeout_s", 300.0);
    service_wait_s_ = params().get<double>("service_wait_s", 60.0);
    retry_ = std::chrono::milliseconds(params().get<std::uint64_t>("retry_ms", 50));
    max_idle_ = params().get<std::uint64_t>("max_idle_actions", 6);
    max_actions_ = params().get<std::uint64_t>("max_actions", 0);
    max_candidates_ = params().get<std::uint64_t>("pick_candidates", 4);
    grip_attempts_ = params().get<std::uint64_t>("grip_attempts", grip_attempts_);
    settle_s_ = params().get<double>("settle_s", 0.3);
    retreat_m_ = params().get<double>("retreat_m", 0.3);
    dropoff_backoff_m_ = params().get<double>("dropoff_backoff_m", 0.5);
    carry_height_m_ = params().get<double>("carry_height_m", carry_height_m_);
    show_progress_ = params().get<bool>("progress", true);
    for (auto [key, target] :
         {std::pair{"nose_home", &nose_home_}, std::pair{"nose_down", &nose_down_},
          std::pair{"nose_sweep", &nose_sweep_}}) {
      *target = params().get<std::vector<double>>(key, *target);
      if (target->size() != 3)
        return make_error(PLR_ERR_INVALID,
                          std::string("param '") + key + "': expected 3 nose joint values");
    }
    arm_clear_ = params().get<std::vector<double>>("arm_clear", arm_clear_);
    if (arm_clear_.size() != 4)
      return make_error(PLR_ERR_INVALID, "param 'arm_clear': expected 4 arm joint values");
    if (!(plan_timeout_s_ > 0) || !(execute_timeout_s_ > 0) || !(service_wait_s_ >= 0))
      return make_error(PLR_ERR_INVALID, "param 'plan_timeout_s'/'execute_timeout_s': must be > 0");
    if (max_idle_ == 0)
      return make_error(PLR_ERR_INVALID, "param 'max_idle_actions': must be >= 1");
    if (max_candidates_ == 0)
      return make_error(PLR_ERR_INVALID, "param 'pick_candidates': must be >= 1");
    if (grip_attempts_ == 0)
      return make_error(PLR_ERR_INVALID, "param 'grip_attempts': must be >= 1");
    auto robot = sim::load_robot(params().get<std::string>("urdf", ""));
    if (!robot) return make_error(PLR_ERR_INVALID, "param 'urdf': " + robot.error().message);
    robot_ = std::move(*robot);
    auto status = ctx().advertise<msg::Statistics>("executor/status");
    if (!status) return status.error();
    status_ = *status;
    auto done = ctx().advertise<msg::PipelineDone>("pipeline/done");
    if (!done) return done.error();
    done_ = *done;
    tty_ = isatty(STDERR_FILENO) == 1;
    return {};
  }

  plr::Status on_activate() override {
    stop_ = false;
    stats_ = {};
    grips_.clear();
    unreached_.clear();
    worker_ = std::thread([this] { run(); });
    return {};
  }

  plr::Status on_deactivate() override {
    {
      std::lock_guard lock(m_);
      stop_ = true;
    }
    cv_.notify_all();
    if (worker_.joinable()) worker_.join();
    return {};
  }

 private:
  // ---- Bus helpers ---------------------------------------------------------

  void pause(std::chrono::nanoseconds d) {
    std::unique_lock lock(m_);
    if (cv_.wait_for(lock, d, [this] { return stop_.load(); })) throw Stopped{};
  }

  template <class Req, class Rep>
  Expected<Message<Rep>> call_once(const std::string& service,
                                   const flatbuffers::FlatBufferBuilder& fbb, double timeout_s) {
    auto f = ctx().call<Req, Rep>(service, fbb,
                                  std::chrono::duration_cast<std::chrono::nanoseconds>(
                                      std::chrono::duration<double>(timeout_s)));
    while (!f.wait_for(20ms)) {
      if (stop_) {
        f.cancel();
        (void)f.get();
        throw Stopped{};
      }
    }
    return f.get();
  }

  // Retries while the provider is unavailable: not started yet, or being
  // swapped. A swap is atomic in the kernel; this makes a query survive even
  // a gap, so none is lost.
  template <class Req, class Rep>
  Expected<Message<Rep>> call_retry(const std::string& service,
                                    const flatbuffers::FlatBufferBuilder& fbb, double timeout_s) {
    const auto t0 = Clock::now();
    for (;;) {
      auto r = call_once<Req, Rep>(service, fbb, timeout_s);
      if (r || r.error().code != PLR_ERR_UNAVAILABLE || seconds_since(t0) > service_wait_s_)
        return r;
      pause(retry_);
    }
  }

  Observed observe() {
    flatbuffers::FlatBufferBuilder fbb;
    fbb.Finish(msg::CreateObserveRequest(fbb, false));
    auto r = call_once<msg::ObserveRequest, msg::WorldState>("sim/observe", fbb, 30.0);
    if (!r) {
      if (r.error().code == PLR_ERR_UNAVAILABLE || r.error().code == PLR_ERR_TIMEOUT)
        throw SimulatorLost{"sim/observe: " + r.error().message};
      throw std::runtime_error("sim/observe: " + r.error().message);
    }
    Observed o;
    o.message = std::move(r.value());
    check_clock(static_cast<double>(o.message->stamp_ns()) * 1e-9, "sim/observe");
    o.message->UnPackTo(&o.state);
    o.world = sim::world_from_message(*o.message);
    if (o.state.robot && o.state.robot->positions.size() == sim::kNumJoints)
      for (int j = 0; j < sim::kNumJoints; ++j)
        o.q[j] = o.state.robot->positions[static_cast<std::size_t>(j)];
    o.held = o.state.held_box_ids;
    o.unloaded = o.state.boxes_unloaded;
    return o;
  }

  // A simulator host restarted between two calls resumes from its checkpoint,
  // with its clock set back: the same as a call it failed.
  void check_clock(double sim_time_s, const char* service) {
    if (sim_time_s + 1e-9 < sim_clock_s_) {
      const double seen = sim_clock_s_;
      sim_clock_s_ = -1.0;
      throw SimulatorLost{
          fmt::format("{}: the simulator's clock went back from {:.2f} s to {:.2f} s", service,
                      seen, sim_time_s)};
    }
    sim_clock_s_ = sim_time_s;
  }

  // Waits for the simulator to answer (at start, and after its host restarted).
  Observed wait_for_simulator() {
    const auto t0 = Clock::now();
    for (;;) {
      try {
        return observe();
      } catch (const SimulatorLost& lost) {
        if (seconds_since(t0) > service_wait_s_)
          throw std::runtime_error("simulator unavailable for " +
                                   fmt::format("{:.0f}", service_wait_s_) + " s: " + lost.what);
      }
      pause(200ms);
    }
  }

  // Empty when the simulator took or restored the checkpoint, else why not.
  std::string snapshot_or_restore(const char* service) {
    flatbuffers::FlatBufferBuilder fbb;
    fbb.Finish(msg::CreateSnapshotRequestDirect(fbb, "checkpoint"));
    auto r = call_retry<msg::SnapshotRequest, msg::SnapshotReply>(service, fbb, 60.0);
    if (!r) {
      if (r.error().code == PLR_ERR_UNAVAILABLE)
        throw SimulatorLost{std::string(service) + ": " + r.error().message};
      return r.error().message;
    }
    if (!r.value()->ok()) return r.value()->message() ? r.value()->message()->str() : "refused";
    return {};
  }

  // ---- Planning and execution ---------------------------------------------

  void count_query(PlanMode mode, const msg::PlanResponse* rep, double wall_s) {
    auto& ms = stats_.modes[static_cast<std::size_t>(mode)];
    ++ms.queries;
    if (rep == nullptr || rep->status() != msg::PlanStatus::Solved) ++ms.failures;
    const auto* st = rep ? rep->stats() : nullptr;
    ms.ms.add(st && st->planning_ms() > 0 ? st->planning_ms() : 1e3 * wall_s);
    if (st) {
      ms.expansions.add(static_cast<double>(st->expansions()));
      ms.max_expansions = std::max(ms.max_expansions, st->expansions());
    }
    if (st && st->m6_used() && mode != PlanMode::kEscape) {
      // The escape the planner ran first counts as an M6 query of its own.
      ++stats_.m6_implicit;
      auto& m6 = stats_.modes[static_cast<std::size_t>(PlanMode::kEscape)];
      ++m6.queries;
      if (st->escape_ms() > 0) m6.ms.add(st->escape_ms());
    }
  }

  PlanResult plan_once(PlanMode mode, const Observed& w, const Goal& goal,
                       const std::vector<std::uint32_t>& leave_out, ActionRun& run) {
    msg::PlanRequestT req;
    req.mode = static_cast<msg::PlanMode>(mode);
    req.start.assign(w.q.data(), w.q.data() + sim::kNumJoints);
    if (goal.pose) {
      const auto& t = *goal.pose;
      // The plate is vertical: its orientation is the yaw of its normal.
      const Eigen::Quaterniond q(Eigen::AngleAxisd(t.yaw, Eigen::Vector3d::UnitZ()));
      req.goal_pose =
          std::make_unique<msg::Pose>(msg::Vec3(t.position.x(), t.position.y(), t.position.z()),
                                      msg::Quat(q.x(), q.y(), q.z(), q.w()));
      req.has_goal_pose = true;
    } else if (mode != PlanMode::kEscape) {
      sim::JointVector g = w.q;
      for (auto [j, v] : goal.joints) g[j] = v;
      req.goal_joints.assign(g.data(), g.data() + sim::kNumJoints);
    }
    req.timeout_s = plan_timeout_s_;
    req.max_expansions = plan_expansions_;
    req.epsilons = plan_epsilons_;
    req.world = std::make_unique<msg::WorldStateT>(w.state);
    auto& boxes = req.world->boxes;
    boxes.erase(std::remove_if(boxes.begin(), boxes.end(),
                               [&](const msg::BoxState& b) {
                                 // A held box is part of the arm: the planner needs it.
                                 return std::find(leave_out.begin(), leave_out.end(), b.id()) !=
                                            leave_out.end() &&
                                        std::find(w.held.begin(), w.held.end(), b.id()) ==
                                            w.held.end();
                               }),
                boxes.end());
    req.held_box_ids = w.held;
    flatbuffers::FlatBufferBuilder fbb;
    fbb.Finish(msg::PlanRequest::Pack(fbb, &req));
    const auto t0 = Clock::now();
    auto r = call_retry<msg::PlanRequest, msg::PlanResponse>("plan", fbb, plan_timeout_s_ + 10.0);
    const double wall = seconds_since(t0);
    run.plan_s += wall;
    PlanResult out;
    if (!r) {
      count_query(mode, nullptr, wall);
      ++stats_.plan_calls_unanswered;
      out.message = "plan: " + r.error().message;
      return out;
    }
    const auto* rep = r.value().get();
    count_query(mode, rep, wall);
    ++stats_.planners[rep->planner() ? rep->planner()->str() : "?"];
    if (rep->status() != msg::PlanStatus::Solved || rep->trajectory() == nullptr ||
        rep->trajectory()->points() == nullptr || rep->trajectory()->points()->size() == 0) {
      out.message = std::string(msg::EnumNamePlanStatus(rep->status())) +
                    (rep->message() ? ": " + rep->message()->str() : "");
      out.ok = false;
      last_status_ = rep->status();
      return out;
    }
    out.ok = true;
    out.trajectory = std::unique_ptr<msg::TrajectoryT>(rep->trajectory()->UnPack());
    return out;
  }

  // Free-space arm moves (M1, M2) go to joint goals from the arm's closed-form
  // IK, nearest solution first: the lattice reaches a joint goal far sooner
  // than it snaps onto a pose. A goal in collision tries the next solution.
  PlanResult plan_goal(PlanMode mode, const Observed& w, const Goal& goal,
                       const std::vector<std::uint32_t>& leave_out, ActionRun& run) {
    if (!goal.pose || (mode != PlanMode::kArm && mode != PlanMode::kArmBase))
      return plan_once(mode, w, goal, leave_out, run);
    auto solutions = robot_.arm_ik(*goal.pose, w.q);
    std::erase_if(solutions,
                  [&](const sim::JointVector& q) { return !follows_lines(robot_, q, goal.then); });
    PlanResult p;
    p.message = goal.then.empty() ? "no arm IK solution for the goal pose"
                                  : "no arm IK solution for the goal pose from which the "
                                    "straight moves after it stay on one IK branch";
    for (std::size_t i = 0; i < solutions.size() && i < 3; ++i) {
      Goal g;
      for (int j : {sim::kArm1, sim::kArm2, sim::kArm3, sim::kArm4})
        g.joints.emplace_back(j, solutions[i][j]);
      p = plan_once(mode, w, g, leave_out, run);
      if (p.ok || last_status_ != msg::PlanStatus::GoalInvalid) break;
    }
    return p;
  }

  // Runs a trajectory; returns the outcome, or nullopt when the simulator refused it.
  std::optional<Message<msg::ExecuteOutcome>> execute(const msg::TrajectoryT& trajectory,
                                                      Suction before, Suction after,
                                                      ActionRun& run) {
    // A robot goes straight on to its next move; only a grip or a release
    // waits for what it moved to come to rest.
    const double settle_s = before != Suction::Keep || after != Suction::Keep ? settle_s_ : 0.0;
    msg::ExecuteRequestT req;
    req.trajectory = std::make_unique<msg::TrajectoryT>(trajectory);
    // A uniform time scaling: the same path, accelerations divided by its square.
    for (auto& p : req.trajectory->points) {
      p->time_s *= time_scale_;
      for (auto& v : p->velocities) v /= time_scale_;
    }
    req.suction_before = before;
    req.suction_after = after;
    req.conveyor = true;
    req.settle_s = settle_s;
    flatbuffers::FlatBufferBuilder fbb;
    fbb.Finish(msg::ExecuteRequest::Pack(fbb, &req));
    auto r =
        call_once<msg::ExecuteRequest, msg::ExecuteOutcome>("sim/execute", fbb, execute_timeout_s_);
    if (!r) {
      if (r.error().code == PLR_ERR_UNAVAILABLE)
        throw SimulatorLost{"sim/execute: " + r.error().message};
      log().warn("sim/execute: {}", r.error().message);
      return std::nullopt;
    }
    const auto& out = r.value();
    check_clock(out->sim_time_s(), "sim/execute");
    const auto& points = req.trajectory->points;
    const double duration = (points.empty() ? 0.0 : points.back()->time_s) + settle_s;
    // A box the belt carries out after the robot stopped is counted by the
    // time the robot goes on.
    if (const auto* after = out->unloaded_after_s())
      for (double t : *after)
        run.unloaded_at_s.push_back(run.plan_s + run.exec_s + std::clamp(t, 0.0, duration));
    run.exec_s += duration;
    run.contacts += out->robot_trailer_contacts();
    run.sim_time_s = out->sim_time_s();
    if (!out->ok()) {
      log().warn("sim/execute: {}", out->message() ? out->message()->str() : "not ok");
      return std::nullopt;
    }
    return r.value();
  }

  // One sub-action: observe, plan (escaping a start in collision with M6 when
  // the planner reports it), execute. False when it could not be done.
  bool step(const std::string& what, PlanMode mode, const Goal& goal, Suction before, Suction after,
            ActionRun& run, const std::vector<std::uint32_t>& leave_out = {}) {
    report_progress(what);
    Observed w = observe();
    if (!goal.pose && !goal.joints.empty()) {
      bool there = true;
      for (auto [j, v] : goal.joints) there = there && std::abs(w.q[j] - v) < 0.01;
      if (there && before == Suction::Keep && after == Suction::Keep) return true;
    }
    last_status_ = msg::PlanStatus::Solved;
    // Boxes lying on the nose ride along with nose and base moves (or are
    // carried off by the belt): they are not obstacles to them.
    std::vector<std::uint32_t> ignored = leave_out;
    if (mode == PlanMode::kNose || mode == PlanMode::kBaseLine) {
      for (auto id : boxes_on_nose(w))
        if (std::find(ignored.begin(), ignored.end(), id) == ignored.end()) ignored.push_back(id);
    }
    PlanResult p = plan_goal(mode, w, goal, ignored, run);
    if (!p.ok && last_status_ == msg::PlanStatus::StartInvalid) {
      // The planner did not escape by itself: ask for M6 explicitly, then retry.
      PlanResult escape = plan_once(PlanMode::kEscape, w, {}, {}, run);
      if (escape.ok && execute(*escape.trajectory, Suction::Keep, Suction::Keep, run)) {
        w = observe();
        p = plan_goal(mode, w, goal, ignored, run);
      }
    }
    if (!p.ok) {
      log().info("{}: {} not planned: {}", action_name_, what, p.message);
      step_failure_ = what + " not planned: " + p.message;
      return false;
    }
    log().debug("{}: {} ({} points, {:.2f} s)", action_name_, what, p.trajectory->points.size(),
                p.trajectory->points.empty() ? 0.0 : p.trajectory->points.back()->time_s);
    auto out = execute(*p.trajectory, before, after, run);
    if (!out) {
      step_failure_ = what + " not executed";
      return false;
    }
    last_held_ = (*out)->held_box_ids()
                     ? std::vector<std::uint32_t>((*out)->held_box_ids()->begin(),
                                                  (*out)->held_box_ids()->end())
                     : std::vector<std::uint32_t>{};
    return true;
  }

  // Boxes touching the conveyor or the scoop (within 2 cm of their shapes' bounds).
  std::vector<std::uint32_t> boxes_on_nose(const Observed& w) const {
    constexpr double kTouch = 0.02;
    std::vector<Eigen::Isometry3d> poses;
    robot_.forward_kinematics(w.q, poses);
    std::vector<sim::Bounds> nose;
    for (const char* name : {"nose_conveyor", "nose_scoop"}) {
      const int l = robot_.link_index(name);
      if (l < 0) continue;
      for (const auto& shape : robot_.links()[static_cast<std::size_t>(l)].shapes) {
        if (shape.type != sim::CollisionShape::Type::kBox) continue;
        const Eigen::Isometry3d pose = poses[static_cast<std::size_t>(l)] * shape.origin;
        const Eigen::Vector3d e = pose.linear().cwiseAbs() * (shape.size / 2);
        const Eigen::Vector3d lo = pose.translation() - e, hi = pose.translation() + e;
        nose.push_back({lo.x(), hi.x(), lo.y(), hi.y(), lo.z(), hi.z()});
      }
    }
    std::vector<std::uint32_t> out;
    for (const auto& box : w.world.boxes) {
      const auto b = sim::bounds(box);
      for (const auto& n : nose) {
        if (b.x0 < n.x1 + kTouch && n.x0 < b.x1 + kTouch && b.y0 < n.y1 + kTouch &&
            n.y0 < b.y1 + kTouch && b.z0 < n.z1 + kTouch && n.z0 < b.z1 + kTouch) {
          out.push_back(box.id);
          break;
        }
      }
    }
    return out;
  }

  Goal joints(std::initializer_list<std::pair<int, double>> j) { return Goal{j, std::nullopt, {}}; }
  Goal nose(const std::vector<double>& n, double lift = 0.0) {
    return Goal{
        {{sim::kNose1, n[0] + lift}, {sim::kNose2, n[1]}, {sim::kNose3, n[2]}}, std::nullopt, {}};
  }
  Goal arm_clear() {
    return joints({{sim::kArm1, arm_clear_[0]},
                   {sim::kArm2, arm_clear_[1]},
                   {sim::kArm3, arm_clear_[2]},
                   {sim::kArm4, arm_clear_[3]}});
  }
  Goal pose(const sim::PlateTarget& t, std::vector<sim::PlateTarget> then = {}) {
    return Goal{{}, t, std::move(then)};
  }

  // ---- Actions -------------------------------------------------------------

  void pick(sim::Action action, const Observed& w0, ActionRun& run) {
    const auto scene = sim::analyse(w0.world, obs_);
    std::unordered_set<std::uint32_t> failed;
    std::size_t given_up = 0;
    for (const auto& [id, h] : grips_) {
      failed.insert(id);
      given_up += h.given_up ? 1 : 0;
    }
    // Boxes given up still come out of pick_candidates: ask for as many more.
    std::vector<PickCandidate> candidates;
    for (auto& c : pick_candidates(w0.world, scene, action, obs_, robot_, geometry_, w0.q,
                                   max_candidates_ + given_up, failed))
      if (candidates.size() < max_candidates_ && worth_another_grip(c))
        candidates.push_back(std::move(c));
    // A box the cups did not hold is tried again only after the others.
    std::stable_partition(candidates.begin(), candidates.end(),
                          [&](const PickCandidate& c) { return !ungripped_.count(c.box); });
    if (candidates.empty()) {
      log().info("{}: no reachable pick point", action_name_);
      return;
    }
    const PickCandidate* chosen = nullptr;
    bool delivered = false;
    for (const auto& c : candidates) {
      // Nose down before anything else in reach of the boxes moves; a pile in
      // front may leave only a lifted nose possible.
      if (!step("base to pick point", PlanMode::kBaseLine, joints({{sim::kBaseX, c.base_x}}),
                Suction::Keep, Suction::Keep, run)) {
        unreached_[c.box] = step_failure_;
        continue;
      }
      if (!step("nose down", PlanMode::kNose, nose(nose_down_), Suction::Keep, Suction::Keep,
                run) &&
          !step("nose down (lifted)", PlanMode::kNose, nose(nose_down_, 0.15), Suction::Keep,
                Suction::Keep, run)) {
        unreached_[c.box] = step_failure_;
        continue;
      }
      log().debug("{}: box {}, plate at ({:.2f}, {:.2f}, {:.2f}) yaw {:.2f}, {} cups", action_name_,
                  c.box, c.grasp.position.x(), c.grasp.position.y(), c.grasp.position.z(),
                  c.grasp.yaw, c.cups);
      if (!step("pre-grasp", PlanMode::kArmBase, pose(c.pregrasp, {c.grasp, c.lift, c.retract}),
                Suction::Keep, Suction::On, run)) {
        unreached_[c.box] = step_failure_;
        continue;
      }
      // The plate ends touching the box (a settled box may lean a little).
      if (!step("approach", PlanMode::kArmCartesian, pose(c.grasp), Suction::Keep, Suction::On, run,
                {c.box})) {
        unreached_[c.box] = step_failure_;
        continue;
      }
      chosen = &c;
      break;
    }
    if (chosen != nullptr) {
      const bool gripped = !last_held_.empty();
      if (!gripped) {
        run.failed_grasp = true;
        ungripped_.insert(chosen->box);
        log().info("{}: grasp of box {} failed (nothing held)", action_name_, chosen->box);
      }
      // A box dropped before is carried slower: half the speed, a quarter of
      // the acceleration, for each drop.
      const auto history = grips_.find(chosen->box);
      const int drops = history == grips_.end() ? 0 : history->second.drops;
      const double scale = std::pow(2.0, drops);
      if (history != grips_.end())
        log().info("{}: box {} again (attempt {} of {}): {} cups{}", action_name_, chosen->box,
                   history->second.failures + 1, grip_attempts_, chosen->cups,
                   drops > 0 ? fmt::format(", carried at 1/{:.0f} of the speed", scale) : "");
      const Slowed slowed(time_scale_, scale);
      step("lift", PlanMode::kArmCartesian, pose(chosen->lift), Suction::Keep, Suction::Keep, run);
      const bool out = step("retract", PlanMode::kArmCartesian, pose(chosen->retract),
                            Suction::Keep, Suction::Keep, run);
      if (!out) {
        // Still in the wall: no drop-off can be planned from here. Set the
        // box down where it was and withdraw; it is tried after the others.
        step("put back", PlanMode::kArmCartesian, pose(chosen->grasp), Suction::Keep, Suction::Off,
             run, {chosen->box});
        step("withdraw", PlanMode::kArmCartesian, pose(chosen->pregrasp), Suction::Keep,
             Suction::Keep, run, {chosen->box});
        ungripped_.insert(chosen->box);
      }
      const Observed w = observe();
      if (!w.held.empty() && last_held_.empty()) run.failed_grasp = false;
      if (!gripped && w.held.empty()) grip_failed(*chosen, false, "not held after the approach");
      if (out && w.held.empty() && gripped) {
        run.failed_grasp = true;
        log().info("{}: box {} dropped while retracting", action_name_, chosen->box);
        grip_failed(*chosen, true, "dropped while lifted or retracted");
      }
      if (!w.held.empty()) {
        const Delivery d = drop_off(w, run);
        delivered = d == Delivery::kDelivered;
        if (d == Delivery::kLost) {
          run.failed_grasp = true;
          grip_failed(*chosen, true, "dropped while carried to the nose");
        }
      }
    }
    // After a delivered box the robot stays as it is, nose down and the arm
    // over the belt: the next pick starts from there (its nose-down step is
    // then already done). Otherwise it stows and backs away, so that the next
    // action starts from a known, clear pose.
    if (delivered) return;
    stow(run);
    const Observed w = observe();
    step("base back", PlanMode::kBaseLine, joints({{sim::kBaseX, w.q[sim::kBaseX] - retreat_m_}}),
         Suction::Keep, Suction::Keep, run);
  }

  // A grip that failed: the next attempt at that box must change what failed
  // (more cups on its face; after a drop, a slower carry too).
  void grip_failed(const PickCandidate& c, bool dropped, const char* what) {
    auto& h = grips_[c.box];
    h.last =
        fmt::format("{} ({} cups{})", what, c.cups,
                    h.drops > 0 ? fmt::format(", 1/{:.0f} speed", std::pow(2.0, h.drops)) : "");
    ++h.failures;
    h.drops += dropped ? 1 : 0;
    h.cups = c.cups;
  }

  // Whether a box whose grip failed before is worth another attempt from
  // this candidate; gives it up (for this run) when not: after grip_attempts
  // failures, or when the cups refused its weight and no plate pose covers
  // more of them.
  bool worth_another_grip(const PickCandidate& c) {
    const auto it = grips_.find(c.box);
    if (it == grips_.end()) return true;
    GripHistory& h = it->second;
    if (h.given_up) return false;
    if (h.failures >= static_cast<int>(grip_attempts_))
      h.why = fmt::format("{} grips failed, the last {}", h.failures, h.last);
    else if (h.drops == 0 && c.cups <= h.cups)
      h.why = fmt::format("{}, and no plate pose covers more cups", h.last);
    else
      return true;
    h.given_up = true;
    log().info("{}: box {} given up: {}", action_name_, c.box, h.why);
    return false;
  }

  // The folded arm leaves the belt free, and the nose room to rise.
  void stow(ActionRun& run) {
    step("arm clear", PlanMode::kArm, arm_clear(), Suction::Keep, Suction::Keep, run);
    step("nose home", PlanMode::kNose, nose(nose_home_), Suction::Keep, Suction::Keep, run);
  }

  enum class Delivery { kDelivered, kNoPlace, kLost };

  // Releases what the plate holds over the nose's conveyor: kNoPlace when no
  // drop-off place could be reached, kLost when the load fell on the way.
  Delivery drop_off(const Observed& w, ActionRun& run) {
    // Room for the arm to swing the box down to the nose: back away from
    // the structure first.
    step("back off", PlanMode::kBaseLine,
         joints({{sim::kBaseX, w.q[sim::kBaseX] - dropoff_backoff_m_}}), Suction::Keep,
         Suction::Keep, run);
    // From a high pick the elbow is up near the ceiling, and folding the arm
    // straight towards the nose would raise it further: lower the load
    // first, on a straight line.
    {
      const Observed now = observe();
      const sim::PlateTarget p = robot_.plate_target(now.q);
      if (p.position.z() > carry_height_m_)
        step("lower", PlanMode::kArmCartesian,
             pose({{p.position.x(), p.position.y(), carry_height_m_}, p.yaw}), Suction::Keep,
             Suction::Keep, run);
    }
    // A place the arm reaches may still fold it into itself: try the next.
    const Observed at = observe();
    if (at.held.empty()) {
      log().info("{}: the load fell while carried to the nose", action_name_);
      return Delivery::kLost;
    }
    for (const auto& drop :
         dropoff_targets(at.world, at.held, robot_, geometry_, at.q, max_candidates_)) {
      if (step("drop-off", PlanMode::kArm, pose(drop), Suction::Keep, Suction::Off, run))
        return Delivery::kDelivered;
    }
    log().warn("{}: no drop-off pose could be planned", action_name_);
    return Delivery::kNoPlace;
  }

  void sweep(sim::Action action, const Observed& w0, ActionRun& run) {
    const auto scene = sim::analyse(w0.world, obs_);
    const auto plan =
        sweep_plan(scene, action, geometry_, nose_sweep_[2], w0.q, w0.world.trailer.depth);
    if (!plan) {
      log().info("{}: no pile in front to sweep", action_name_);
      return;
    }
    // A pick may have left the arm over the belt: fold it before the scoop
    // brings boxes up.
    step("arm clear", PlanMode::kArm, arm_clear(), Suction::Keep, Suction::Keep, run);
    if (step("back up", PlanMode::kBaseLine, joints({{sim::kBaseX, plan->start_base_x}}),
             Suction::Keep, Suction::Keep, run) &&
        step("nose down", PlanMode::kNose, nose(nose_sweep_, plan->lift), Suction::Keep,
             Suction::Keep, run)) {
      // The scoop goes under the pile: the planner must not treat it as an obstacle.
      step("sweep forward", PlanMode::kBaseLine, joints({{sim::kBaseX, plan->end_base_x}}),
           Suction::Keep, Suction::Keep, run, plan->swept);
      // What was scooped may still lie on the scoop: it rides along.
      step("back up", PlanMode::kBaseLine, joints({{sim::kBaseX, plan->start_base_x}}),
           Suction::Keep, Suction::Keep, run, plan->swept);
    }
    step("nose home", PlanMode::kNose, nose(nose_home_), Suction::Keep, Suction::Keep, run,
         plan->swept);
  }

  // ---- The job -------------------------------------------------------------

  sim::Strategy ask_strategy(const Observed& w, sim::Observation observation) {
    const auto view = w.message.view();
    flatbuffers::FlatBufferBuilder fbb;
    const auto world = plr::create_nested(fbb, view.data, view.size);
    fbb.Finish(msg::CreateNextStrategyRequest(fbb, world, observation));
    auto r =
        call_retry<msg::NextStrategyRequest, msg::NextStrategyReply>("strategy/next", fbb, 30.0);
    if (!r) throw std::runtime_error("strategy/next: " + r.error().message);
    if (r.value()->strategy() == nullptr)
      throw std::runtime_error("strategy/next: reply without a strategy");
    ++stats_.strategies_asked;
    auto s = sim::from_message(*r.value()->strategy(), "strategy/next reply");
    log().info("strategy '{}' from {} ({} nodes) for {}", s.name,
               r.value()->source() ? r.value()->source()->str() : "?", s.nodes.size(),
               sim::to_string(observation));
    return s;
  }

  void checkpoint() {
    // A checkpoint not taken only costs a longer repeat after a crash.
    if (const auto why = snapshot_or_restore("sim/snapshot"); !why.empty())
      log().warn("sim/snapshot 'checkpoint' failed: {}", why);
    checkpoint_robot_time_ = stats_.robot_time_s;
    checkpoint_curve_ = stats_.curve.size();
  }

  void recover(const std::string& why) {
    log().warn("simulator lost ({}); waiting for it to restart", why);
    report_progress("waiting for the simulator");
    sim_clock_s_ = -1.0;  // the restart set it back
    wait_for_simulator();
    // Going on without it would unload a world that is not the trailer's.
    if (const auto why = snapshot_or_restore("sim/restore"); !why.empty())
      throw std::runtime_error("sim/restore 'checkpoint': " + why);
    sim_clock_s_ = -1.0;  // and so did the restore
    stats_.robot_time_s = checkpoint_robot_time_;
    stats_.curve.resize(checkpoint_curve_);
    ++stats_.recoveries;
    log().info("simulator back; restored 'checkpoint', repeating the interrupted action");
  }

  void run() {
    const auto t0 = Clock::now();
    try {
      job(t0);
      finish(true, t0);
    } catch (const Stopped&) {
      stats_.stop_reason = "stopped";
    } catch (const std::exception& e) {
      stats_.stop_reason = e.what();
      log().error("executor: {}", e.what());
      finish(false, t0);
    } catch (const SimulatorLost& lost) {
      stats_.stop_reason = "simulator lost: " + lost.what;
      log().error("executor: {}", stats_.stop_reason);
      finish(false, t0);
    }
  }

  void job(Clock::time_point t0) {
    // A simulator may hold no world before its first reset: reset first when
    // asked to (waiting for it to come up), observe only otherwise.
    if (!env_.empty() || !world_file_.empty()) {
      flatbuffers::FlatBufferBuilder fbb;
      fbb.Finish(msg::CreateResetRequestDirect(fbb, env_.c_str(), seed_, world_file_.c_str()));
      auto r = call_retry<msg::ResetRequest, msg::WorldState>("sim/reset", fbb, 120.0);
      if (!r) throw std::runtime_error("sim/reset: " + r.error().message);
    }
    Observed w = wait_for_simulator();
    stats_.boxes_total = static_cast<std::uint32_t>(w.world.boxes.size()) + w.unloaded;
    const std::uint32_t unloaded_at_start = w.unloaded;
    log().info("{} boxes in the trailer", stats_.boxes_total);
    checkpoint();

    sim::Strategy strategy;
    std::optional<std::uint32_t> node;
    // The action a lost simulator interrupted, done again once it is back
    // (a flag, not an optional: GCC 12 warns falsely on optional<enum> here).
    bool repeating = false;
    sim::Action repeat{};
    std::uint64_t idle = 0, actions = 0;
    for (;;) {
      try {
        w = observe();
      } catch (const SimulatorLost& lost) {
        recover(lost.what);
        continue;
      }
      stats_.boxes_unloaded = w.unloaded - unloaded_at_start;
      left_.clear();
      for (const auto& b : w.world.boxes) left_.push_back(b.id);
      if (w.world.boxes.empty()) {
        stats_.stop_reason = "trailer empty";
        break;
      }
      if (max_actions_ != 0 && actions >= max_actions_) {
        stats_.stop_reason = fmt::format("action limit ({})", max_actions_);
        break;
      }
      sim::Action action{};
      if (repeating) {
        action = repeat;
      } else {
        const auto observation = *sim::classify(w.world, obs_);
        if (const auto child = node ? strategy.next(*node, observation) : std::nullopt) {
          node = child;
          ++stats_.strategy_steps;
        } else {
          strategy = ask_strategy(w, observation);
          node = strategy.root;
        }
        action = strategy.nodes[*node].action;
      }
      action_name_ = fmt::format("#{} {}", actions + 1, sim::to_string(action));
      ActionRun run;
      try {
        repeat = action;
        repeating = true;
        if (sim::kind(action) == sim::ActionKind::kPick)
          pick(action, w, run);
        else
          sweep(action, w, run);
        w = observe();
        repeating = false;
      } catch (const SimulatorLost& lost) {
        recover(lost.what);
        continue;
      }
      ++actions;
      const std::uint32_t unloaded = w.unloaded - unloaded_at_start;
      const std::uint32_t gained =
          unloaded > stats_.boxes_unloaded ? unloaded - stats_.boxes_unloaded : 0;
      stats_.boxes_unloaded = unloaded;
      auto& as = sim::kind(action) == sim::ActionKind::kPick ? stats_.pick : stats_.sweep;
      ++as.executions;
      as.boxes += gained;
      as.plan_s.add(run.plan_s);
      as.exec_s.add(run.exec_s);
      const double action_start = stats_.robot_time_s;
      stats_.robot_time_s += run.plan_s + run.exec_s;
      stats_.robot_trailer_collisions += run.contacts;
      if (run.sim_time_s > 0) stats_.sim_time_s = run.sim_time_s;
      stats_.failed_grasps += run.failed_grasp ? 1 : 0;
      // The curve steps where each box left; the action's end has the count
      // the simulator's state says.
      std::sort(run.unloaded_at_s.begin(), run.unloaded_at_s.end());
      std::uint32_t count = stats_.boxes_unloaded - gained;
      for (double t : run.unloaded_at_s)
        if (count < stats_.boxes_unloaded)
          stats_.curve.push_back({std::min(action_start + t, stats_.robot_time_s), ++count});
      stats_.curve.push_back({stats_.robot_time_s, stats_.boxes_unloaded});
      stats_.wall_time_s = seconds_since(t0);
      report_progress(fmt::format("{}: +{} boxes", action_name_, gained), true);
      publish_status();
      idle = gained == 0 ? idle + 1 : 0;
      if (gained > 0) ungripped_.clear();  // the world changed: worth another try
      if (idle >= max_idle_) {
        stats_.stop_reason = fmt::format("no progress in {} actions", idle);
        break;
      }
      try {
        checkpoint();
      } catch (const SimulatorLost& lost) {
        recover(lost.what);
      }
    }
  }

  void finish(bool ok, Clock::time_point t0) {
    stats_.wall_time_s = seconds_since(t0);
    if (show_progress_ && tty_) std::fputs("\n", stderr);
    log().info("done: {} of {} boxes in {:.1f} s robot time ({:.1f} s wall): {}",
               stats_.boxes_unloaded, stats_.boxes_total, stats_.robot_time_s, stats_.wall_time_s,
               stats_.stop_reason);
    if (!left_.empty()) {
      std::string why;
      for (const auto id : left_) {
        if (const auto it = grips_.find(id); it != grips_.end() && it->second.given_up) {
          stats_.boxes_given_up[id] = it->second.why;
          why += fmt::format("; box {} given up: {}", id, it->second.why);
        } else if (const auto miss = unreached_.find(id); miss != unreached_.end()) {
          why += fmt::format("; box {}: its last pick stopped at {}", id, miss->second);
        }
      }
      log().info("left in the trailer: {} box{} ({}; the others no pick or sweep took){}",
                 left_.size(), left_.size() == 1 ? "" : "es", stats_.stop_reason, why);
    }
    std::string report_error;
    try {
      write_report();
    } catch (const std::exception& e) {
      report_error = e.what();
      log().error("report: {}", report_error);
    }
    publish_status();
    flatbuffers::FlatBufferBuilder fbb;
    const std::string reason =
        fmt::format("{}: {}/{} boxes unloaded{}", stats_.stop_reason, stats_.boxes_unloaded,
                    stats_.boxes_total, report_error.empty() ? "" : "; report: " + report_error);
    fbb.Finish(msg::CreatePipelineDoneDirect(fbb, ok && report_error.empty(), reason.c_str()));
    (void)done_.publish(fbb);
  }

  void write_report() {
    namespace fs = std::filesystem;
    const fs::path dir(report_dir_);
    std::error_code ec;
    fs::create_directories(dir, ec);
    if (ec) throw std::runtime_error(dir.string() + ": " + ec.message());
    auto write = [&](const std::string& name, const std::string& content) {
      if (const auto err = write_atomically(dir / name, content); !err.empty())
        throw std::runtime_error((dir / name).string() + ": " + err);
    };
    write("report.json", to_json(stats_).dump(2) + "\n");
    write("unloading.svg", curve_svg(stats_.curve, stats_.boxes_total,
                                     fmt::format("{}: {}/{} boxes unloaded", ctx().name(),
                                                 stats_.boxes_unloaded, stats_.boxes_total)));
    // The final scene, with the robot's links drawn over it.
    try {
      const Observed w = observe();
      sim::RenderOptions options;
      options.title = fmt::format("final scene: {} boxes left", w.world.boxes.size());
      std::vector<Eigen::Isometry3d> poses;
      robot_.forward_kinematics(w.q, poses);
      for (std::size_t i = 0; i < robot_.links().size(); ++i) {
        for (const auto& shape : robot_.links()[i].shapes) {
          sim::Overlay o;
          o.pose = poses[i] * shape.origin;
          switch (shape.type) {
            case sim::CollisionShape::Type::kBox:
              o.size = shape.size;
              break;
            case sim::CollisionShape::Type::kCylinder:
              o.size = {2 * shape.size.x(), 2 * shape.size.x(), shape.size.y()};
              break;
            case sim::CollisionShape::Type::kSphere:
              o.size = Eigen::Vector3d::Constant(2 * shape.size.x());
              break;
          }
          options.robot.push_back(o);
        }
      }
      sim::write_svg(dir / "scene_side.svg", w.world, sim::View::kSide, options);
      sim::write_svg(dir / "scene_top.svg", w.world, sim::View::kTop, options);
      // What is left, as a world file another run can start from.
      write("final_world.yaml", sim::format_world(w.world));
    } catch (const SimulatorLost& lost) {
      log().warn("no final scene: {}", lost.what);
    } catch (const std::runtime_error& e) {
      log().warn("no final scene: {}", e.what());
    }
  }

  // ---- Progress ------------------------------------------------------------

  void report_progress(const std::string& what, bool action_done = false) {
    if (!show_progress_) return;
    const auto line = progress_line(stats_.boxes_unloaded, stats_.boxes_total, stats_.robot_time_s,
                                    action_done ? what : action_name_ + ": " + what);
    if (tty_) {
      std::fprintf(stderr, "\r\033[K%s", line.c_str());
      std::fflush(stderr);
    } else if (action_done) {
      std::fprintf(stderr, "%s\n", line.c_str());
    }
  }

  void publish_status() {
    flatbuffers::FlatBufferBuilder fbb;
    std::vector<flatbuffers::Offset<msg::Stat>> s;
    auto add = [&](const char* key, double v) { s.push_back(msg::CreateStatDirect(fbb, key, v)); };
    add("boxes_unloaded", stats_.boxes_unloaded);
    add("boxes_total", stats_.boxes_total);
    add("actions", static_cast<double>(stats_.pick.executions + stats_.sweep.executions));
    add("robot_time_s", stats_.robot_time_s);
    add("boxes_per_s", stats_.robot_time_s > 0 ? stats_.boxes_unloaded / stats_.robot_time_s : 0.0);
    fbb.Finish(msg::CreateStatisticsDirect(fbb, ctx().name().c_str(), &s));
    (void)status_.publish(fbb);
  }

  // Parameters.
  std::string report_dir_, env_, world_file_;
  std::uint64_t seed_ = 1;
  sim::ObservationParams obs_;
  Geometry geometry_;
  double plan_timeout_s_ = 5, execute_timeout_s_ = 300, service_wait_s_ = 60, settle_s_ = 0.3;
  double retreat_m_ = 0.3, dropoff_backoff_m_ = 0.5;
  std::chrono::milliseconds retry_{50};
  std::uint64_t max_idle_ = 6, max_actions_ = 0, max_candidates_ = 4;
  // Different grips tried per box (more cups, slower carries) before it is
  // left to a sweep or in the trailer.
  std::uint64_t grip_attempts_ = 3;
  // A budget of search expansions, not of time, makes each plan (and so the
  // run) the same for a seed whatever the machine's load; 0 plans until the
  // time limit. ARA* spends the whole budget lowering ε, so by default it
  // stops at its first solution (ε = 5) and the budget only caps the search.
  std::uint64_t plan_expansions_ = 5000;
  std::vector<double> plan_epsilons_{5.0};
  std::vector<double> nose_home_{0.5, 0.0, 0.0}, nose_down_{0.0, 0.05, 0.0},
      nose_sweep_{0.0, 0.05, 0.3};
  // Arm folded over the base: out of the way of boxes leaving on the belt.
  std::vector<double> arm_clear_{0.0, -1.0, 2.0, 0.0};
  bool show_progress_ = true, tty_ = false;
  sim::RobotModel robot_;
  Publisher<msg::Statistics> status_;
  Publisher<msg::PipelineDone> done_;

  // Worker.
  std::thread worker_;
  std::mutex m_;
  std::condition_variable cv_;
  std::atomic<bool> stop_{false};

  // Run state (worker thread only).
  RunStats stats_;
  std::string action_name_;
  std::vector<std::uint32_t> last_held_;
  double sim_clock_s_ = -1.0;          // the simulator's clock when last heard, s
  double carry_height_m_ = 1.4;        // plate height a load is lowered to before the drop-off
  std::set<std::uint32_t> ungripped_;  // boxes whose grasp failed since the last unloaded box
  std::map<std::uint32_t, GripHistory> grips_;
  // Why the last pick of a box stopped before its grasp: for the final log.
  std::map<std::uint32_t, std::string> unreached_;
  std::string step_failure_;  // why the last step that failed did
  double time_scale_ = 1.0;   // of the trajectories executed: > 1 carries a box that dropped slower
  std::vector<std::uint32_t> left_;  // boxes in the trailer when last observed
  msg::PlanStatus last_status_ = msg::PlanStatus::Solved;
  double checkpoint_robot_time_ = 0;
  std::size_t checkpoint_curve_ = 0;
};

}  // namespace
}  // namespace plr::executor

PLR_PLUGIN(
    plr::executor::ExecutorNode, "strategy_executor", "1.0.0", PLR_KIND_EXECUTOR,
    "Walks strategies, instantiates Pick/Sweep into planner queries, runs them on the simulator")
