// The strategy chooser (the paper's online phase): for the world in front
// of the robot, the features, the nearest library world (NN), and the SVM
// model M that says whether NN's strategy or H runs from here. H is asked
// through the bus (its node serves `hardcoded_service`); the reply says
// which was chosen and why (NN's distance, M's margin).
#include <plr/interface.hpp>
#include <plr/messages.hpp>
#include <plr/node.hpp>
#include <plr/plugin.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <limits>
#include <optional>

#include "plr/chooser/model.hpp"
#include "plr/chooser/nearest.hpp"
#include "plr/sim/library.hpp"
#include "plr/sim/observation.hpp"
#include "plr/sim/strategy.hpp"

namespace {

using namespace std::chrono_literals;
namespace chooser = plr::chooser;

class StrategyChooser : public plr::Node {
 public:
  using Node::Node;

 protected:
  plr::Status on_configure() override {
    params().allow_only(
        {"observation", "library", "model", "hardcoded_service", "max_distance", "h_timeout_s"});
    auto observation = plr::sim::ObservationParams::from_json(
        params().json().value("observation", nlohmann::json()));
    if (!observation) return observation.error();
    obs_ = *observation;
    auto library = plr::sim::load_library(params().get<std::string>("library", ""));
    if (!library)
      return plr::make_error(PLR_ERR_INVALID, "param 'library': " + library.error().message);
    if (library->entries.empty())
      return plr::make_error(PLR_ERR_INVALID, "param 'library': the library is empty");
    auto model = chooser::Model::load(params().get<std::string>("model", ""));
    if (!model) return plr::make_error(PLR_ERR_INVALID, "param 'model': " + model.error().message);
    if (model->library_crc() != chooser::fingerprint(*library))
      return plr::make_error(
          PLR_ERR_INVALID,
          fmt::format("param 'model': trained with another library (CRC {:08x}, this one {:08x})",
                      model->library_crc(), chooser::fingerprint(*library)));
    if (const auto& made_by = model->made_by();
        made_by.find(chooser::kBelowMinimum) != std::string::npos)
      log().warn("param 'model': trained on too little data: {}",
                 made_by.substr(made_by.rfind(": ") + 2));
    index_.emplace(*library, model->scaling(), obs_);
    library_ = std::move(*library);
    model_.emplace(std::move(*model));
    h_service_ = params().get<std::string>("hardcoded_service", "strategy/hardcoded");
    max_distance_ = params().get<double>("max_distance", std::numeric_limits<double>::infinity());
    h_timeout_s_ = params().get<double>("h_timeout_s", 10.0);
    if (!(max_distance_ > 0) || !(h_timeout_s_ > 0))
      return plr::make_error(PLR_ERR_INVALID, "params 'max_distance', 'h_timeout_s': must be > 0");
    return ctx().provide<plr::msg::NextStrategyRequest, plr::msg::NextStrategyReply>(
        "strategy/next",
        [this](const plr::Message<plr::msg::NextStrategyRequest>& request,
               flatbuffers::FlatBufferBuilder& reply) { return next(*request, reply); });
  }

 private:
  plr::Status next(const plr::msg::NextStrategyRequest& request,
                   flatbuffers::FlatBufferBuilder& reply) {
    auto read = plr::sim::world_from_request(request);
    if (!read) return read.error();
    const plr::sim::World& world = *read;
    const chooser::Features f = chooser::features(world, obs_);
    const chooser::Nearest nn = index_->nearest(model_->scaling().apply(f));
    const chooser::Verdict verdict = model_->decide(f);
    const plr::sim::LibraryEntry& entry = library_.entries[nn.entry];
    const plr::sim::Strategy& strategy = entry.strategy;
    const auto* excluded = request.excluded();
    const bool root_excluded =
        excluded != nullptr && std::find(excluded->begin(), excluded->end(),
                                         strategy.nodes[strategy.root].action) != excluded->end();
    std::string why;
    if (nn.distance > max_distance_) {
      why = fmt::format("nearest {} at {:.2f} is beyond {:.2f}", entry.name, nn.distance,
                        max_distance_);
    } else if (!verdict.nearest) {
      why = fmt::format("M margin {:.3f} for nearest {} at {:.2f}", verdict.margin, entry.name,
                        nn.distance);
    } else if (root_excluded) {
      why = fmt::format("nearest {}'s first action was tried here", entry.name);
    } else {
      why = fmt::format("M margin {:.3f}, nearest at {:.2f}", verdict.margin, nn.distance);
      log().debug("{} -> library:{} ({})", f[chooser::kBoxCount], entry.name, why);
      reply.Finish(plr::msg::CreateNextStrategyReply(
          reply, plr::sim::build(reply, strategy), reply.CreateString("library:" + entry.name),
          nn.distance, verdict.margin, reply.CreateString(why)));
      return {};
    }
    // H, asked with the executor's own request.
    flatbuffers::FlatBufferBuilder ask;
    std::vector<plr::msg::Action> ex;
    if (excluded) ex.assign(excluded->begin(), excluded->end());
    std::vector<std::uint8_t> world_bytes(request.world()->begin(), request.world()->end());
    ask.Finish(
        plr::msg::CreateNextStrategyRequestDirect(ask, &world_bytes, request.observation(), &ex));
    const auto h = ctx()
                       .call<plr::msg::NextStrategyRequest, plr::msg::NextStrategyReply>(
                           h_service_, ask,
                           std::chrono::duration_cast<std::chrono::nanoseconds>(
                               std::chrono::duration<double>(h_timeout_s_)))
                       .get();
    if (!h) return plr::make_error(h.error().code, h_service_ + ": " + h.error().message);
    if (h.value()->strategy() == nullptr)
      return plr::make_error(PLR_ERR_INVALID, h_service_ + ": reply without a strategy");
    auto hs = plr::sim::from_message(*h.value()->strategy(), h_service_ + " reply");
    if (!hs) return hs.error();
    reply.Finish(plr::msg::CreateNextStrategyReply(reply, plr::sim::build(reply, *hs),
                                                   reply.CreateString("hardcoded"), nn.distance,
                                                   verdict.margin, reply.CreateString(why)));
    return {};
  }

  plr::sim::ObservationParams obs_;
  plr::sim::Library library_;
  std::optional<chooser::LibraryIndex> index_;
  std::optional<chooser::Model> model_;
  std::string h_service_;
  double max_distance_ = 0, h_timeout_s_ = 0;
};

}  // namespace

PLR_PLUGIN(StrategyChooser, "strategy_chooser", "1.0.0", PLR_KIND_CHOOSER,
           "Strategy chooser: the nearest library strategy or H, as an SVM decides")
PLR_INTERFACE(
    plr::service<plr::msg::NextStrategyRequest, plr::msg::NextStrategyReply>("strategy/next"))
