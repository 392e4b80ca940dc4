// A minimal PLR node to start from: one parameter (`gain`), one topic in
// (`input`), one topic out (`scaled`) and one service (`scale`). Copy the
// folder, rename the plug-in, and replace the logic.
#include <plr/interface.hpp>
#include <plr/messages.hpp>
#include <plr/node.hpp>
#include <plr/plugin.hpp>

#include <cstdint>

namespace {

class TemplateNode : public plr::Node {
 public:
  using Node::Node;

 protected:
  // Reads and checks parameters and registers topics and services. Anything
  // thrown here (a ParamError) fails configure with PLR_ERR_INVALID.
  plr::Status on_configure() override {
    params().allow_only({"gain"});
    gain_ = params().get<std::int64_t>("gain", 2);
    if (gain_ == 0) return plr::make_error(PLR_ERR_INVALID, "param 'gain': must not be 0");

    auto scaled = ctx().advertise<plr::msg::Count>("scaled");
    if (!scaled) return scaled.error();
    scaled_ = *scaled;

    if (auto s = ctx().subscribe<plr::msg::Count>(
            "input", [this](const plr::Message<plr::msg::Count>& in) { on_input(*in); });
        !s)
      return s;

    return ctx().provide<plr::msg::DoubleRequest, plr::msg::DoubleReply>(
        "scale",
        [this](const plr::Message<plr::msg::DoubleRequest>& request,
               flatbuffers::FlatBufferBuilder& reply) -> plr::Status {
          reply.Finish(plr::msg::CreateDoubleReply(reply, request->value() * gain_));
          return {};
        });
  }

  plr::Status on_activate() override {
    log().info("scaling by {}", gain_);
    return {};
  }

  plr::Status on_deactivate() override {
    log().info("scaled {} messages", handled_);
    return {};
  }

 private:
  // Runs on the node's callback thread, one callback at a time.
  void on_input(const plr::msg::Count& in) {
    flatbuffers::FlatBufferBuilder fbb;
    fbb.Finish(plr::msg::CreateCount(fbb, in.value() * gain_));
    if (auto s = scaled_.publish(fbb); !s) log().warn("publish failed: {}", s.error().message);
    ++handled_;
  }

  std::int64_t gain_ = 2;
  std::int64_t handled_ = 0;
  plr::Publisher<plr::msg::Count> scaled_;
};

}  // namespace

PLR_PLUGIN(TemplateNode, "template_node", "0.1.0", PLR_KIND_OTHER,
           "Template: scales counts by a gain")
PLR_INTERFACE(plr::topic<plr::msg::Count>("scaled"),
              plr::service<plr::msg::DoubleRequest, plr::msg::DoubleReply>("scale"))
