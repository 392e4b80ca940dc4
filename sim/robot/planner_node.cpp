#include "planner_node.hpp"

#include <plr/messages.hpp>

#include <stdexcept>

namespace plr::sim {

plr::Status PlannerNode::provide_service(std::string planner) {
  planner_ = std::move(planner);
  sample_dt_ = params().get<double>("sample_dt", 0.02);
  if (!(sample_dt_ > 0.0))
    return plr::make_error(PLR_ERR_INVALID, "param 'sample_dt': must be positive");
  robot_ = std::make_unique<RobotModel>(
      RobotModel::from_urdf_file(params().get<std::string>("urdf", PLR_UNLOADER_URDF)));
  return ctx().provide<plr::msg::PlanRequest, plr::msg::PlanResponse>(
      "plan", [this](const plr::Message<plr::msg::PlanRequest>& req,
                     flatbuffers::FlatBufferBuilder& out) { return serve(*req, out); });
}

plr::Status PlannerNode::on_cleanup() {
  robot_.reset();
  return {};
}

plr::Status PlannerNode::serve(const plr::msg::PlanRequest& req,
                               flatbuffers::FlatBufferBuilder& out) {
  PlanResult result;
  try {
    const DecodedPlanRequest d = decode_plan_request(req);
    CollisionChecker checker(*robot_, d.world, d.octree);
    result = plan(d.query, checker);
  } catch (const std::invalid_argument& e) {
    result.status = PlanStatus::kInvalidRequest;
    result.message = e.what();
  }
  if (result.status != PlanStatus::kSolved) {
    log().info("plan {}: {}", to_string(result.status), result.message);
  }
  encode_plan_response(result, planner_, sample_dt_, out);
  return {};
}

}  // namespace plr::sim
