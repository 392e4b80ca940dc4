#include "plr/planning/planner_node.hpp"

#include <plr/messages.hpp>

#include <algorithm>
#include <mutex>

#include "plr/planning/plan_messages.hpp"

namespace plr::planning {

PlannerNode::~PlannerNode() = default;

plr::Status PlannerNode::on_configure() {
  std::vector<std::string> known = planner_params();
  known.insert(known.end(), {"urdf", "sample_dt"});
  for (const auto& [key, value] : params().json().items()) {
    if (std::find(known.begin(), known.end(), key) == known.end())
      return plr::make_error(PLR_ERR_INVALID, "param '" + key + "': unknown parameter");
  }
  sample_dt_ = params().get<double>("sample_dt", 0.02);
  if (!(sample_dt_ > 0.0))
    return plr::make_error(PLR_ERR_INVALID, "param 'sample_dt': must be positive");
  auto robot = sim::load_robot(params().get<std::string>("urdf", ""));
  if (!robot) return plr::make_error(PLR_ERR_INVALID, "param 'urdf': " + robot.error().message);
  robot_ = std::make_unique<sim::RobotModel>(std::move(*robot));
  auto planner = make_planner();
  if (!planner) return planner.error();
  planner_ = std::move(*planner);
  return ctx().provide<plr::msg::PlanRequest, plr::msg::PlanResponse>(
      "plan", [this](const plr::Message<plr::msg::PlanRequest>& req,
                     flatbuffers::FlatBufferBuilder& out) { return serve(*req, out); });
}

plr::Status PlannerNode::on_cleanup() {
  checker_.reset();  // it refers to robot_
  planner_.reset();
  robot_.reset();
  return {};
}

plr::Status PlannerNode::serve(const plr::msg::PlanRequest& request,
                               flatbuffers::FlatBufferBuilder& out) {
  PlanResult result;
  if (auto decoded = decode_plan_request(request); !decoded) {
    result.status = PlanStatus::kInvalidRequest;
    result.message = decoded.error().message;
  } else {
    // The previous request's checker, given this request's world: its
    // trailer part stays while the octree does (plan_messages keeps the
    // parsed octree while the bytes are the same). Taken out under the lock,
    // so a request served on another thread meanwhile makes its own.
    std::unique_ptr<sim::CollisionChecker> checker;
    {
      const std::lock_guard lock(checker_mutex_);
      checker = std::move(checker_);
    }
    if (checker)
      checker->set_world(decoded->world, decoded->octree);
    else
      checker = std::make_unique<sim::CollisionChecker>(*robot_, decoded->world, decoded->octree);
    result = planner_->plan(decoded->query, *checker);
    const std::lock_guard lock(checker_mutex_);
    checker_ = std::move(checker);
  }
  if (result.status != PlanStatus::kSolved)
    log().info("plan {}: {}", to_string(result.status), result.message);
  encode_plan_response(result, planner_->name(), sample_dt_, out);
  return {};
}

}  // namespace plr::planning
