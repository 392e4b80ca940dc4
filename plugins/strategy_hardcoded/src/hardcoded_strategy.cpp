// Strategy H: the hand-written rule of thumb the executor falls back on.
//
// Boxes in columns lower than h_pile form the pile, the others walls. If the
// pile in front of the first wall is deeper than d_min, sweep it; else if the
// first wall is higher than h_min, pick from it — from its top box's height
// and side, which is how the executor's pick-point choice ends up preferring
// boxes near the robot and high up. Otherwise what is left is low: pick the
// shallow pile's top box, or from the low wall.
#include <plr/messages.hpp>

#include <algorithm>
#include <plr/interface.hpp>
#include <plr/node.hpp>
#include <plr/plugin.hpp>

#include "plr/sim/hardcoded_strategy.hpp"
#include "plr/sim/observation.hpp"
#include "plr/sim/strategy.hpp"

namespace {

class HardcodedStrategy : public plr::Node {
 public:
  using Node::Node;

 protected:
  plr::Status on_configure() override {
    params().allow_only({"observation", "h_min", "d_min", "service"});
    auto observation = plr::sim::ObservationParams::from_json(
        params().json().value("observation", nlohmann::json()));
    if (!observation) return observation.error();
    obs_ = observation.value();
    h_.h_min = params().get<double>("h_min", h_.h_min);
    h_.d_min = params().get<double>("d_min", h_.d_min);
    if (auto ok = h_.check(); !ok) return ok;
    // Under a chooser, H serves another name (strategy/hardcoded) and the
    // chooser serves strategy/next.
    return ctx().provide<plr::msg::NextStrategyRequest, plr::msg::NextStrategyReply>(
        params().get<std::string>("service", "strategy/next"),
        [this](const plr::Message<plr::msg::NextStrategyRequest>& request,
               flatbuffers::FlatBufferBuilder& reply) { return next(*request, reply); });
  }

 private:
  plr::Status next(const plr::msg::NextStrategyRequest& request,
                   flatbuffers::FlatBufferBuilder& reply) {
    auto read = plr::sim::world_from_request(request);
    if (!read) return read.error();
    const plr::sim::World& world = *read;
    const auto scene = plr::sim::analyse(world, obs_);
    if (!scene.observation)
      return plr::make_error(PLR_ERR_INVALID, "strategy/next: the trailer is empty");
    // H's first choice, or its first fallback the executor has not tried
    // here yet; when it has tried them all, H's first choice again.
    const auto ranking = plr::sim::hardcoded_ranking(scene, h_);
    auto action = ranking.front();
    if (const auto* excluded = request.excluded()) {
      for (const auto a : ranking) {
        if (std::find(excluded->begin(), excluded->end(), a) == excluded->end()) {
          action = a;
          break;
        }
      }
    }
    log().debug("{}: d_pile {:.2f} m, h_W {:.2f} m -> {}", plr::sim::to_string(*scene.observation),
                scene.pile_depth, scene.wall_height, plr::sim::to_string(action));
    const auto strategy = plr::sim::single_action(action, "H");
    reply.Finish(plr::msg::CreateNextStrategyReply(reply, plr::sim::build(reply, strategy),
                                                   reply.CreateString("hardcoded")));
    return {};
  }

  plr::sim::ObservationParams obs_;
  plr::sim::HardcodedParams h_;
};

}  // namespace

PLR_PLUGIN(HardcodedStrategy, "strategy_hardcoded", "1.0.0", PLR_KIND_CHOOSER,
           "Strategy H: sweep a deep pile, else pick from a high enough wall")
// Under a chooser it serves another name: a remap of strategy/next, which the
// count of a run's shared memory follows (its `service` param is not seen).
PLR_INTERFACE(
    plr::service<plr::msg::NextStrategyRequest, plr::msg::NextStrategyReply>("strategy/next"))
