// The simulator plug-in: a trailer of boxes under Simbody physics, the robot
// moved kinematically along planned trajectories, suction and conveyor.
// Services and topics as in docs/services.md. Simulated time is published on
// `clock`, so a pipeline with `clock: sim` runs on it.
#include "checkpoint.hpp"
#include "world_message.hpp"

#include <plr/messages.hpp>
#include <plr/node.hpp>
#include <plr/plugin.hpp>
#include <plr/sim/generators.hpp>
#include <plr/sim/physics.hpp>
#include <plr/sim/robot_links.hpp>
#include <plr/sim/robot_model.hpp>
#include <plr/sim/world_io.hpp>

#include <algorithm>
#include <chrono>
#include <map>
#include <memory>
#include <optional>
#include <set>

namespace plr::simulator {
namespace {

using msg::Suction;

// How far (rad or m, any joint) a trajectory may start from the robot's
// configuration: planners start from the observed one, exactly.
constexpr double kStartTolerance = 1e-4;

// Where the robot starts: base front edge at the trailer's open rear, arm
// folded, nose raised (see docs/notes-planner.md).
sim::JointVector home_configuration() {
  sim::JointVector q;
  q << 0.0, 0.0, -1.0, 2.0, 0.0, 0.5, 0.0, 0.0;
  return q;
}

struct Saved {
  sim::Snapshot snapshot;
  RobotState robot;
  std::uint32_t boxes_unloaded = 0;
};

class SimulatorNode : public Node {
 public:
  using Node::Node;

 protected:
  Status on_configure() override {
    params().allow_only({"urdf", "octree_resolution", "control_period_s", "belt_speed",
                         "checkpoint_dir", "max_settle_s", "carry_max_s"});
    auto robot = sim::load_robot(params().get<std::string>("urdf", ""));
    if (!robot) return make_error(PLR_ERR_INVALID, "param 'urdf': " + robot.error().message);
    model_.emplace(std::move(*robot));
    resolution_ = params().get<double>("octree_resolution", 0.05);
    period_ = params().get<double>("control_period_s", 0.01);
    belt_speed_ = params().get<double>("belt_speed", 0.8);
    checkpoint_dir_ = params().get<std::string>("checkpoint_dir", "");
    max_settle_ = params().get<double>("max_settle_s", 6.0);
    carry_max_ = params().get<double>("carry_max_s", 4.0);
    if (resolution_ <= 0 || period_ <= 0 || belt_speed_ < 0)
      return make_error(
          PLR_ERR_INVALID,
          "params 'octree_resolution', 'control_period_s' must be > 0, 'belt_speed' >= 0");

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
      if (auto c = load_checkpoint(checkpoint_dir_)) {
        start(c->world, c->robot, c->boxes_total, c->boxes_unloaded);
        log().info("resumed from checkpoint in {} ({} boxes left, {} unloaded)", checkpoint_dir_,
                   c->world.boxes.size(), c->boxes_unloaded);
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
    sim_ = std::make_unique<sim::Simulation>(world);
    robot_ = robot;
    boxes_total_ = total;
    unloaded_before_ = unloaded;
    octree_ = trailer_octree_bytes(world.trailer, resolution_);
    saved_.clear();
    move_robot(robot_.q, false);
  }

  std::uint32_t boxes_unloaded() const {
    return unloaded_before_ + static_cast<std::uint32_t>(sim_->unloaded().size());
  }

  Status reset(const msg::ResetRequest& r, flatbuffers::FlatBufferBuilder& out) {
    sim::World world;
    try {
      if (r.world_file() && r.world_file()->size() > 0) {
        world = sim::load_world(r.world_file()->str());
      } else {
        const std::string env = r.env() ? r.env()->str() : "A1";
        auto family = sim::parse_env_family(env);
        if (!family)
          return make_error(PLR_ERR_INVALID,
                            "sim/reset: env '" + env + "': expected A1, A2, B1 or B2");
        world = sim::make_environment(*family, r.seed(), {}, max_settle_);
      }
    } catch (const std::exception& e) {
      return make_error(PLR_ERR_INVALID, std::string("sim/reset: ") + e.what());
    }
    start(world, {home_configuration(), {}}, static_cast<std::uint32_t>(world.boxes.size()), 0);
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
    robot_.held = sim_->held_boxes();
    build_world_state(out, sim_->world(), robot_, octree_, resolution_, boxes_unloaded(),
                      true_state, static_cast<std::int64_t>(sim_->time() * 1e9));
    return {};
  }

  // Robot links and plate follow q; the belt runs while the conveyor is on.
  void move_robot(const sim::JointVector& q, bool conveyor) {
    sim_->set_robot_links(sim::robot_link_geometry(*model_, q, conveyor ? belt_speed_ : 0.0));
    sim_->set_suction_plate(sim::suction_plate_at(*model_, q));
  }

  // Robot shapes beyond the side walls, the ceiling or the front wall (the
  // floor is where the scoop works, so touching it is not counted).
  bool touches_trailer() const {
    const auto& t = sim_->trailer();
    for (const auto& link : sim_->robot_links()) {
      Eigen::Vector3d half = link.size / 2;
      if (link.shape == sim::LinkGeometry::Shape::kCylinder)
        half = Eigen::Vector3d(link.size.x(), link.size.x(), link.size.z() / 2);
      for (int c = 0; c < 8; ++c) {
        const Eigen::Vector3d local((c & 1 ? 1 : -1) * half.x(), (c & 2 ? 1 : -1) * half.y(),
                                    (c & 4 ? 1 : -1) * half.z());
        const Eigen::Vector3d p = link.pose * local;
        if (p.x() < 0) continue;  // outside the trailer, behind its open rear
        if (std::abs(p.y()) > t.width / 2 || p.z() > t.height || p.x() > t.depth) return true;
      }
    }
    return false;
  }

  // A box not held whose centre is over a running belt, at most a box
  // height above its surface.
  bool belt_loaded() const {
    const auto held = sim_->held_boxes();
    for (const auto& box : sim_->world().boxes) {
      if (std::find(held.begin(), held.end(), box.id) != held.end()) continue;
      for (const auto& link : sim_->robot_links()) {
        if (link.belt_speed <= 0.0) continue;
        const Eigen::Vector3d local = link.pose.inverse() * box.pose.translation();
        if (std::abs(local.x()) < link.size.x() / 2 && std::abs(local.y()) < link.size.y() / 2 &&
            local.z() > 0.0 && local.z() < link.size.z() / 2 + box.size.maxCoeff())
          return true;
      }
    }
    return false;
  }

  void apply_suction(Suction s, std::set<std::uint32_t>& gripped) {
    if (s == Suction::On) {
      for (auto id : sim_->suction_on()) gripped.insert(id);
    } else if (s == Suction::Off) {
      sim_->suction_off();
    }
  }

  Status execute(const msg::ExecuteRequest& r, flatbuffers::FlatBufferBuilder& out) {
    if (!sim_) return make_error(PLR_ERR_STATE, "no world yet: call sim/reset first");
    std::vector<std::pair<double, sim::JointVector>> points;
    if (const auto* traj = r.trajectory(); traj && traj->points()) {
      for (const auto* p : *traj->points()) {
        if (!p->positions() || p->positions()->size() != sim::kNumJoints)
          return make_error(PLR_ERR_INVALID,
                            "sim/execute: every trajectory point needs 8 positions");
        sim::JointVector q;
        for (int i = 0; i < sim::kNumJoints; ++i) q[i] = p->positions()->Get(i);
        if (!points.empty() && p->time_s() < points.back().first)
          return make_error(PLR_ERR_INVALID, "sim/execute: trajectory times must not decrease");
        points.emplace_back(p->time_s(), q);
      }
    }
    // A trajectory planned from another state would make the robot jump: a
    // robot controller refuses it, and so does the simulator.
    if (!points.empty()) {
      const double off = (points.front().second - robot_.q).cwiseAbs().maxCoeff();
      if (off > kStartTolerance)
        return make_error(PLR_ERR_STATE,
                          fmt::format("sim/execute: the trajectory starts {:.4f} (rad or m) away "
                                      "from the robot's configuration",
                                      off));
    }
    const auto before = sim_->world();
    const auto events_before = sim_->unloaded().size();
    const double start_time = sim_->time();
    const auto suction_before = sim_->suction_events().size();
    const auto wall_start = std::chrono::steady_clock::now();
    std::set<std::uint32_t> gripped;
    std::uint32_t contacts = 0;
    bool touching = false;
    auto advance = [&](double dt, const sim::JointVector& q) {
      move_robot(q, r.conveyor());
      sim_->step(dt);
      const bool now = touches_trailer();
      if (now && !touching) ++contacts;
      touching = now;
    };

    apply_suction(r.suction_before(), gripped);
    for (std::size_t i = 1; i < points.size(); ++i) {
      const auto& [t0, q0] = points[i - 1];
      const auto& [t1, q1] = points[i];
      const double span = t1 - t0;
      const int steps = std::max(1, static_cast<int>(std::ceil(span / period_)));
      for (int k = 1; k <= steps; ++k) {
        const double a = static_cast<double>(k) / steps;
        advance(span / steps, q0 + a * (q1 - q0));
      }
    }
    if (!points.empty()) robot_.q = points.back().second;
    apply_suction(r.suction_after(), gripped);
    for (double t = 0; t < r.settle_s(); t += period_) advance(period_, robot_.q);
    // The belt keeps running until nothing lies on it (a real conveyor does
    // not stop between actions), bounded by carry_max_s.
    if (r.conveyor()) {
      for (double t = 0; t < carry_max_ && belt_loaded(); t += period_) advance(period_, robot_.q);
    }
    robot_.held = sim_->held_boxes();

    std::vector<std::uint32_t> moved, unloaded;
    std::vector<double> unloaded_after;
    const auto after = sim_->world();
    std::map<std::uint32_t, Eigen::Vector3d> end;
    for (const auto& b : after.boxes) end[b.id] = b.pose.translation();
    for (const auto& b : before.boxes) {
      auto it = end.find(b.id);
      if (it == end.end() || (it->second - b.pose.translation()).norm() > 0.01)
        moved.push_back(b.id);
    }
    const auto& events = sim_->unloaded();
    for (auto i = events_before; i < events.size(); ++i) {
      unloaded.push_back(events[i].box_id);
      unloaded_after.push_back(events[i].time - start_time);
    }
    const auto& suction = sim_->suction_events();
    for (auto i = suction_before; i < suction.size(); ++i) {
      const auto& e = suction[i];
      if (e.kind == sim::SuctionEvent::Kind::kDropped ||
          e.kind == sim::SuctionEvent::Kind::kRefused)
        log().info("box {} {} at t={:.2f} s: the cups had to hold {:.0f} N, can hold {:.0f} N",
                   e.box_id,
                   e.kind == sim::SuctionEvent::Kind::kDropped ? "dropped" : "not gripped", e.time,
                   e.load, e.capacity);
    }
    log().debug(
        "execute: {} points, {:.2f} s simulated in {:.2f} s, {} unloaded", points.size(),
        points.empty() ? 0.0 : points.back().first - points.front().first,
        std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count(),
        unloaded.size());

    out.Finish(msg::CreateExecuteOutcomeDirect(
        out, true, "", sim_->time(), &moved, &unloaded, &robot_.held, contacts,
        static_cast<std::uint32_t>(after.boxes.size()), &unloaded_after));
    publish_state();
    return {};
  }

  Status snapshot(const std::string& name, flatbuffers::FlatBufferBuilder& out) {
    if (!sim_) return make_error(PLR_ERR_STATE, "no world yet: call sim/reset first");
    robot_.held = sim_->held_boxes();
    saved_.insert_or_assign(name, Saved{sim_->snapshot(), robot_, boxes_unloaded()});
    if (name == "checkpoint" && !checkpoint_dir_.empty()) {
      try {
        save_checkpoint(checkpoint_dir_,
                        {sim_->world(), robot_, sim_->time(), boxes_total_, boxes_unloaded()});
      } catch (const std::exception& e) {
        return make_error(PLR_ERR_INTERNAL, std::string("sim/snapshot: ") + e.what());
      }
    }
    out.Finish(msg::CreateSnapshotReplyDirect(out, true, "", name.c_str()));
    return {};
  }

  Status restore(const std::string& name, flatbuffers::FlatBufferBuilder& out) {
    if (auto it = saved_.find(name); it != saved_.end() && sim_) {
      sim_->restore(it->second.snapshot);
      robot_ = it->second.robot;
      // The restored physics carries its own unload events; count from there.
      unloaded_before_ =
          it->second.boxes_unloaded - static_cast<std::uint32_t>(sim_->unloaded().size());
      move_robot(robot_.q, false);
    } else if (name == "checkpoint" && !checkpoint_dir_.empty()) {
      auto c = load_checkpoint(checkpoint_dir_);
      if (!c)
        return make_error(PLR_ERR_INVALID, "sim/restore: no checkpoint in " + checkpoint_dir_);
      start(c->world, c->robot, c->boxes_total, c->boxes_unloaded);
    } else {
      return make_error(PLR_ERR_INVALID, "sim/restore: no snapshot named '" + name + "'");
    }
    publish_state();
    out.Finish(msg::CreateSnapshotReplyDirect(out, true, "", name.c_str()));
    return {};
  }

  void publish_state() {
    flatbuffers::FlatBufferBuilder w;
    if (observe(false, w)) (void)world_pub_.publish(w);
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
  std::string checkpoint_dir_;
  std::unique_ptr<sim::Simulation> sim_;
  RobotState robot_;
  std::string octree_;
  std::uint32_t boxes_total_ = 0;
  std::uint32_t unloaded_before_ = 0;
  std::map<std::string, Saved> saved_;
  Publisher<msg::WorldState> world_pub_;
  Publisher<msg::Progress> progress_pub_;
  Publisher<msg::Clock> clock_pub_;
};

}  // namespace
}  // namespace plr::simulator

PLR_PLUGIN(plr::simulator::SimulatorNode, "simulator_simbody", "0.1.0", PLR_KIND_SIMULATOR,
           "Simbody physics of a trailer of boxes, the robot, suction and conveyor")
