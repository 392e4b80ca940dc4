// Plug-in: RRTConnect (OMPL) with shortcutting behind the "plan" service
// (PlanRequest -> PlanResponse, sdk/schemas/plan.fbs).
#include <plr/plugin.hpp>

#include "ompl_planner.hpp"
#include "planner_node.hpp"

namespace {

class PlannerOmplNode : public plr::sim::PlannerNode {
 public:
  using PlannerNode::PlannerNode;

 protected:
  plr::Status on_configure() override {
    params().allow_only({"urdf", "sample_dt"});
    return provide_service("rrtconnect");
  }

  plr::sim::PlanResult plan(const plr::sim::PlanQuery& query,
                            plr::sim::CollisionChecker& checker) override {
    return planner_.plan(query, checker);
  }

 private:
  plr::ompl_planner::Planner planner_;
};

}  // namespace

PLR_PLUGIN(PlannerOmplNode, "planner_ompl", "0.1.0", PLR_KIND_PLANNER,
           "RRTConnect motion planner (modes M1-M5) serving `plan`")
