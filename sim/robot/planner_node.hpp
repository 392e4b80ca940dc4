// The half the planner plug-ins share: params `urdf` and `sample_dt`, and the
// "plan" service (PlanRequest -> PlanResponse, sdk/schemas/plan.fbs) with a
// collision checker built per request on the request's world. Bad requests
// are answered with kInvalidRequest and the decoder's one-line reason.
#pragma once

#include <plr/node.hpp>

#include <memory>
#include <string>

#include "plr/sim/plan_types.hpp"

namespace plr::sim {

class PlannerNode : public plr::Node {
 public:
  using Node::Node;

 protected:
  // From on_configure, after params().allow_only(...) (which must list
  // "urdf" and "sample_dt") and building the planner. `planner` names the
  // planner in responses. Throws "<file>: <cause>" for a bad URDF.
  plr::Status provide_service(std::string planner);
  const RobotModel& robot() const { return *robot_; }
  virtual PlanResult plan(const PlanQuery& query, CollisionChecker& checker) = 0;

  plr::Status on_cleanup() override;

 private:
  plr::Status serve(const plr::msg::PlanRequest& request, flatbuffers::FlatBufferBuilder& out);

  std::unique_ptr<RobotModel> robot_;
  std::string planner_;
  double sample_dt_ = 0.02;
};

}  // namespace plr::sim
