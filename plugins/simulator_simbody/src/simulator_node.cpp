// The simulator plug-in: a trailer of boxes under Simbody physics, the robot
// moved kinematically along planned trajectories, suction and conveyor.
// Services and topics as in docs/services.md. Simulated time is published on
// `clock`, so a pipeline with `clock: sim` runs on it.
#include "checkpoint.hpp"
#include "world_message.hpp"

#include <plr/actions/motion_messages.hpp>
#include <plr/actions/unloader_simulation.hpp>
#include <plr/interface.hpp>
#include <plr/messages.hpp>
#include <plr/node.hpp>
#include <plr/plugin.hpp>
#include <plr/sim/fidelity.hpp>
#include <plr/sim/generators.hpp>
#include <plr/sim/physics.hpp>
#include <plr/sim/robot_model.hpp>
#include <plr/sim/world_io.hpp>

#include <chrono>
#include <map>
#include <memory>
#include <optional>
#include <thread>
#include <tuple>

namespace plr::simulator {
namespace {

using actions::home_configuration;

class SimulatorNode : public Node {
 public:
  using Node::Node;

 protected:
  Status on_configure() override {
    params().allow_only({"urdf", "octree_resolution", "control_period_s", "belt_speed",
                         "checkpoint_dir", "max_settle_s", "carry_max_s", "frame_rate_hz",
                         "real_time_factor", "fidelity"});
    auto robot = sim::load_robot(params().get<std::string>("urdf", ""));
    if (!robot) return make_error(PLR_ERR_INVALID, "param 'urdf': " + robot.error().message);
    model_.emplace(std::move(*robot));
    resolution_ = params().get<double>("octree_resolution", 0.05);
    period_ = params().get<double>("control_period_s", 0.01);
    belt_speed_ = params().get<double>("belt_speed", 0.8);
    checkpoint_dir_ = params().get<std::string>("checkpoint_dir", "");
    max_settle_ = params().get<double>("max_settle_s", 6.0);
    carry_max_ = params().get<double>("carry_max_s", 4.0);
    frame_rate_ = params().get<double>("frame_rate_hz", 10.0);
    real_time_factor_ = params().get<double>("real_time_factor", 0.0);
    auto fidelity = sim::parse_fidelity(params().get<std::string>("fidelity", "full"));
    if (!fidelity) return make_error(PLR_ERR_INVALID, "param " + fidelity.error().message);
    fidelity_ = *fidelity;
    // Bounds, so no value makes memory or time grow without end: an octree at
    // 0.1 mm of a trailer does not fit in memory, and at a control period of
    // 1e-7 s an action never ended.
    for (const auto& [name, value, lo, hi] :
         {std::tuple{"octree_resolution", resolution_, 0.01, 0.5},
          std::tuple{"control_period_s", period_, 0.001, 0.1},
          std::tuple{"belt_speed", belt_speed_, 0.0, 5.0},
          std::tuple{"max_settle_s", max_settle_, 0.0, 60.0},
          std::tuple{"carry_max_s", carry_max_, 0.0, 60.0},
          std::tuple{"frame_rate_hz", frame_rate_, 0.0, 100.0},
          std::tuple{"real_time_factor", real_time_factor_, 0.0, 1000.0}}) {
      if (!(value >= lo && value <= hi))
        return make_error(
            PLR_ERR_INVALID,
            fmt::format("param '{}': must be between {} and {}, got {}", name, lo, hi, value));
    }

    auto world = ctx().advertise<msg::WorldState>("world");
    auto progress = ctx().advertise<msg::Progress>("progress");
    auto clock = ctx().advertise<msg::Clock>("clock");
    if (!world) return world.error();
    if (!progress) return progress.error();
    if (!clock) return clock.error();
    world_pub_ = *world;
    progress_pub_ = *progress;
    clock_pub_ = *clock;

    using FB = flatbuffers::FlatBufferBuilder;
    Status s = ctx().provide<msg::ResetRequest, msg::WorldState>(
        "sim/reset",
        [this](const Message<msg::ResetRequest>& r, FB& out) { return reset(*r, out); });
    if (s)
      s = ctx().provide<msg::ObserveRequest, msg::WorldState>(
          "sim/observe", [this](const Message<msg::ObserveRequest>& r, FB& out) {
            return observe(r->true_state(), out);
          });
    if (s)
      s = ctx().provide<msg::ExecuteRequest, msg::ExecuteOutcome>(
          "sim/execute",
          [this](const Message<msg::ExecuteRequest>& r, FB& out) { return execute(*r, out); });
    if (s)
      s = ctx().provide<msg::SnapshotRequest, msg::SnapshotReply>(
          "sim/snapshot", [this](const Message<msg::SnapshotRequest>& r, FB& out) {
            return snapshot(name_of(*r), out);
          });
    if (s)
      s = ctx().provide<msg::SnapshotRequest, msg::SnapshotReply>(
          "sim/restore", [this](const Message<msg::SnapshotRequest>& r, FB& out) {
            return restore(name_of(*r), out);
          });
    if (!s) return s;

    // A restarted simulator process picks up the run at its last checkpoint.
    if (!checkpoint_dir_.empty()) {
      auto c = load_checkpoint(checkpoint_dir_);
      if (!c) return c.error();
      if (*c) {
        const Checkpoint& resumed = **c;
        start(resumed.world, resumed.robot, resumed.boxes_total, resumed.boxes_unloaded);
        log().info("resumed from checkpoint in {} ({} boxes left, {} unloaded)", checkpoint_dir_,
                   resumed.world.boxes.size(), resumed.boxes_unloaded);
      }
    }
    return {};
  }

  Status on_cleanup() override {
    sim_.reset();
    saved_.clear();
    return {};
  }

 private:
  static std::string name_of(const msg::SnapshotRequest& r) {
    return r.name() ? r.name()->str() : "default";
  }

  void start(const sim::World& world, const RobotState& robot, std::uint32_t total,
             std::uint32_t unloaded) {
    actions::UnloaderOptions options;
    options.control_period_s = period_;
    options.belt_speed = belt_speed_;
    options.carry_max_s = carry_max_;
    options.fidelity = fidelity_;
    sim_ = std::make_unique<actions::UnloaderSimulation>(*model_, world, robot.q, options);
    boxes_total_ = total;
    unloaded_before_ = unloaded;
    octree_ = trailer_octree_bytes(world.trailer, resolution_);
    saved_.clear();
  }

  std::uint32_t boxes_unloaded() const { return unloaded_before_ + sim_->boxes_unloaded(); }

  RobotState robot_state() const { return {sim_->q(), sim_->held()}; }

  Status reset(const msg::ResetRequest& r, flatbuffers::FlatBufferBuilder& out) {
    sim::World world;
    std::optional<sim::EnvFamily> family;
    if (r.world_file() && r.world_file()->size() > 0) {
      auto loaded = sim::load_world(r.world_file()->str());
      if (!loaded) return make_error(PLR_ERR_INVALID, loaded.error().message);
      world = std::move(*loaded);
    } else {
      const std::string env = r.env() ? r.env()->str() : "A1";
      family = sim::parse_env_family(env);
      if (!family)
        return make_error(PLR_ERR_INVALID,
                          "env '" + env + "': expected " + sim::env_family_names());
    }
    // The physics throws, on a world it cannot simulate (a box without mass) and from Simbody.
    try {
      if (family) world = sim::make_environment(*family, r.seed(), {}, max_settle_);
      start(world, {home_configuration(), {}}, static_cast<std::uint32_t>(world.boxes.size()), 0);
    } catch (const std::exception& e) {
      return make_error(PLR_ERR_INVALID, e.what());
    }
    log().info("reset: {} boxes", world.boxes.size());
    publish_state();
    return observe(false, out);
  }

  Status observe(bool true_state, flatbuffers::FlatBufferBuilder& out) {
    // Before the first reset the trailer is empty: callers can wait for the
    // simulator to answer before they ask for a world.
    if (!sim_) {
      build_world_state(out, sim::World{}, {home_configuration(), {}}, "", resolution_, 0,
                        true_state, 0);
      return {};
    }
    build_world_state(out, sim_->truth(), robot_state(), octree_, resolution_, boxes_unloaded(),
                      true_state, static_cast<std::int64_t>(sim_->time() * 1e9));
    return {};
  }

  Status execute(const msg::ExecuteRequest& r, flatbuffers::FlatBufferBuilder& out) {
    if (!sim_) return make_error(PLR_ERR_STATE, "no world yet: call sim/reset first");
    auto motion = actions::decode_execute_request(r);
    if (!motion) return make_error(PLR_ERR_INVALID, motion.error().message);
    const auto wall_start = std::chrono::steady_clock::now();
    auto done = sim_->execute(*motion, frames(wall_start));
    if (!done) return make_error(done.error().code, done.error().message);
    for (const auto& e : done->suction)
      log().info("box {} {} at t={:.2f} s: the cups had to hold {:.0f} N, can hold {:.0f} N",
                 e.box_id, e.kind == sim::SuctionEvent::Kind::kDropped ? "dropped" : "not gripped",
                 e.time, e.load, e.capacity);
    if (done->stalled)
      log().info("the base stalled {:.2f} s into the motion: the boxes pushed back with {:.0f} N",
                 done->stall_after_s, done->stall_force);
    log().debug(
        "execute: {} points, {:.2f} s simulated in {:.2f} s, {} unloaded", motion->points.size(),
        motion->points.empty() ? 0.0 : motion->points.back().time_s,
        std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count(),
        done->unloaded.size());
    encode_execute_outcome(*done, static_cast<std::uint32_t>(sim_->truth().boxes.size()), out);
    publish_state();
    return {};
  }

  // During a motion: the world published at most frame_rate_hz times a
  // second of wall time, so a live view moves with the robot rather than
  // jumping from motion to motion; with a real_time_factor the motion is
  // also held to that pace (1: as fast as the real robot would move).
  actions::UnloaderSimulation::PeriodObserver frames(
      std::chrono::steady_clock::time_point wall_start) {
    if (frame_rate_ <= 0.0 && real_time_factor_ <= 0.0) return {};
    const double sim_start = sim_->time();
    return [this, wall_start, sim_start,
            last = std::chrono::steady_clock::time_point{}](const sim::JointVector& q) mutable {
      using Seconds = std::chrono::duration<double>;
      if (real_time_factor_ > 0.0)
        std::this_thread::sleep_until(
            wall_start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                             Seconds((sim_->time() - sim_start) / real_time_factor_)));
      const auto now = std::chrono::steady_clock::now();
      if (frame_rate_ > 0.0 && now - last >= Seconds(1.0 / frame_rate_)) {
        last = now;
        publish_state({q, sim_->held()});
      }
    };
  }

  Status snapshot(const std::string& name, flatbuffers::FlatBufferBuilder& out) {
    if (!sim_) return make_error(PLR_ERR_STATE, "no world yet: call sim/reset first");
    saved_.insert_or_assign(name, sim_->save());
    std::uint64_t on_disk = 0;
    if (name == "checkpoint" && !checkpoint_dir_.empty()) {
      const auto saved = save_checkpoint(
          checkpoint_dir_,
          {sim_->truth(), robot_state(), sim_->time(), boxes_total_, boxes_unloaded()});
      if (!saved) return make_error(PLR_ERR_INTERNAL, saved.error().message);
      on_disk = *saved;
    }
    out.Finish(msg::CreateSnapshotReplyDirect(out, true, "", name.c_str(), on_disk));
    return {};
  }

  Status restore(const std::string& name, flatbuffers::FlatBufferBuilder& out) {
    if (auto it = saved_.find(name); it != saved_.end() && sim_) {
      sim_->restore(*it->second);
    } else if (name == "checkpoint" && !checkpoint_dir_.empty()) {
      auto c = load_checkpoint(checkpoint_dir_);
      if (!c) return make_error(c.error().code, c.error().message);
      if (!*c) return make_error(PLR_ERR_INVALID, "no checkpoint in " + checkpoint_dir_);
      const Checkpoint& restored = **c;
      start(restored.world, restored.robot, restored.boxes_total, restored.boxes_unloaded);
    } else {
      return make_error(PLR_ERR_INVALID, "no snapshot named '" + name + "'");
    }
    publish_state();
    out.Finish(msg::CreateSnapshotReplyDirect(out, true, "", name.c_str()));
    return {};
  }

  void publish_state() { publish_state(robot_state()); }

  void publish_state(const RobotState& robot) {
    flatbuffers::FlatBufferBuilder w;
    build_world_state(w, sim_->truth(), robot, octree_, resolution_, boxes_unloaded(), false,
                      static_cast<std::int64_t>(sim_->time() * 1e9));
    (void)world_pub_.publish(w);
    flatbuffers::FlatBufferBuilder p;
    p.Finish(msg::CreateProgress(p, sim_->time(), boxes_total_, boxes_unloaded()));
    (void)progress_pub_.publish(p);
    flatbuffers::FlatBufferBuilder c;
    c.Finish(msg::CreateClock(c, static_cast<std::int64_t>(sim_->time() * 1e9)));
    (void)clock_pub_.publish(c);
  }

  std::optional<sim::RobotModel> model_;
  double resolution_ = 0.05;
  double period_ = 0.01;
  double belt_speed_ = 0.8;
  double max_settle_ = 6.0;
  double carry_max_ = 4.0;
  sim::Fidelity fidelity_ = sim::Fidelity::kFull;
  double frame_rate_ = 10.0;
  double real_time_factor_ = 0.0;
  std::string checkpoint_dir_;
  std::unique_ptr<actions::UnloaderSimulation> sim_;
  std::string octree_;
  std::uint32_t boxes_total_ = 0;
  std::uint32_t unloaded_before_ = 0;
  std::map<std::string, std::shared_ptr<const actions::UnloaderSimulation::Saved>> saved_;
  Publisher<msg::WorldState> world_pub_;
  Publisher<msg::Progress> progress_pub_;
  Publisher<msg::Clock> clock_pub_;
};

}  // namespace
}  // namespace plr::simulator

PLR_PLUGIN(plr::simulator::SimulatorNode, "simulator_simbody", "0.1.0", PLR_KIND_SIMULATOR,
           "Simbody physics of a trailer of boxes, the robot, suction and conveyor")
PLR_INTERFACE(plr::topic<plr::msg::WorldState>("world"), plr::topic<plr::msg::Progress>("progress"),
              plr::topic<plr::msg::Clock>("clock"),
              plr::service<plr::msg::ResetRequest, plr::msg::WorldState>("sim/reset"),
              plr::service<plr::msg::ObserveRequest, plr::msg::WorldState>("sim/observe"),
              plr::service<plr::msg::ExecuteRequest, plr::msg::ExecuteOutcome>("sim/execute"),
              plr::service<plr::msg::SnapshotRequest, plr::msg::SnapshotReply>("sim/snapshot"),
              plr::service<plr::msg::SnapshotRequest, plr::msg::SnapshotReply>("sim/restore"))
