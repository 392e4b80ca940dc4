#include "dashboard_state.hpp"

#include <plr/sim/strategy.hpp>
#include <plr/sim/unaligned.hpp>

#include <Eigen/Geometry>

namespace plr::monitor_web {

namespace {

nlohmann::json vec(const msg::Vec3* v) {
  if (v == nullptr) return {0, 0, 0};
  return {v->x(), v->y(), v->z()};
}

std::string text(const flatbuffers::String* s) {
  return s ? s->str() : std::string();
}

// An axis-aligned box: centre and half extents, what both views draw.
nlohmann::json aabb(const Eigen::Vector3d& centre, const Eigen::Vector3d& half) {
  return {{"c", {centre.x(), centre.y(), centre.z()}}, {"h", {half.x(), half.y(), half.z()}}};
}

}  // namespace

DashboardState::DashboardState(std::optional<sim::RobotModel> robot) : robot_(std::move(robot)) {}

void DashboardState::update(const msg::WorldState& w) {
  nlohmann::json j;
  j["trailer"] = vec(w.trailer_size());
  j["boxes_unloaded"] = w.boxes_unloaded();
  j["stamp_ns"] = w.stamp_ns();
  nlohmann::json boxes = nlohmann::json::array();
  if (w.boxes())
    for (flatbuffers::uoffset_t i = 0; i < w.boxes()->size(); ++i) {
      const msg::BoxState b = sim::element(*w.boxes(), i);
      const auto& p = b.pose().position();
      const auto& q = b.pose().orientation();
      const Eigen::Matrix3d r = Eigen::Quaterniond(q.w(), q.x(), q.y(), q.z()).toRotationMatrix();
      const Eigen::Vector3d size(b.size().x(), b.size().y(), b.size().z());
      auto box = aabb(Eigen::Vector3d(p.x(), p.y(), p.z()), 0.5 * r.cwiseAbs() * size);
      box["id"] = b.id();
      boxes.push_back(std::move(box));
    }
  j["boxes"] = std::move(boxes);
  nlohmann::json links = nlohmann::json::array();
  const auto* joints = w.robot() ? w.robot()->positions() : nullptr;
  if (robot_ && joints && joints->size() == sim::kNumJoints) {
    sim::JointVector q;
    for (int i = 0; i < sim::kNumJoints; ++i)
      q[i] = joints->Get(static_cast<flatbuffers::uoffset_t>(i));
    std::vector<Eigen::Isometry3d> poses;
    robot_->forward_kinematics(q, poses);
    for (std::size_t l = 0; l < robot_->links().size(); ++l)
      for (const auto& shape : robot_->links()[l].shapes) {
        const Eigen::Isometry3d at = poses[l] * shape.origin;
        links.push_back(aabb(at.translation(), sim::half_extents(shape, at)));
      }
  }
  j["robot"] = std::move(links);
  std::lock_guard lock(m_);
  world_ = std::move(j);
  ++version_;
}

void DashboardState::update(const msg::ExecutorState& e) {
  nlohmann::json j;
  j["action"] = text(e.action());
  j["subaction"] = text(e.subaction());
  j["boxes_total"] = e.boxes_total();
  j["boxes_unloaded"] = e.boxes_unloaded();
  j["robot_time_s"] = e.robot_time_s();
  j["active_node"] = e.active_node();
  nlohmann::json strategy = nullptr;
  if (const auto* s = e.strategy()) {
    strategy = {{"name", text(s->name())}, {"root", s->root()}};
    nlohmann::json nodes = nlohmann::json::array();
    if (s->nodes())
      for (const auto* n : *s->nodes()) {
        nlohmann::json children = nlohmann::json::array();
        if (n && n->children())
          for (const auto* c : *n->children())
            if (c)
              children.push_back({{"observation", msg::EnumNameObservation(c->observation())},
                                  {"child", c->child()}});
        nodes.push_back({{"action", n ? msg::EnumNameAction(n->action()) : ""},
                         {"children", std::move(children)}});
      }
    strategy["nodes"] = std::move(nodes);
  }
  j["strategy"] = std::move(strategy);
  nlohmann::json curve = nlohmann::json::array();
  if (e.curve())
    for (flatbuffers::uoffset_t i = 0; i < e.curve()->size(); ++i) {
      const msg::CurveSample c = sim::element(*e.curve(), i);
      curve.push_back({c.robot_time_s(), c.boxes()});
    }
  j["curve"] = std::move(curve);
  nlohmann::json modes = nlohmann::json::array();
  if (e.modes())
    for (const auto* m : *e.modes())
      modes.push_back({{"mode", text(m->mode())},
                       {"queries", m->queries()},
                       {"failures", m->failures()},
                       {"mean_ms", m->mean_ms()},
                       {"mean_expansions", m->mean_expansions()}});
  j["modes"] = std::move(modes);
  std::lock_guard lock(m_);
  executor_ = std::move(j);
  ++version_;
}

void DashboardState::update(const msg::KernelTelemetry& t) {
  const std::string kernel = text(t.kernel());
  nlohmann::json j;
  j["kernel"] = kernel;
  nlohmann::json nodes = nlohmann::json::array();
  if (t.nodes())
    for (const auto* n : *t.nodes())
      nodes.push_back({{"name", text(n->name())},
                       {"plugin", text(n->plugin())},
                       {"kind", text(n->kind())},
                       {"state", text(n->state())},
                       {"host", text(n->host())}});
  j["nodes"] = std::move(nodes);
  nlohmann::json topics = nlohmann::json::array();
  if (t.topics())
    for (const auto* s : *t.topics())
      topics.push_back({{"name", text(s->name())},
                        {"messages", s->messages()},
                        {"drops", s->drops()},
                        {"rate_hz", s->rate_hz()},
                        {"latency_mean_us", s->latency_mean_us()},
                        {"latency_max_us", s->latency_max_us()}});
  j["topics"] = std::move(topics);
  std::lock_guard lock(m_);
  kernels_[kernel] = std::move(j);
  ++version_;
}

void DashboardState::update(const msg::Progress& p) {
  nlohmann::json j = {{"sim_time_s", p.sim_time_s()},
                      {"boxes_total", p.boxes_total()},
                      {"boxes_unloaded", p.boxes_unloaded()}};
  std::lock_guard lock(m_);
  progress_ = std::move(j);
  ++version_;
}

void DashboardState::set_server(nlohmann::json server) {
  std::lock_guard lock(m_);
  if (server == server_) return;
  server_ = std::move(server);
  ++version_;
}

std::uint64_t DashboardState::version() const {
  std::lock_guard lock(m_);
  return version_;
}

std::string DashboardState::json() const {
  std::lock_guard lock(m_);
  nlohmann::json kernels = nlohmann::json::array();
  for (const auto& [id, k] : kernels_) kernels.push_back(k);
  return nlohmann::json{{"version", version_},           {"world", world_},
                        {"executor", executor_},         {"progress", progress_},
                        {"kernels", std::move(kernels)}, {"server", server_}}
      .dump();
}

}  // namespace plr::monitor_web
