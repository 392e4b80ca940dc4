// Plug-in: RRTConnect (OMPL) with shortcutting behind the "plan" service
// (PlanRequest -> PlanResponse, sdk/schemas/plan.fbs).
#include <plr/messages.hpp>
#include <plr/node.hpp>
#include <plr/plugin.hpp>

#include <memory>
#include <optional>

#include "ompl_planner.hpp"
#include "plr/sim/collision.hpp"

namespace {

class PlannerOmplNode : public plr::Node {
 public:
  using Node::Node;

 protected:
  plr::Status on_configure() override {
    params().allow_only({"urdf", "sample_dt"});
    const auto urdf = params().get<std::string>("urdf", PLR_UNLOADER_URDF);
    sample_dt_ = params().get<double>("sample_dt", 0.02);
    if (!(sample_dt_ > 0.0))
      return plr::make_error(PLR_ERR_INVALID, "param 'sample_dt': must be positive");
    // Both throw "<file>: <cause>", which configure reports as invalid.
    robot_ = std::make_unique<plr::sim::RobotModel>(plr::sim::RobotModel::fromUrdfFile(urdf));
    planner_ = std::make_unique<plr::ompl_planner::Planner>();
    return ctx().provide<plr::msg::PlanRequest, plr::msg::PlanResponse>(
        "plan", [this](const plr::Message<plr::msg::PlanRequest>& req,
                       flatbuffers::FlatBufferBuilder& out) { return serve(*req, out); });
  }

  plr::Status on_cleanup() override {
    planner_.reset();
    robot_.reset();
    return {};
  }

 private:
  plr::Status serve(const plr::msg::PlanRequest& req, flatbuffers::FlatBufferBuilder& out) {
    plr::sim::PlanResult result;
    try {
      const plr::sim::DecodedPlanRequest d = plr::sim::decodePlanRequest(req);
      plr::sim::CollisionChecker checker(*robot_, d.world, d.octree);
      result = planner_->plan(d.query, checker);
    } catch (const std::invalid_argument& e) {
      result.status = plr::sim::PlanStatus::kInvalidRequest;
      result.message = e.what();
    }
    if (result.status != plr::sim::PlanStatus::kSolved) {
      log().info("plan {}: {}", plr::sim::toString(result.status), result.message);
    }
    plr::sim::encodePlanResponse(result, "rrtconnect", sample_dt_, out);
    return {};
  }

  std::unique_ptr<plr::sim::RobotModel> robot_;
  std::unique_ptr<plr::ompl_planner::Planner> planner_;
  double sample_dt_ = 0.02;
};

}  // namespace

PLR_PLUGIN(PlannerOmplNode, "planner_ompl", "0.1.0", PLR_KIND_PLANNER,
           "RRTConnect motion planner (modes M1-M5) serving `plan`")
