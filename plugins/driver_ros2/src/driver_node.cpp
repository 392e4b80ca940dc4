// The robot driver: serves `sim/execute` as the simulator does, so the
// executor cannot tell them apart, by streaming the trajectory to a ros2_control
// joint trajectory controller over DDS (FollowJointTrajectory, ROS 2 types and
// names). Safety lives here: joint limits checked before anything is sent, a
// watchdog on joint_states, an e-stop latch (topic `estop`), nothing sent
// while not active. The suction and conveyor commands go to the I/O
// controller (`io_commands`, plr/ros2/io_command.hpp). The motion as the
// joints reported it, with those commands, then goes to the world:
// `world/execute` (in configs/unload_robot.yaml the simulator, standing in
// for the trailer).
#include "controller_client.hpp"
#include "limit_check.hpp"

#include <plr/msg/driver_generated.h>
#include <plr/actions/motion_messages.hpp>
#include <plr/interface.hpp>
#include <plr/messages.hpp>
#include <plr/node.hpp>
#include <plr/plugin.hpp>
#include <plr/sim/robot_model.hpp>
#include <plr/sim/suction_plate.hpp>

#include <algorithm>
#include <cmath>
#include <memory>
#include <mutex>
#include <random>
#include <set>
#include <tuple>

namespace plr::driver {
namespace {

using namespace std::chrono_literals;

// The I/O a motion asks for before it (the cups' valves with the vacuum on;
// the conveyor as it runs during the motion) and after it, from `now`.
ros2::IoCommand io_before(ros2::IoCommand now, const actions::Motion& motion) {
  now.conveyor = motion.conveyor;
  if (motion.before == actions::Suction::kOff) now.vacuum = false;
  if (motion.before == actions::Suction::kOn) {
    now.vacuum = true;
    now.cups_open.assign(now.cups_open.size(), true);
    for (std::size_t i = 0; i < motion.cups_open.size() && i < now.cups_open.size(); ++i)
      now.cups_open[i] = motion.cups_open[i];
  }
  return now;
}

ros2::IoCommand io_after(const ros2::IoCommand& now, const actions::Motion& motion) {
  ros2::IoCommand io = io_before(now, motion);
  if (motion.after != actions::Suction::kKeep) io.vacuum = motion.after == actions::Suction::kOn;
  return io;
}

class DriverNode : public Node {
 public:
  using Node::Node;
  ~DriverNode() override {
    stop_jobs("the driver is shutting down");
    client_.close();
  }

 protected:
  Status on_configure() override {
    params().allow_only({"urdf", "action", "joint_states", "domain_id", "loopback_only",
                         "time_scale", "path_tolerance", "goal_tolerance", "goal_time_tolerance_s",
                         "watchdog_s", "accept_timeout_s", "limit_margin", "start_tolerance",
                         "world_execute", "world_observe", "io_commands"});
    auto robot = sim::load_robot(params().get<std::string>("urdf", ""));
    if (!robot) return make_error(PLR_ERR_INVALID, "param 'urdf': " + robot.error().message);
    robot_.emplace(std::move(*robot));
    time_scale_ = params().get<double>("time_scale", 1.0);
    path_tolerance_ = params().get<double>("path_tolerance", 0.1);
    goal_tolerance_ = params().get<double>("goal_tolerance", 0.01);
    goal_time_tolerance_ = params().get<double>("goal_time_tolerance_s", 1.0);
    watchdog_s_ = params().get<double>("watchdog_s", 0.5);
    accept_timeout_s_ = params().get<double>("accept_timeout_s", 5.0);
    limit_margin_ = params().get<double>("limit_margin", 0.05);
    start_tolerance_ = params().get<double>("start_tolerance", 0.01);
    world_execute_ = params().get<std::string>("world_execute", "world/execute");
    world_observe_ = params().get<std::string>("world_observe", "sim/observe");
    const int domain = params().get<int>("domain_id", 0);
    for (const auto& [name, value, lo, hi] :
         {std::tuple{"time_scale", time_scale_, 0.1, 100.0},
          std::tuple{"path_tolerance", path_tolerance_, 0.0, 10.0},
          std::tuple{"goal_tolerance", goal_tolerance_, 0.0, 1.0},
          std::tuple{"goal_time_tolerance_s", goal_time_tolerance_, 0.0, 60.0},
          std::tuple{"watchdog_s", watchdog_s_, 0.01, 10.0},
          std::tuple{"accept_timeout_s", accept_timeout_s_, 0.1, 60.0},
          std::tuple{"limit_margin", limit_margin_, 0.0, 0.5},
          std::tuple{"start_tolerance", start_tolerance_, 1e-6, 1.0},
          std::tuple{"domain_id", static_cast<double>(domain), 0.0, 232.0}})
      if (!(value >= lo && value <= hi))
        return make_error(
            PLR_ERR_INVALID,
            fmt::format("param '{}': must be between {} and {}, got {}", name, lo, hi, value));
    ClientOptions c;
    c.action = params().get<std::string>("action", c.action);
    c.joint_states = params().get<std::string>("joint_states", c.joint_states);
    c.io_commands = params().get<std::string>("io_commands", c.io_commands);
    c.domain_id = static_cast<std::uint32_t>(domain);
    c.loopback_only = params().get<bool>("loopback_only", false);
    joint_states_name_ = c.joint_states;
    if (auto ok = client_.open(c); !ok) return ok;

    auto status = ctx().advertise<msg::Statistics>("driver/status");
    if (!status) return status.error();
    status_pub_ = *status;
    if (auto s = ctx().subscribe<msg::EStop>(
            "estop", [this](const Message<msg::EStop>& m) { on_estop(*m); });
        !s)
      return s;
    return ctx().provide_async<msg::ExecuteRequest, msg::ExecuteOutcome>(
        "sim/execute",
        [this](const Message<msg::ExecuteRequest>& r, Responder<msg::ExecuteOutcome> responder) {
          auto motion = actions::decode_execute_request(*r);
          if (!motion) {
            (void)responder.fail(PLR_ERR_INVALID, motion.error().message);
            return;
          }
          start_job(std::move(*motion), std::move(responder));
        });
  }

  Status on_activate() override {
    active_ = true;
    return {};
  }

  Status on_deactivate() override {
    active_ = false;
    stop_jobs("the driver was deactivated");
    return {};
  }

  Status on_cleanup() override {
    client_.close();
    robot_.reset();
    return {};
  }

 private:
  struct Job {
    std::thread thread;
    std::shared_ptr<std::atomic<bool>> done;
  };

  void start_job(actions::Motion motion, Responder<msg::ExecuteOutcome> responder) {
    std::lock_guard lock(jobs_m_);
    // Joins the jobs that ended, so threads do not pile up.
    for (auto it = jobs_.begin(); it != jobs_.end();) {
      if (it->done->load()) {
        it->thread.join();
        it = jobs_.erase(it);
      } else {
        ++it;
      }
    }
    auto done = std::make_shared<std::atomic<bool>>(false);
    auto shared = std::make_shared<Responder<msg::ExecuteOutcome>>(std::move(responder));
    jobs_.push_back({std::thread([this, motion = std::move(motion), shared, done] {
                       execute(motion, *shared);
                       *done = true;
                     }),
                     done});
  }

  void stop_jobs(const std::string& why) {
    cancel_active(why);
    std::vector<Job> jobs;
    {
      std::lock_guard lock(jobs_m_);
      jobs.swap(jobs_);
    }
    for (auto& j : jobs) j.thread.join();
  }

  void cancel_active(const std::string& why) {
    std::lock_guard lock(goals_m_);
    for (const auto& id : active_goals_) {
      log().warn("stopping goal {}: {}", ros2::to_string(id), why);
      (void)client_.cancel(id);
    }
  }

  void on_estop(const msg::EStop& m) {
    const std::string reason = m.reason() ? m.reason()->str() : "";
    if (m.engaged()) {
      {
        std::lock_guard lock(goals_m_);
        estop_reason_ = reason.empty() ? "no reason given" : reason;
      }
      estop_ = true;
      log().error("e-stop engaged ({}): halting, motion refused until reset", reason);
      cancel_active("e-stop");
      stop_conveyor();
    } else if (estop_) {
      estop_ = false;
      log().info("e-stop reset{}{}", reason.empty() ? "" : ": ", reason);
    }
  }

  std::string estop_reason() {
    std::lock_guard lock(goals_m_);
    return estop_reason_;
  }

  ros2::GoalId new_goal_id() {
    std::lock_guard lock(goals_m_);
    ros2::GoalId id{};
    for (auto& b : id) b = static_cast<std::uint8_t>(rng_());
    return id;
  }

  ros2::TrajectoryGoal goal_of(const actions::Motion& m) const {
    ros2::TrajectoryGoal g;
    g.joint_names.assign(sim::kJointNames.begin(), sim::kJointNames.end());
    for (const auto& p : m.points)
      g.points.push_back(
          {p.time_s, std::vector<double>(p.position.data(), p.position.data() + sim::kNumJoints),
           std::vector<double>(p.velocity.data(), p.velocity.data() + sim::kNumJoints)});
    for (const auto& name : g.joint_names) {
      g.path_tolerance.push_back({name, path_tolerance_ > 0.0 ? path_tolerance_ : -1.0});
      g.goal_tolerance.push_back({name, goal_tolerance_ > 0.0 ? goal_tolerance_ : -1.0});
    }
    g.goal_time_tolerance_s = goal_time_tolerance_;
    return g;
  }

  // One sim/execute, on its own thread: the node's thread stays free for
  // the e-stop and for a newer motion, which preempts this one.
  void execute(const actions::Motion& motion, Responder<msg::ExecuteOutcome>& responder) {
    const auto refuse = [&](plr_status code, const std::string& why) {
      log().warn("sim/execute refused: {}", why);
      (void)responder.fail(code, why);
    };
    if (!active_) return refuse(PLR_ERR_STATE, "the driver is not active: nothing is sent");
    if (estop_)
      return refuse(PLR_ERR_STATE,
                    "e-stop engaged (" + estop_reason() + "): motion refused until it is reset");
    if (motion.points.empty()) {
      // Suction or conveyor alone: I/O only, nothing for the controller.
      if (auto io = send_io(motion, false); !io) return refuse(io.error().code, io.error().message);
      if (auto io = send_io(motion, true); !io) return refuse(io.error().code, io.error().message);
      flatbuffers::FlatBufferBuilder out;
      if (auto world = to_world(motion, {}, false, out); !world)
        return refuse(world.error().code, world.error().message);
      (void)responder.reply(out);
      return;
    }
    if (auto ok = check_limits(motion.points, *robot_, limit_margin_); !ok)
      return refuse(PLR_ERR_INVALID, "refused before sending: " + ok.error().message);
    const auto state = client_.latest_state();
    // Refusals are PLR_ERR_STATE: the action goes on without the motion. The
    // executor takes UNAVAILABLE for a simulator that restarted and would
    // restore the world, which moves no real robot.
    if (!state)
      return refuse(PLR_ERR_STATE,
                    fmt::format("no joint state on {} yet: nothing is sent", joint_states_name_));
    if (const double age = seconds_since(state->received); age > watchdog_s_)
      return refuse(PLR_ERR_STATE,
                    fmt::format("joint state on {} is {:.2f} s old (watchdog {:.2f} s): nothing "
                                "is sent",
                                joint_states_name_, age, watchdog_s_));

    // A trajectory from t = 0 must start where the joints are: the
    // controller would jump to its first point. A simulated world can hold
    // the robot elsewhere than the joints (restored from a checkpoint after a
    // crash, say) and the plan came from it: the controller first goes there.
    if (motion.points.front().time_s == 0.0) {
      auto at_joints = starts_at_joints(motion, state->sample);
      if (!at_joints && simulated_world()) {
        log().warn("{}: bringing the controller to the world's robot state first",
                   at_joints.error().message);
        const auto moved = realign_with_world();
        if (!moved)
          return refuse(PLR_ERR_STATE, "refused before sending: " + at_joints.error().message +
                                           "; " + moved.error().message);
        log().info("the controller reached the world's robot state in {:.2f} s", *moved);
        const auto now = client_.latest_state();
        at_joints = now ? starts_at_joints(motion, now->sample) : at_joints;
      }
      if (!at_joints)
        return refuse(PLR_ERR_STATE, "refused before sending: " + at_joints.error().message);
    }
    if (auto io = send_io(motion, false); !io) return refuse(io.error().code, io.error().message);
    GoalRun run = run_goal(goal_of(motion));
    if (!run.sent) return refuse(run.code, run.failure);
    // A motion that stopped early keeps its grip: what it carries stays on the plate.
    if (auto io = run.failure.empty() ? send_io(motion, true) : Status{}; !io)
      run.failure = io.error().message;
    // What the joints did goes to the world, even when the motion stopped
    // early: the robot is where it stopped, and what it carries stays on the plate.
    flatbuffers::FlatBufferBuilder out;
    if (auto world = to_world(motion, run.measured, !run.failure.empty(), out); !world) {
      if (run.failure.empty()) return refuse(world.error().code, world.error().message);
      run.failure += "; " + world.error().message;
    }
    if (!run.failure.empty()) return refuse(run.code, run.failure);
    if (flatbuffers::GetRoot<msg::ExecuteOutcome>(out.GetBufferPointer())->stalled() &&
        simulated_world()) {
      if (auto moved = realign_with_world(); !moved)
        log().error("after the world stalled the base: {}", moved.error().message);
      else
        log().warn(
            "the world stalled the base: the controller was brought back to the "
            "world's robot state in {:.2f} s",
            *moved);
    }
    (void)responder.reply(out);
  }

  // The belt stops with the robot. The vacuum stays as it is: released, it
  // would drop a held box.
  void stop_conveyor() {
    std::lock_guard lock(io_m_);
    if (!io_.conveyor) return;
    ros2::IoCommand io = io_;
    io.conveyor = false;
    if (auto sent = client_.send_io(io, to_ms(accept_timeout_s_)); !sent)
      log().error("e-stop: the conveyor could not be stopped: {}", sent.error().message);
    else
      io_ = io;
  }

  // Sends what the motion asks of the I/O before it (`after` false) or
  // after it, unless the I/O controller has that already.
  Status send_io(const actions::Motion& motion, bool after) {
    std::lock_guard lock(io_m_);
    const ros2::IoCommand io = after ? io_after(io_, motion) : io_before(io_, motion);
    if (io == io_) return {};
    if (auto sent = client_.send_io(io, to_ms(accept_timeout_s_)); !sent) return sent;
    io_ = io;
    return {};
  }

  // The sample's positions in the robot's joint order.
  Expected<sim::JointVector> positions_of(const ros2::JointStateSample& joints) const {
    sim::JointVector q;
    for (int j = 0; j < sim::kNumJoints; ++j) {
      const auto it = std::find(joints.names.begin(), joints.names.end(), sim::kJointNames[j]);
      if (it == joints.names.end())
        return make_error(PLR_ERR_STATE, fmt::format("joint state on {} has no joint {}",
                                                     joint_states_name_, sim::kJointNames[j]));
      q[j] = joints.position[static_cast<std::size_t>(it - joints.names.begin())];
    }
    return q;
  }

  // Whether the trajectory starts where `joints` are (within start_tolerance), or how far off.
  Status starts_at_joints(const actions::Motion& motion,
                          const ros2::JointStateSample& joints) const {
    const auto q = positions_of(joints);
    if (!q) return q.error();
    for (int j = 0; j < sim::kNumJoints; ++j) {
      const double off = std::abs(motion.points.front().position[j] - (*q)[j]);
      if (off > start_tolerance_)
        return make_error(PLR_ERR_STATE,
                          fmt::format("the trajectory starts {:.4f} from joint {} (start "
                                      "tolerance {:.4f})",
                                      off, sim::kJointNames[j], start_tolerance_));
    }
    return {};
  }

  struct GoalRun {
    bool sent = false;    // the controller accepted the goal
    std::string failure;  // why it did not succeed; empty when it did
    plr_status code = PLR_ERR_STATE;
    std::vector<ros2::JointStateSample> measured;  // joint states from before it to after it
  };

  // Sends one goal and follows it to its end, stopping the robot (cancel:
  // the controller holds where the joints are) on the e-stop, stale joint
  // states, deactivation or a missing result.
  GoalRun run_goal(const ros2::TrajectoryGoal& goal) {
    GoalRun run;
    const ros2::GoalId id = new_goal_id();
    const std::uint64_t first_state = client_.states_received();
    {
      std::lock_guard lock(goals_m_);
      active_goals_.insert(id);
    }
    if (auto sent = client_.send_goal(id, goal, to_ms(accept_timeout_s_)); !sent) {
      forget(id);
      run.code = PLR_ERR_STATE;
      run.failure = sent.error().message;
      return run;
    }
    run.sent = true;
    (void)client_.request_result(id);
    const double duration = goal.points.back().time_s;
    const auto deadline =
        WallClock::now() +
        to_ms((duration + goal.goal_time_tolerance_s + 1.0) / time_scale_ + accept_timeout_s_);
    auto last_status = WallClock::now();
    std::optional<ros2::TrajectoryResult> result;
    for (;;) {
      // Before the result: the e-stop's or the deactivation's own cancel may
      // have ended the goal.
      if (estop_) {
        run.failure = "e-stop engaged (" + estop_reason() + "): halted mid-trajectory";
        break;
      }
      if (!active_) {
        run.failure = "the driver was deactivated: halted mid-trajectory";
        run.code = PLR_ERR_CANCELLED;
        break;
      }
      if ((result = client_.result(id))) break;
      const auto now_state = client_.latest_state();
      if (const double age = seconds_since(now_state->received); age > watchdog_s_) {
        run.failure =
            fmt::format("joint state on {} stale for {:.2f} s (watchdog {:.2f} s): stopped",
                        joint_states_name_, age, watchdog_s_);
        break;
      }
      if (WallClock::now() > deadline) {
        run.failure = fmt::format("no result {:.1f} s after the trajectory's end: stopped",
                                  goal.goal_time_tolerance_s + 1.0);
        break;
      }
      if (WallClock::now() - last_status > 100ms) {
        publish_status(id, duration);
        last_status = WallClock::now();
      }
      client_.wait(10ms);
    }
    if (!result) {
      (void)client_.cancel(id);
      log().error("goal {}: {}", ros2::to_string(id), run.failure);
      const auto until = WallClock::now() + 300ms;
      while (!client_.result(id) && WallClock::now() < until) client_.wait(10ms);
    } else if (result->status != ros2::GoalStatus::kSucceeded) {
      run.failure =
          fmt::format("controller ended the goal {}: {} ({})", ros2::to_string(result->status),
                      ros2::to_string(result->error), result->error_string);
      if (result->status == ros2::GoalStatus::kCanceled &&
          result->error == ros2::TrajectoryError::kInvalidGoal)
        run.failure = "preempted by a newer motion: " + run.failure;
      log().error("goal {}: {}", ros2::to_string(id), run.failure);
    }
    forget(id);
    publish_status(id, duration);
    client_.forget(id);
    // The result may overtake the last joint state (another topic): wait for
    // one more, so the measured motion ends where the joints stopped.
    const std::uint64_t seen = client_.states_received();
    for (const auto until = WallClock::now() + 200ms;
         client_.states_received() == seen && WallClock::now() < until;)
      client_.wait(5ms);
    run.measured = client_.states_since(first_state);
    return run;
  }

  // A world that follows the joints (world_execute) and tells where it holds
  // the robot (world_observe).
  bool simulated_world() const { return !world_execute_.empty() && !world_observe_.empty(); }

  // Brings the controller to where the world holds the robot, to within
  // 1e-5, so that a trajectory planned from the world's state starts where
  // the joints are; returns how long the move took. Needed where the world
  // is simulated: it stops the base where its boxes push back harder than the
  // drive can push (the emulated joints feel no boxes and go on), and it can
  // be restored from a checkpoint. A real robot's world follows the joints.
  Expected<double> realign_with_world() {
    flatbuffers::FlatBufferBuilder req;
    req.Finish(msg::CreateObserveRequest(req, false));
    auto w = ctx().call<msg::ObserveRequest, msg::WorldState>(world_observe_, req, 30s).get();
    const auto state = client_.latest_state();
    if (!w || !w.value()->robot() || !w.value()->robot()->positions() ||
        w.value()->robot()->positions()->size() != sim::kNumJoints || !state)
      return make_error(PLR_ERR_STATE, world_observe_ +
                                           ": no robot state to bring the "
                                           "controller to");
    std::vector<double> target(w.value()->robot()->positions()->begin(),
                               w.value()->robot()->positions()->end());
    // Rest to rest in T with a cubic: peak velocity 1.5 d/T, peak acceleration 6 d/T^2.
    double duration = 0.1;
    const auto q = positions_of(state->sample);
    if (!q) return q.error();
    for (int j = 0; j < sim::kNumJoints; ++j) {
      const double d = std::abs(target[static_cast<std::size_t>(j)] - (*q)[j]);
      const sim::JointLimits& l = robot_->limits(j);
      duration = std::max({duration, 1.5 * d / l.velocity, std::sqrt(6.0 * d / l.acceleration)});
    }
    ros2::TrajectoryGoal g;
    g.joint_names.assign(sim::kJointNames.begin(), sim::kJointNames.end());
    g.points.push_back({duration * 1.2, target, std::vector<double>(sim::kNumJoints, 0.0)});
    for (const auto& name : g.joint_names) {
      g.path_tolerance.push_back({name, -1.0});
      g.goal_tolerance.push_back({name, 1e-5});
    }
    g.goal_time_tolerance_s = 2.0;
    const GoalRun run = run_goal(g);
    if (!run.failure.empty())
      return make_error(run.code, "bringing the controller to the world's robot: " + run.failure);
    return duration * 1.2;
  }

  void forget(const ros2::GoalId& id) {
    std::lock_guard lock(goals_m_);
    active_goals_.erase(id);
  }

  // The motion as the joints reported it, with the request's I/O commands,
  // to the world; its outcome is the reply. Without a world, the outcome says
  // only that the motion ran.
  Status to_world(const actions::Motion& asked, const std::vector<ros2::JointStateSample>& measured,
                  bool stopped_early, flatbuffers::FlatBufferBuilder& out) {
    if (world_execute_.empty()) {
      const double end = measured.empty() ? 0.0 : measured.back().stamp_s;
      out.Finish(msg::CreateExecuteOutcomeDirect(out, true, "", end));
      return {};
    }
    actions::Motion m;
    m.before = asked.before;
    m.after = stopped_early ? actions::Suction::kKeep : asked.after;
    m.cups_open = asked.cups_open;
    m.conveyor = asked.conveyor;
    m.settle_s = asked.settle_s;
    std::vector<int> index(sim::kNumJoints, -1);
    for (const auto& s : measured) {
      for (int j = 0; j < sim::kNumJoints; ++j) {
        const auto it = std::find(s.names.begin(), s.names.end(), sim::kJointNames[j]);
        index[j] = it == s.names.end() ? -1 : static_cast<int>(it - s.names.begin());
      }
      if (std::count(index.begin(), index.end(), -1) > 0) continue;
      planning::TimedPoint p;
      p.time_s = s.stamp_s - measured.front().stamp_s;
      if (!m.points.empty() && p.time_s <= m.points.back().time_s) continue;
      for (int j = 0; j < sim::kNumJoints; ++j) {
        p.position[j] = s.position[index[j]];
        p.velocity[j] = s.velocity.size() == s.names.size() ? s.velocity[index[j]] : 0.0;
      }
      m.points.push_back(p);
    }
    if (!asked.points.empty() && m.points.size() < 2)
      return make_error(PLR_ERR_STATE,
                        fmt::format("{} joint states with all joints during the motion: the world "
                                    "cannot follow it",
                                    m.points.size()));
    flatbuffers::FlatBufferBuilder req;
    actions::encode_execute_request(m, req);
    auto reply = ctx()
                     .call<msg::ExecuteRequest, msg::ExecuteOutcome>(world_execute_, req,
                                                                     std::chrono::seconds(300))
                     .get();
    if (!reply)
      return make_error(reply.error().code, world_execute_ + ": " + reply.error().message);
    msg::ExecuteOutcomeT copy;
    reply.value()->UnPackTo(&copy);
    out.Finish(msg::ExecuteOutcome::Pack(out, &copy));
    return {};
  }

  void publish_status(const ros2::GoalId& id, double duration) {
    const auto fb = client_.feedback(id);
    double progress = 0.0, worst = 0.0;
    if (fb) {
      progress = duration > 0.0 ? std::min(1.0, fb->desired.time_s / duration) : 1.0;
      for (double e : fb->error.positions) worst = std::max(worst, std::abs(e));
    }
    flatbuffers::FlatBufferBuilder fbb;
    std::vector<flatbuffers::Offset<msg::Stat>> stats = {
        msg::CreateStatDirect(fbb, "progress", progress),
        msg::CreateStatDirect(fbb, "position_error_max", worst),
        msg::CreateStatDirect(fbb, "estop", estop_ ? 1.0 : 0.0)};
    fbb.Finish(msg::CreateStatisticsDirect(fbb, "driver", &stats));
    (void)status_pub_.publish(fbb);
  }

  static double seconds_since(WallClock::time_point t) {
    return std::chrono::duration<double>(WallClock::now() - t).count();
  }
  static std::chrono::milliseconds to_ms(double s) {
    return std::chrono::milliseconds(static_cast<std::int64_t>(s * 1000.0));
  }

  std::optional<sim::RobotModel> robot_;
  ControllerClient client_;
  std::string joint_states_name_, world_execute_, world_observe_;
  // The I/O last sent: vacuum off, conveyor stopped, every cup valve open.
  std::mutex io_m_;
  ros2::IoCommand io_{
      false, false,
      std::vector<bool>(
          static_cast<std::size_t>(sim::SuctionPlate{}.cups_x* sim::SuctionPlate{}.cups_y), true)};
  double time_scale_ = 1.0, path_tolerance_ = 0.1, goal_tolerance_ = 0.01,
         goal_time_tolerance_ = 1.0, watchdog_s_ = 0.5, accept_timeout_s_ = 5.0,
         limit_margin_ = 0.05, start_tolerance_ = 0.01;
  Publisher<msg::Statistics> status_pub_;
  std::atomic<bool> active_{false};
  std::atomic<bool> estop_{false};
  std::mutex goals_m_;
  std::string estop_reason_;
  std::set<ros2::GoalId> active_goals_;
  std::mt19937_64 rng_{std::random_device{}()};
  std::mutex jobs_m_;
  std::vector<Job> jobs_;
};

}  // namespace
}  // namespace plr::driver

PLR_PLUGIN(plr::driver::DriverNode, "driver_ros2", "0.1.0", PLR_KIND_DRIVER,
           "Drives a ros2_control joint trajectory controller over DDS (ROS 2 types)")
PLR_INTERFACE(plr::topic<plr::msg::Statistics>("driver/status"),
              plr::service<plr::msg::ExecuteRequest, plr::msg::ExecuteOutcome>("sim/execute"))
