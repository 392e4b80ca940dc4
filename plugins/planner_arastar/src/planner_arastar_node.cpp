// Plug-in: the ARA* lattice planner (plr/planning/lattice_planner.hpp)
// behind the `plan` service. Parameter `lattice`: a lattice file (the
// shipped robots/unloader_lattice.yaml by default); `experience` (bool,
// default false): M1 and M2 searches reuse the paths of earlier requests on
// the same trailer (docs/planner.md, "Experience for recurring motions").
#include <plr/interface.hpp>
#include <plr/messages.hpp>
#include <plr/plugin.hpp>

#include "plr/planning/lattice_planner.hpp"
#include "plr/planning/planner_node.hpp"
#include "plr/sim/shipped_files.hpp"

namespace {

using plr::planning::LatticeConfig;
using plr::planning::Planner;

class PlannerArastarNode final : public plr::planning::PlannerNode {
 public:
  using PlannerNode::PlannerNode;

 protected:
  std::vector<std::string> planner_params() const override { return {"lattice", "experience"}; }

  plr::Expected<std::unique_ptr<Planner>> make_planner() override {
    std::string file = params().get<std::string>("lattice", "");
    if (file.empty()) {
      const auto shipped = plr::sim::shipped_file("robots/unloader_lattice.yaml");
      if (!shipped)
        return plr::make_error(PLR_ERR_INVALID, "param 'lattice': " + shipped.error().message);
      file = shipped->string();
    }
    auto config = LatticeConfig::from_file(file);
    if (!config)
      return plr::make_error(PLR_ERR_INVALID, "param 'lattice': " + config.error().message);
    // Off by default: with it an answer depends on the requests before, and
    // the planner contract (conformance: BudgetIsDeterministic) promises one
    // that is a function of the request.
    config->experience.enabled = params().get<bool>("experience", false);
    return std::unique_ptr<Planner>(
        std::make_unique<plr::planning::LatticePlanner>(std::move(*config)));
  }
};

}  // namespace

PLR_PLUGIN(PlannerArastarNode, "planner_arastar", "0.2.0", PLR_KIND_PLANNER,
           "ARA* lattice motion planner (modes M1-M6) serving `plan`")
PLR_INTERFACE(plr::service<plr::msg::PlanRequest, plr::msg::PlanResponse>("plan"))
