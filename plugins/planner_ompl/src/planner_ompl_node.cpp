// Plug-in: RRTConnect (OMPL) with shortcutting behind the `plan` service.
#include <plr/interface.hpp>
#include <plr/messages.hpp>
#include <plr/plugin.hpp>

#include "plr/planning/ompl_planner.hpp"
#include "plr/planning/planner_node.hpp"

namespace {

class PlannerOmplNode final : public plr::planning::PlannerNode {
 public:
  using PlannerNode::PlannerNode;

 protected:
  plr::Expected<std::unique_ptr<plr::planning::Planner>> make_planner() override {
    return std::unique_ptr<plr::planning::Planner>(
        std::make_unique<plr::ompl_planner::OmplPlanner>());
  }
};

}  // namespace

PLR_PLUGIN(PlannerOmplNode, "planner_ompl", "0.2.0", PLR_KIND_PLANNER,
           "RRTConnect motion planner (modes M1-M5; M6 escape) serving `plan`")
PLR_INTERFACE(plr::service<plr::msg::PlanRequest, plr::msg::PlanResponse>("plan"))
