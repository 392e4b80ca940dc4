// The executor in the fake kernel, against a kinematic stand-in simulator
// (robot jumps to each trajectory's end, suction grips the box the plate
// faces, a sweep takes what the scoop reaches) and a stand-in planner (IK for
// pose goals, straight lines). Strategy H is the real plug-in.
#include <gtest/gtest.h>
#include <plr/testing/fake_kernel.hpp>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>

#include "plr/planning/plan_query.hpp"
#include "plr/sim/observation.hpp"
#include "plr/sim/robot_model.hpp"
#include "plr/sim/strategy.hpp"
#include "plr/sim/testing/worlds.hpp"
#include "plr/sim/world_io.hpp"

namespace plr {
namespace {

namespace fs = std::filesystem;
using testing::FakeKernel;
using testing::NodeOptions;

struct SimState {
  sim::World world;
  sim::JointVector q;
  std::vector<std::uint32_t> held;
  std::uint32_t unloaded = 0;
  double t = 0;
};

class FakeSim {
 public:
  explicit FakeSim(sim::World w) {
    s_.world = std::move(w);
    s_.q << 1.0, 0, -1.0, 2.0, 0.0, 0.5, 0, 0;
    q0_ = s_.q;
  }

  void serve(FakeKernel& k) {
    k.fake_service<msg::ObserveRequest, msg::WorldState>(
        "sim/observe",
        [this](const msg::ObserveRequest&, flatbuffers::FlatBufferBuilder& fbb) -> Status {
          if (down_ && --observes_while_down < 0) down_ = false;
          if (down_) return make_error(PLR_ERR_UNAVAILABLE, "no provider");
          // Stamped with the simulated clock, as the simulator does.
          fbb.Finish(sim::testing::pack_world(fbb, s_.world, joints(), s_.held, s_.unloaded, s_.t));
          return {};
        });
    k.fake_service<msg::ExecuteRequest, msg::ExecuteOutcome>(
        "sim/execute", [this](const msg::ExecuteRequest& r, flatbuffers::FlatBufferBuilder& fbb) {
          return execute(r, fbb);
        });
    k.fake_service<msg::ResetRequest, msg::WorldState>(
        "sim/reset",
        [this](const msg::ResetRequest& r, flatbuffers::FlatBufferBuilder& fbb) -> Status {
          if (down_) return make_error(PLR_ERR_UNAVAILABLE, "no provider");
          const auto it = worlds.find(r.world_file() ? r.world_file()->str() : "");
          if (it == worlds.end()) return make_error(PLR_ERR_INVALID, "no such world");
          s_.world = it->second;
          s_.q = q0_;
          s_.held.clear();
          s_.unloaded = 0;
          s_.t = 0;
          fbb.Finish(sim::testing::pack_world(fbb, s_.world, joints(), s_.held, s_.unloaded, s_.t));
          // The host dies after its reply and restarts unseen, from its checkpoint.
          if (++resets_ == restart_after_reset) s_ = snapshots_.at("checkpoint");
          if (resets_ == refuse_after_reset) {
            refusing_ = snapshots_refused;
            executes_since_reset_ = 0;
          }
          return {};
        });
    k.fake_service<msg::SnapshotRequest, msg::SnapshotReply>(
        "sim/snapshot",
        [this](const msg::SnapshotRequest& r, flatbuffers::FlatBufferBuilder& fbb) -> Status {
          if (down_) return make_error(PLR_ERR_UNAVAILABLE, "no provider");
          if (refusing_ > 0) {
            --refusing_;
            fbb.Finish(msg::CreateSnapshotReplyDirect(
                fbb, false, "cannot create a temporary file: Read-only file system",
                r.name()->c_str()));
            return {};
          }
          snapshots_[r.name()->str()] = s_;
          trailer_starts_.try_emplace(resets_, s_);
          fbb.Finish(msg::CreateSnapshotReplyDirect(
              fbb, true, "", r.name()->c_str(), kCheckpointBytesPerBox * s_.world.boxes.size()));
          return {};
        });
    k.fake_service<msg::SnapshotRequest, msg::SnapshotReply>(
        "sim/restore",
        [this](const msg::SnapshotRequest& r, flatbuffers::FlatBufferBuilder& fbb) -> Status {
          const auto it = snapshots_.find(r.name()->str());
          if (it != snapshots_.end()) s_ = it->second;
          ++restores_;
          fbb.Finish(
              msg::CreateSnapshotReplyDirect(fbb, it != snapshots_.end(), "", r.name()->c_str()));
          return {};
        });
  }

  // The checkpoint's size on disk, as the fake reports it.
  static constexpr std::uint64_t kCheckpointBytesPerBox = 100;
  bool suction_works = true;
  // Suction as the simulator's (docs/notes-sim.md) when > 0: a cup holds
  // cup_force with its whole rim on the face; a box heavier than its cups
  // hold is refused, and one whose load while carried (weight plus mass times
  // the peak acceleration of a rest-to-rest move over the trajectory's time)
  // exceeds them falls back where it was gripped. 0: the plate holds any box
  // it faces.
  double cup_force = 0.0;
  int crash_at_execute = -1;  // the n-th execute dies with the host
  // After the n-th execute the host dies and restarts unseen, between two
  // calls: it resumes from its checkpoint on disk, clock and all.
  int restart_after_execute = -1;
  int observes_while_down = 3;
  std::map<std::string, sim::World> worlds;  // what sim/reset makes, by world_file
  int restart_after_reset = -1;              // the n-th reset's host restarts after replying
  // After the n-th reset the disk refuses `snapshots_refused` snapshots, and
  // the host restarts unseen after `restart_after_reset_execute` executes.
  int refuse_after_reset = -1;
  int snapshots_refused = 0;
  int restart_after_reset_execute = -1;
  // After the n-th reset the host restarts unseen after its first execute,
  // from the first trailer's start (a checkpoint file of another trailer).
  int restart_into_first_trailer_after_reset = -1;

  const SimState& state() const { return s_; }
  int drops() const { return drops_; }
  int restores() const { return restores_; }
  int executes() const { return executes_; }

 private:
  std::vector<double> joints() const { return {s_.q.data(), s_.q.data() + sim::kNumJoints}; }

  Status execute(const msg::ExecuteRequest& r, flatbuffers::FlatBufferBuilder& fbb) {
    if (down_) return make_error(PLR_ERR_UNAVAILABLE, "no provider");
    if (++executes_ == crash_at_execute) {
      // The host dies mid-motion: the robot has moved and a held box fell.
      s_.q[sim::kBaseX] += 0.2;
      s_.held.clear();
      down_ = true;
      return make_error(PLR_ERR_UNAVAILABLE, "provider gone");
    }
    suction(r.suction_before());
    const auto* pts = r.trajectory()->points();
    const auto* last = pts->Get(pts->size() - 1);
    const Eigen::Isometry3d plate_before = robot_.plate_pose(s_.q);
    for (int j = 0; j < sim::kNumJoints; ++j) s_.q[j] = last->positions()->Get(j);
    // Held boxes ride on the plate, unless their cups let go.
    const Eigen::Isometry3d carry = robot_.plate_pose(s_.q) * plate_before.inverse();
    const double accel = 4 * carry.translation().norm() / std::pow(last->time_s(), 2);
    for (auto& b : s_.world.boxes) {
      if (std::find(s_.held.begin(), s_.held.end(), b.id) == s_.held.end()) continue;
      if (cup_force > 0 && b.mass * (kGravity + accel) > capacity_.at(b.id)) {
        b.pose = gripped_at_.at(b.id);
        std::erase(s_.held, b.id);
        ++drops_;
        continue;
      }
      b.pose = carry * b.pose;
    }
    s_.t += last->time_s() + r.settle_s();
    sweep();
    suction(r.suction_after());
    std::vector<std::uint32_t> none;
    fbb.Finish(msg::CreateExecuteOutcomeDirect(fbb, true, "", s_.t, &none, &none, &s_.held, 0,
                                               static_cast<std::uint32_t>(s_.world.boxes.size())));
    if (executes_ == restart_after_execute ||
        (executes_since_reset_ >= 0 && ++executes_since_reset_ == restart_after_reset_execute))
      s_ = snapshots_.at("checkpoint");
    if (resets_ == restart_into_first_trailer_after_reset && !restarted_into_first_trailer_) {
      restarted_into_first_trailer_ = true;
      s_ = snapshots_["checkpoint"] = trailer_starts_.at(1);
    }
    return {};
  }

  void suction(msg::Suction s) {
    if (s == msg::Suction::Off) {
      // Released over the nose: the conveyor takes the boxes out.
      for (auto id : s_.held) {
        std::erase_if(s_.world.boxes, [&](const sim::Box& b) { return b.id == id; });
        ++s_.unloaded;
      }
      s_.held.clear();
    } else if (s == msg::Suction::On && suction_works) {
      const Eigen::Isometry3d plate = robot_.plate_pose(s_.q);
      const Eigen::Vector3d p = plate.translation();
      const bool down = plate.linear().col(0).z() < -0.7;  // plate normal pointing down
      for (const auto& b : s_.world.boxes) {
        const auto bb = sim::bounds(b);
        const Eigen::Vector3d c = b.pose.translation();
        const bool faces =
            down ? bb.z1 < p.z() + 0.01 && bb.z1 > p.z() - 0.03 && std::abs(c.x() - p.x()) < 0.25 &&
                       std::abs(c.y() - p.y()) < 0.25
                 : bb.x0 > p.x() - 0.01 && bb.x0 < p.x() + 0.08 && std::abs(c.y() - p.y()) < 0.25 &&
                       std::abs(c.z() - p.z()) < 0.2;
        if (!faces || std::find(s_.held.begin(), s_.held.end(), b.id) != s_.held.end()) continue;
        if (cup_force > 0) {
          const double capacity = cups_on_front_face(plate, b) * cup_force;
          if (b.mass * kGravity > capacity) continue;
          capacity_[b.id] = capacity;
          gripped_at_[b.id] = b.pose;
        }
        s_.held.push_back(b.id);
      }
    }
  }

  // The plate's 3 x 4 cups (0.5 m across, 0.4 m up) whose rim lies on the
  // box's front face (an unturned box).
  static int cups_on_front_face(const Eigen::Isometry3d& plate, const sim::Box& b) {
    constexpr double kRim = 0.03;
    int n = 0;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 4; ++j) {
        const Eigen::Vector3d cup =
            plate * Eigen::Vector3d(0.0, (i + 0.5) / 3 * 0.5 - 0.25, (j + 0.5) / 4 * 0.4 - 0.2);
        const Eigen::Vector3d d = cup - b.pose.translation();
        if (std::abs(d.y()) <= b.size.y() / 2 - kRim && std::abs(d.z()) <= b.size.z() / 2 - kRim)
          ++n;
      }
    }
    return n;
  }

  void sweep() {
    // A lowered, extended scoop takes every low box its tip has passed.
    if (s_.q[sim::kNose1] > 0.12 || s_.q[sim::kNose3] < 0.2) return;
    const double tip = s_.q[sim::kBaseX] + 1.0 + s_.q[sim::kNose3];
    const auto before = s_.world.boxes.size();
    std::erase_if(s_.world.boxes, [&](const sim::Box& b) {
      const auto bb = sim::bounds(b);
      return bb.x0 < tip && bb.z0 < 0.05;
    });
    s_.unloaded += static_cast<std::uint32_t>(before - s_.world.boxes.size());
  }

  static constexpr double kGravity = 9.81;
  sim::RobotModel robot_ = sim::load_robot().value();
  SimState s_;
  sim::JointVector q0_;
  int resets_ = 0;
  std::map<std::uint32_t, double> capacity_;  // N the cups of a held box hold
  std::map<std::uint32_t, Eigen::Isometry3d> gripped_at_;
  int drops_ = 0;
  std::map<std::string, SimState> snapshots_;
  bool down_ = false;
  int restores_ = 0;
  int executes_ = 0;
  int refusing_ = 0;
  int executes_since_reset_ = -1;
  std::map<int, SimState> trailer_starts_;  // the first checkpoint after each reset
  bool restarted_into_first_trailer_ = false;
};

// Straight lines to the goal; pose goals through the arm's IK.
class FakePlanner {
 public:
  int unavailable_first = 0;  // calls refused as if the planner were being swapped

  void serve(FakeKernel& k) {
    k.fake_service<msg::PlanRequest, msg::PlanResponse>(
        "plan", [this](const msg::PlanRequest& r, flatbuffers::FlatBufferBuilder& fbb) -> Status {
          if (calls_++ < unavailable_first) return make_error(PLR_ERR_UNAVAILABLE, "swapping");
          ++modes_[static_cast<int>(r.mode())];
          return plan(r, fbb);
        });
  }
  int answered(int mode) const { return modes_.count(mode) ? modes_.at(mode) : 0; }
  int calls() const { return calls_; }

 private:
  Status plan(const msg::PlanRequest& r, flatbuffers::FlatBufferBuilder& fbb) {
    EXPECT_EQ(r.start()->size(), 8u);
    EXPECT_NE(r.world(), nullptr);
    sim::JointVector start, goal;
    for (int j = 0; j < 8; ++j) start[j] = r.start()->Get(j);
    goal = start;
    const auto mode = static_cast<planning::PlanMode>(r.mode());
    if (r.has_goal_pose()) {
      const auto& p = *r.goal_pose();
      const Eigen::Quaterniond q(p.orientation().w(), p.orientation().x(), p.orientation().y(),
                                 p.orientation().z());
      const Eigen::Vector3d n = q.toRotationMatrix().col(0);  // plate normal
      sim::PlateTarget t{{p.position().x(), p.position().y(), p.position().z()},
                         std::atan2(n.y(), n.x())};
      const auto sols = robot_.arm_ik(t, start);
      if (sols.empty()) return reply(fbb, msg::PlanStatus::GoalInvalid, {});
      goal = sols.front();
    } else if (mode != planning::PlanMode::kEscape) {
      for (int j : planning::planned_joints(mode)) goal[j] = r.goal_joints()->Get(j);
    }
    return reply(fbb, msg::PlanStatus::Solved, {start, goal});
  }

  Status reply(flatbuffers::FlatBufferBuilder& fbb, msg::PlanStatus status,
               const std::vector<sim::JointVector>& path) {
    std::vector<flatbuffers::Offset<msg::TrajectoryPoint>> points;
    for (std::size_t i = 0; i < path.size(); ++i) {
      const std::vector<double> pos(path[i].data(), path[i].data() + 8), vel(8, 0.0);
      points.push_back(msg::CreateTrajectoryPointDirect(fbb, static_cast<double>(i), &pos, &vel));
    }
    const auto traj = msg::CreateTrajectoryDirect(fbb, &points);
    const auto stats = msg::CreatePlanStats(fbb, 10, 1.0, 2.0, 1.0, 1.0, false);
    fbb.Finish(msg::CreatePlanResponseDirect(fbb, status, "", traj, stats, "fake"));
    return {};
  }

  sim::RobotModel robot_ = sim::load_robot().value();
  int calls_ = 0;
  std::map<int, int> modes_;
};

class Executor : public ::testing::Test {
 protected:
  Executor() {
    std::string pattern = (fs::temp_directory_path() / "plr_executor_XXXXXX").string();
    dir_ = mkdtemp(pattern.data());
  }
  ~Executor() override {
    // The executor's own account, when something went wrong.
    if (HasFailure())
      for (const auto& l : kernel_.logs())
        if (l.node == "executor" || l.node == "planner")
          std::cerr << l.node << ": " << l.text << "\n";
    fs::remove_all(dir_);
  }

  // Thresholds for these walls of 0.4 m boxes, the same for H and the
  // executor: a 0.8 m wall is a wall, its boxes all of the low class.
  static constexpr const char* kObservation =
      R"({"h_pile": 0.55, "pile_mid": 0.25, "pile_high": 0.4, "wall_mid": 1.2, "wall_high": 1.9})";

  static sim::World small_wall() {
    sim::World w;
    sim::testing::add_wall(w, 5.0, 3, 2);  // six 0.4 m boxes, 0.8 m high
    return w;
  }

  // The trailers "six" (the small wall) and "four" (a wall of 2 x 2).
  static void add_two_trailers(FakeSim& sim) {
    sim.worlds["six"] = small_wall();
    sim::World four;
    sim::testing::add_wall(four, 5.0, 2, 2);
    sim.worlds["four"] = four;
  }

  // Runs the two trailers; each must be recorded with its own boxes, the
  // second's counted by the executor and by the simulator alike.
  void unloads_six_then_four() {
    const auto report = run(R"(, "trailers": [{"world_file": "six"}, {"world_file": "four"}])");
    EXPECT_TRUE(done_ok_) << done_reason_;
    EXPECT_EQ(done_reason_, "2 trailers done: 10/10 boxes unloaded");
    ASSERT_EQ(report["trailers"].size(), 2u) << report.dump(1);
    const auto& t = report["trailers"][1];
    EXPECT_EQ(t["name"], "four");
    EXPECT_EQ(t["boxes_unloaded"], 4) << t.dump();
    EXPECT_EQ(t["sim_boxes_unloaded"], 4) << t.dump();
    EXPECT_EQ(t["sim_boxes_left"], 0) << t.dump();
  }

  // Runs the executor to pipeline/done; returns the report.
  nlohmann::json run(const std::string& extra_params = "", bool with_h = true,
                     int spin_limit = 60000) {
    if (with_h) {
      auto h = kernel_.load_node(
          STRATEGY_HARDCODED_SO,
          NodeOptions()
              .with_name("strategy")
              .with_params(R"({"observation": )" + std::string(kObservation) + "}"));
      EXPECT_TRUE(h) << h.error().message;
      EXPECT_TRUE(h->configure());
      EXPECT_TRUE(h->activate());
    }
    const std::string params =
        R"({"report_dir": ")" + dir_.string() +
        R"(", "progress": false, "retry_ms": 1, "service_wait_s": 5, "observation": )" +
        kObservation + extra_params + "}";
    auto n = kernel_.load_node(STRATEGY_EXECUTOR_SO,
                               NodeOptions().with_name("executor").with_params(params));
    EXPECT_TRUE(n) << n.error().message;
    auto c = n->configure();
    EXPECT_TRUE(c) << c.error().message;
    EXPECT_TRUE(n->activate());
    // Strategy H answers from the test thread: spin until the executor is done.
    for (int i = 0; i < spin_limit && kernel_.published("pipeline/done").empty(); ++i) {
      kernel_.spin();
      kernel_.wait_published("pipeline/done", 1, std::chrono::milliseconds(1));
    }
    EXPECT_TRUE(n->deactivate());
    const auto done = kernel_.published("pipeline/done");
    EXPECT_EQ(done.size(), 1u);
    if (!done.empty()) {
      done_ok_ = done[0].as<msg::PipelineDone>()->ok();
      done_reason_ = done[0].as<msg::PipelineDone>()->reason()->str();
    }
    return reported();
  }

  // The executor's latest figures on pipeline/report: what `plr run` writes
  // into report.json.
  nlohmann::json reported() const {
    const auto reports = kernel_.published("pipeline/report");
    EXPECT_FALSE(reports.empty()) << "nothing on pipeline/report";
    if (reports.empty()) return {};
    const auto* r = reports.back().as<msg::NodeReport>();
    EXPECT_EQ(r->node()->str(), "executor");
    return nlohmann::json::parse(r->figures()->str());
  }

  FakeKernel kernel_;
  fs::path dir_;
  bool done_ok_ = false;
  std::string done_reason_;
};

TEST_F(Executor, UnloadsASmallWallWithStrategyH) {
  FakeSim sim(small_wall());
  FakePlanner planner;
  sim.serve(kernel_);
  planner.serve(kernel_);
  const auto report = run();
  EXPECT_TRUE(done_ok_) << done_reason_;
  EXPECT_EQ(done_reason_, "trailer empty: 6/6 boxes unloaded");
  EXPECT_EQ(report["boxes_total"], 6);
  EXPECT_EQ(report["boxes_unloaded"], 6);
  EXPECT_EQ(sim.state().unloaded, 6u);
  EXPECT_EQ(report["robot_trailer_collisions"], 0);
  // By picks (M5 base, M3 nose, M2 pre-grasp, M4 approach and retract, M1
  // drop-off): the low row left is a pile too shallow to sweep, also picked.
  EXPECT_GE(report["actions"]["pick"]["executions"], 3);
  EXPECT_EQ(report["actions"]["sweep"]["executions"], 0);
  EXPECT_EQ(report["actions"]["pick"]["boxes"].get<int>() +
                report["actions"]["sweep"]["boxes"].get<int>(),
            6);
  EXPECT_GT(report["actions"]["pick"]["boxes_per_s"], 0.0);
  for (int m = 1; m <= 5; ++m) {
    EXPECT_GT(planner.answered(m), 0) << "M" << m;
    EXPECT_EQ(report["planner_modes"]["M" + std::to_string(m)]["queries"], planner.answered(m));
    EXPECT_EQ(report["planner_modes"]["M" + std::to_string(m)]["failures"], 0);
  }
  EXPECT_NEAR(report["planner_modes"]["M2"]["mean_ms"].get<double>(), 2.0, 1e-9);
  EXPECT_EQ(report["curve"].size(),
            report["actions"]["pick"]["executions"].get<std::size_t>() +
                report["actions"]["sweep"]["executions"].get<std::size_t>());
  EXPECT_GT(report["robot_time_s"].get<double>(), 0.0);
  for (const char* f : {"unloading.svg", "scene_side.svg", "scene_top.svg"})
    EXPECT_TRUE(fs::exists(dir_ / f)) << f;
  const auto snaps = kernel_.requests("sim/snapshot");
  ASSERT_FALSE(snaps.empty());
  for (const auto& s : snaps) EXPECT_EQ(s.as<msg::SnapshotRequest>()->name()->str(), "checkpoint");
  EXPECT_FALSE(kernel_.published("executor/status").empty());
}

// Ctrl-C, SIGTERM, --duration or a lost host stop the executor before the
// job is done: its figures were lost (no report.json). Now they are
// reported after every action and when it stops.
TEST_F(Executor, AStoppedRunKeepsItsFiguresInTheReport) {
  FakeSim sim(small_wall());
  FakePlanner planner;
  sim.serve(kernel_);
  planner.serve(kernel_);
  auto h =
      kernel_.load_node(STRATEGY_HARDCODED_SO,
                        NodeOptions()
                            .with_name("strategy")
                            .with_params(R"({"observation": )" + std::string(kObservation) + "}"));
  ASSERT_TRUE(h) << h.error().message;
  ASSERT_TRUE(h->configure());
  ASSERT_TRUE(h->activate());
  auto n = kernel_.load_node(
      STRATEGY_EXECUTOR_SO,
      NodeOptions()
          .with_name("executor")
          .with_params(
              R"({"report_dir": ")" + dir_.string() +
              R"(", "progress": false, "retry_ms": 1, "service_wait_s": 5, "observation": )" +
              kObservation + "}"));
  ASSERT_TRUE(n) << n.error().message;
  ASSERT_TRUE(n->configure());
  ASSERT_TRUE(n->activate());
  // Until the first action is done and reported.
  for (int i = 0; i < 60000 && kernel_.published("pipeline/report").empty(); ++i) {
    kernel_.spin();
    kernel_.wait_published("pipeline/done", 1, std::chrono::milliseconds(1));
  }
  ASSERT_FALSE(kernel_.published("pipeline/report").empty());
  EXPECT_TRUE(n->deactivate());
  EXPECT_TRUE(kernel_.published("pipeline/done").empty()) << "stopped, not done";
  const auto report = reported();
  EXPECT_EQ(report["stop_reason"], "stopped");
  EXPECT_EQ(report["boxes_total"], 6);
  EXPECT_GE(report["actions"]["pick"]["executions"].get<int>() +
                report["actions"]["sweep"]["executions"].get<int>(),
            1);
  EXPECT_GT(report["robot_time_s"].get<double>(), 0.0);
}

TEST_F(Executor, SweepsADeepPileWithStrategyH) {
  // Three rows of low boxes, 1.2 m deep (> d_min) and nothing behind: H
  // sweeps; the scoop takes what its tip passes.
  sim::World w;
  std::uint32_t id = 1;
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      w.boxes.push_back(
          sim::testing::make_box(id++, 5.2 + r * 0.41, (c - 1) * 0.41, 0.0, {0.4, 0.4, 0.3}));
  FakeSim sim(w);
  FakePlanner planner;
  sim.serve(kernel_);
  planner.serve(kernel_);
  const auto report = run();
  EXPECT_TRUE(done_ok_) << done_reason_;
  EXPECT_EQ(report["boxes_unloaded"], 9);
  EXPECT_GE(report["actions"]["sweep"]["executions"], 1);
  EXPECT_GT(report["actions"]["sweep"]["boxes"], 0);
  EXPECT_GT(report["actions"]["sweep"]["boxes_per_s"], 0.0);
}

TEST_F(Executor, PlannerGapLosesNoQuery) {
  FakeSim sim(small_wall());
  FakePlanner planner;
  planner.unavailable_first = 5;
  sim.serve(kernel_);
  planner.serve(kernel_);
  const auto report = run();
  EXPECT_TRUE(done_ok_) << done_reason_;
  EXPECT_EQ(report["boxes_unloaded"], 6);
  int answered = 0;
  for (int m = 1; m <= 6; ++m) answered += planner.answered(m);
  EXPECT_EQ(planner.calls(), answered + 5);
  int counted = 0;
  for (int m = 1; m <= 6; ++m)
    counted += report["planner_modes"]["M" + std::to_string(m)]["queries"].get<int>();
  EXPECT_EQ(counted, answered);  // each query counted once, none failed
}

TEST_F(Executor, RepeatsTheActionASimulatorCrashInterrupted) {
  FakeSim sim(small_wall());
  sim.crash_at_execute = 6;  // inside the first pick, with a box held
  FakePlanner planner;
  sim.serve(kernel_);
  planner.serve(kernel_);
  const auto report = run();
  EXPECT_TRUE(done_ok_) << done_reason_;
  EXPECT_EQ(sim.restores(), 1);
  const auto restores = kernel_.requests("sim/restore");
  ASSERT_EQ(restores.size(), 1u);
  EXPECT_EQ(restores[0].as<msg::SnapshotRequest>()->name()->str(), "checkpoint");
  EXPECT_EQ(report["recoveries"], 1);
  // No box appeared or vanished.
  EXPECT_EQ(report["boxes_unloaded"], 6);
  EXPECT_EQ(sim.state().unloaded + sim.state().world.boxes.size(), 6u);
}

TEST_F(Executor, NoticesASimulatorThatRestartedBetweenCalls) {
  // No call fails: the executor sees the simulator's clock go back.
  FakeSim sim(small_wall());
  sim.restart_after_execute = 14;  // inside the second pick, after its checkpoint
  FakePlanner planner;
  sim.serve(kernel_);
  planner.serve(kernel_);
  const auto report = run();
  EXPECT_TRUE(done_ok_) << done_reason_;
  EXPECT_EQ(report["recoveries"], 1);
  EXPECT_EQ(sim.restores(), 1);
  EXPECT_EQ(report["boxes_unloaded"], 6);
  EXPECT_EQ(sim.state().unloaded + sim.state().world.boxes.size(), 6u);
}

// Trailer after trailer (a shift's worth; bench_soak): each is reset,
// checkpointed, unloaded and reported, with what the simulator holds at its
// end. A simulator that restarts just after a reset resumes the trailer
// before from its checkpoint: the executor sees it and resets again.
TEST_F(Executor, UnloadsTrailerAfterTrailerAndResetsAgainASimulatorThatRestarted) {
  FakeSim sim(small_wall());
  add_two_trailers(sim);
  sim.restart_after_reset = 3;  // the first trailer of the second cycle
  FakePlanner planner;
  sim.serve(kernel_);
  planner.serve(kernel_);
  const auto report =
      run(R"(, "trailers": [{"world_file": "six"}, {"world_file": "four"}], "cycles": 2)");
  EXPECT_TRUE(done_ok_) << done_reason_;
  EXPECT_EQ(done_reason_, "4 trailers done: 20/20 boxes unloaded");
  EXPECT_EQ(kernel_.requests("sim/reset").size(), 5u);
  ASSERT_TRUE(report.contains("trailers")) << report.dump(1);
  ASSERT_EQ(report["trailers"].size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) {
    const auto& t = report["trailers"][i];
    const int total = i % 2 == 0 ? 6 : 4;
    EXPECT_EQ(t["name"], i % 2 == 0 ? "six" : "four");
    EXPECT_EQ(t["boxes_total"], total) << t.dump();
    EXPECT_EQ(t["boxes_unloaded"], total) << t.dump();
    EXPECT_EQ(t["sim_boxes_unloaded"], total) << t.dump();
    EXPECT_EQ(t["sim_boxes_left"], 0) << t.dump();
    EXPECT_EQ(t["stop_reason"], "trailer empty") << t.dump();
    // The start that was unloaded, not the one the restart undid.
    EXPECT_EQ(t["start_checkpoint_bytes"], FakeSim::kCheckpointBytesPerBox * total) << t.dump();
  }
}

// bench_soak, 120 min: the disk refused the next trailer's checkpoint, the
// executor went on, and a kill made the simulator resume the trailer before,
// which the executor unloaded as this one. A trailer now starts only once
// its checkpoint is written.
TEST_F(Executor, ATrailerStartsOnlyOnceItsCheckpointIsWritten) {
  FakeSim sim(small_wall());
  add_two_trailers(sim);
  sim.refuse_after_reset = 2;  // "four"
  sim.snapshots_refused = 3;
  sim.restart_after_reset_execute = 1;
  FakePlanner planner;
  sim.serve(kernel_);
  planner.serve(kernel_);
  unloads_six_then_four();
  EXPECT_EQ(sim.restores(), 1);
}

bool logged(const FakeKernel& k, const std::string& text) {
  for (const auto& l : k.logs())
    if (l.node == "executor" && l.text.find(text) != std::string::npos) return true;
  return false;
}

// A simulator that comes back with another trailer's world (its checkpoint
// lost) is reset to the trailer being unloaded, which starts again, rather
// than resumed: its boxes would be counted as this trailer's.
TEST_F(Executor, ASimulatorBackWithAnotherTrailersWorldIsResetNotResumed) {
  FakeSim sim(small_wall());
  add_two_trailers(sim);
  sim.restart_into_first_trailer_after_reset = 2;  // "four" restarts into "six"
  FakePlanner planner;
  sim.serve(kernel_);
  planner.serve(kernel_);
  unloads_six_then_four();
  EXPECT_TRUE(logged(kernel_, "another trailer's world (6 boxes, 0 unloaded; the trailer has 4)"));
}

TEST_F(Executor, FailedGraspsEndInNoProgress) {
  FakeSim sim(small_wall());
  sim.suction_works = false;
  FakePlanner planner;
  sim.serve(kernel_);
  planner.serve(kernel_);
  const auto report = run(R"(, "max_idle_actions": 3)");
  EXPECT_EQ(done_reason_, "no progress in 3 actions: 0/6 boxes unloaded");
  EXPECT_EQ(report["boxes_unloaded"], 0);
  EXPECT_EQ(report["failed_grasps"], 3);
  EXPECT_EQ(report["actions"]["pick"]["executions"], 3);
}

// The small wall with its bottom middle box swapped for a heavy one with a
// 0.29 m face (as B1's 15 kg boxes): the plate centred on it covers two cups,
// which hold its weight but not the fast retract.
sim::World wall_with_heavy_box(double mass) {
  sim::World w;
  sim::testing::add_wall(w, 5.0, 3, 2);
  for (auto& b : w.boxes) b.mass = 5.0;
  auto& heavy = *std::find_if(w.boxes.begin(), w.boxes.end(), [](const sim::Box& b) {
    return std::abs(b.pose.translation().y()) < 0.01 && b.pose.translation().z() < 0.3;
  });
  heavy = sim::testing::make_box(heavy.id, 5.2, 0.0, 0.0, {0.4, 0.29, 0.29});
  heavy.mass = mass;
  return w;
}

TEST_F(Executor, GripsADroppedBoxWithMoreCupsAndASlowerCarry) {
  FakeSim sim(wall_with_heavy_box(16.0));
  sim.cup_force = 90.0;
  FakePlanner planner;
  sim.serve(kernel_);
  planner.serve(kernel_);
  const auto report = run();
  // Before, the same centred grip was retried until no progress was left.
  EXPECT_EQ(done_reason_, "trailer empty: 6/6 boxes unloaded");
  EXPECT_GE(sim.drops(), 1);
  EXPECT_GE(report["failed_grasps"], 1);
  EXPECT_TRUE(logged(kernel_, "(attempt 2 of 3): 6 cups, carried at 1/2 of the speed"));
}

TEST_F(Executor, GivesUpABoxNoGripHoldsAndUnloadsTheOthers) {
  FakeSim sim(wall_with_heavy_box(40.0));  // 392 N: more than all 4 cups that fit its face
  sim.cup_force = 90.0;
  FakePlanner planner;
  sim.serve(kernel_);
  planner.serve(kernel_);
  const auto report = run(R"(, "max_idle_actions": 3)");
  EXPECT_EQ(done_reason_, "no progress in 3 actions: 5/6 boxes unloaded");
  // Refused with the 6 cups that fit its face; no pose covers more: given up.
  EXPECT_EQ(report["failed_grasps"], 1);
  ASSERT_EQ(report["boxes_left"].size(), 1u);
  EXPECT_EQ(report["boxes_left"][0]["reason"], "given up");
  EXPECT_EQ(report["boxes_left_by_reason"]["given up"], 1);
  EXPECT_TRUE(logged(kernel_, "left in the trailer: 1 box (given up: 1)"));
}

TEST_F(Executor, FollowsTheStrategyTreeAndAsksAgainWhenItEnds) {
  FakeSim sim(small_wall());
  FakePlanner planner;
  sim.serve(kernel_);
  planner.serve(kernel_);
  // Pick(low, center), then on any observation Pick(low, center) again, then the tree ends.
  int asked = 0;
  kernel_.fake_service<msg::NextStrategyRequest, msg::NextStrategyReply>(
      "strategy/next",
      [&](const msg::NextStrategyRequest& r, flatbuffers::FlatBufferBuilder& fbb) -> Status {
        ++asked;
        EXPECT_TRUE(verify<msg::WorldState>(r.world()->data(), r.world()->size()));
        sim::Strategy s;
        s.name = "tree";
        s.nodes.push_back({sim::Action::PickLowCenter, {}});
        for (int o = 0; o < sim::kNumObservations; ++o) {
          s.nodes[0].children.emplace_back(static_cast<sim::Observation>(o), o + 1);
          s.nodes.push_back({sim::Action::PickLowCenter, {}});
        }
        fbb.Finish(msg::CreateNextStrategyReply(fbb, sim::build(fbb, s), fbb.CreateString("test")));
        return {};
      });
  const auto report = run(R"(, "max_actions": 4)", false);
  EXPECT_EQ(done_reason_.rfind("action limit (4)", 0), 0u) << done_reason_;
  // #1 the root, #2 its child (a step along the tree), then the tree ends:
  // asked again; #3 finds the low boxes gone (what is left is a pile of
  // the high class), and after an action that moved nothing the tree is not
  // followed: asked again for #4.
  EXPECT_EQ(asked, 3);
  EXPECT_EQ(report["strategies_asked"], 3);
  EXPECT_EQ(report["strategy_steps"], 1);
  EXPECT_EQ(report["not_applicable"], 2);
  EXPECT_GE(report["boxes_unloaded"], 2);
}

TEST_F(Executor, RefusesBadParams) {
  auto n = kernel_.load_node(STRATEGY_EXECUTOR_SO,
                             NodeOptions().with_params(R"({"nose_home": [0.5, 0]})"));
  ASSERT_TRUE(n);
  auto s = n->configure();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().message, "param 'nose_home': expected 3 joint values");
  auto m =
      kernel_.load_node(STRATEGY_EXECUTOR_SO,
                        NodeOptions().with_name("e2").with_params(R"({"urdf": "/no/such.urdf"})"));
  ASSERT_TRUE(m);
  s = m->configure();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().message.rfind("param 'urdf': /no/such.urdf", 0), 0u) << s.error().message;
  auto both = kernel_.load_node(
      STRATEGY_EXECUTOR_SO,
      NodeOptions().with_name("e3").with_params(
          R"({"trailers": [{"world_file": "a.yaml"}, {"env": "A1", "world_file": "b.yaml"}]})"));
  ASSERT_TRUE(both);
  s = both->configure();
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().message, "param 'trailers[1]': give 'env' (and 'seed') or 'world_file'");
}

#ifdef PLANNER_ARASTAR_SO
// The executor's geometry against the real ARA* planner: every sub-action of
// every action has to be plannable in the small test world.
TEST_F(Executor, UnloadsTheSmallWorldWithTheRealPlanner) {
  auto world = sim::load_world(SMALL_WORLD);
  ASSERT_TRUE(world) << world.error().message;
  FakeSim sim(std::move(*world));
  sim.serve(kernel_);
  auto planner = kernel_.load_node(PLANNER_ARASTAR_SO, NodeOptions().with_name("planner"));
  ASSERT_TRUE(planner) << planner.error().message;
  ASSERT_TRUE(planner->configure());
  ASSERT_TRUE(planner->activate());
  const auto report = run(R"(, "max_actions": 40)", true, 600000);
  EXPECT_TRUE(done_ok_) << done_reason_;
  std::cerr << report.dump(1) << "\n";
  // A floor, not the goal (>= 27): with a kinematic simulator nothing falls
  // or slides, and the side boxes of the middle row are out of reach for a
  // 4-DOF arm with a 0.5 m plate in a 0.46 m grid (docs/executor.md).
  EXPECT_GE(report["boxes_unloaded"].get<int>(), 7) << done_reason_;
  EXPECT_EQ(report["robot_trailer_collisions"].get<int>(), 0);
  for (int m = 1; m <= 5; ++m) {
    const auto& mode = report["planner_modes"]["M" + std::to_string(m)];
    EXPECT_GT(mode["queries"].get<int>(), 0) << "M" << m;
    EXPECT_LT(mode["failures"].get<double>(), 0.5 * mode["queries"].get<double>()) << "M" << m;
  }
}
#endif

}  // namespace
}  // namespace plr
