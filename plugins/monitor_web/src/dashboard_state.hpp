// What the dashboard page shows, kept from the bus messages the monitor
// reads and rendered as one JSON document: the trailer, its boxes and the
// robot's links (boxes around them, for the top and side views), the
// executor's state (action, step, strategy tree, curve, planner figures per
// mode) and each kernel's telemetry (node states, topic rates and latencies).
#pragma once

#include <plr/messages.hpp>
#include <plr/sim/robot_model.hpp>

#include <nlohmann/json.hpp>

#include <cstdint>
#include <map>
#include <mutex>
#include <optional>
#include <string>

namespace plr::monitor_web {

class DashboardState {
 public:
  // Without a robot model the robot is not drawn.
  explicit DashboardState(std::optional<sim::RobotModel> robot);

  void update(const msg::WorldState& world);
  void update(const msg::ExecutorState& executor);
  void update(const msg::KernelTelemetry& telemetry);
  void update(const msg::Progress& progress);
  // Extra figures of the monitor itself (clients, drops), shown with the rest.
  void set_server(nlohmann::json server);

  // Increases with every update: the page is sent again only when it changed.
  std::uint64_t version() const;
  std::string json() const;

 private:
  mutable std::mutex m_;
  std::optional<sim::RobotModel> robot_;
  std::uint64_t version_ = 0;
  nlohmann::json world_ = nlohmann::json::object();
  nlohmann::json executor_ = nlohmann::json::object();
  nlohmann::json progress_ = nlohmann::json::object();
  std::map<std::string, nlohmann::json> kernels_;
  nlohmann::json server_ = nlohmann::json::object();
};

}  // namespace plr::monitor_web
