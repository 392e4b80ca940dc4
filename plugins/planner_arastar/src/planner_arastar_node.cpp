// Plug-in: the ARA* lattice planner behind the "plan" service
// (PlanRequest -> PlanResponse, sdk/schemas/plan.fbs).
#include <plr/plugin.hpp>

#include <memory>

#include "arastar_planner.hpp"
#include "planner_node.hpp"

namespace {

class PlannerArastarNode : public plr::sim::PlannerNode {
 public:
  using PlannerNode::PlannerNode;

 protected:
  plr::Status on_configure() override {
    params().allow_only({"urdf", "primitives", "sample_dt"});
    // Throws "<file>: <cause>", which configure reports as invalid.
    planner_ = std::make_unique<plr::arastar::Planner>(plr::arastar::LatticeConfig::from_file(
        params().get<std::string>("primitives", PLR_ARASTAR_PRIMITIVES)));
    return provide_service("arastar");
  }

  plr::Status on_cleanup() override {
    planner_.reset();
    return PlannerNode::on_cleanup();
  }

  plr::sim::PlanResult plan(const plr::sim::PlanQuery& query,
                            plr::sim::CollisionChecker& checker) override {
    return planner_->plan(query, checker);
  }

 private:
  std::unique_ptr<plr::arastar::Planner> planner_;
};

}  // namespace

PLR_PLUGIN(PlannerArastarNode, "planner_arastar", "0.1.0", PLR_KIND_PLANNER,
           "ARA* lattice motion planner (modes M1-M6) serving `plan`")
