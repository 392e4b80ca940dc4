// The node every planner plug-in is: it serves `plan` (PlanRequest ->
// PlanResponse, sdk/schemas/plan.fbs) with a planner of the plug-in's.
//
// The life cycle is the base's (final): it reads the parameters every
// planner node has — `urdf` (the robot; the shipped one by default) and
// `sample_dt` (s between trajectory points in responses) — refuses unknown
// ones, asks the plug-in for its planner, and answers each request with a
// collision checker on the request's world (the previous request's checker
// given the new boxes, its trailer part kept while the octree is the same).
// Undecodable requests are answered with InvalidRequest and the field at
// fault. A plug-in implements make_planner() and, if it reads parameters of
// its own, planner_params().
//
//   class MyNode : public plr::planning::PlannerNode {
//     using PlannerNode::PlannerNode;
//     plr::Expected<std::unique_ptr<plr::planning::Planner>> make_planner() override {
//       return std::unique_ptr<plr::planning::Planner>(std::make_unique<MyPlanner>());
//     }
//   };
//   PLR_PLUGIN(MyNode, "planner_mine", "0.1.0", PLR_KIND_PLANNER, "my planner serving `plan`")
#pragma once

#include <plr/node.hpp>

#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "plr/planning/planner.hpp"

namespace plr::msg {
struct PlanRequest;
}

namespace plr::planning {

class PlannerNode : public plr::Node {
 public:
  using Node::Node;
  ~PlannerNode() override;

 protected:
  // Builds the planner from params() (called by configure; the error fails it).
  virtual plr::Expected<std::unique_ptr<Planner>> make_planner() = 0;
  // The parameters make_planner() reads, besides `urdf` and `sample_dt`.
  virtual std::vector<std::string> planner_params() const { return {}; }

  plr::Status on_configure() final;
  plr::Status on_cleanup() final;

 private:
  plr::Status serve(const plr::msg::PlanRequest& request, flatbuffers::FlatBufferBuilder& out);

  std::unique_ptr<sim::RobotModel> robot_;
  std::unique_ptr<Planner> planner_;
  std::mutex checker_mutex_;
  std::unique_ptr<sim::CollisionChecker> checker_;  // kept between requests
  double sample_dt_ = 0.02;
};

}  // namespace plr::planning
