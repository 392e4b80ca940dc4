// Demo: serves `double` (value -> 2 x value) and counts the values it saw on `count`.
#include <plr/interface.hpp>
#include <plr/messages.hpp>
#include <plr/node.hpp>
#include <plr/plugin.hpp>

namespace {

class DoublerNode : public plr::Node {
 public:
  using Node::Node;

 protected:
  plr::Status on_configure() override {
    params().allow_only({"factor"});
    factor_ = params().get<std::int64_t>("factor", 2);
    if (auto s = ctx().provide<plr::msg::DoubleRequest, plr::msg::DoubleReply>(
            "double",
            [this](const plr::Message<plr::msg::DoubleRequest>& req,
                   flatbuffers::FlatBufferBuilder& out) -> plr::Status {
              out.Finish(plr::msg::CreateDoubleReply(out, req->value() * factor_));
              return {};
            },
            // It answers at once and never waits: the kernel may answer on
            // the thread that received the request.
            plr::ServiceMode::kQuick);
        !s)
      return s;
    return ctx().subscribe<plr::msg::Count>(
        "count", [this](const plr::Message<plr::msg::Count>&) { ++seen_; });
  }

  plr::Status on_deactivate() override {
    log().info("saw {} counts", seen_);
    return {};
  }

 private:
  std::int64_t factor_ = 2;
  std::int64_t seen_ = 0;
};

}  // namespace

PLR_PLUGIN(DoublerNode, "demo_doubler", "1.0.0", PLR_KIND_OTHER,
           "Demo: serves `double` and counts what it hears on `count`")
PLR_INTERFACE(plr::service<plr::msg::DoubleRequest, plr::msg::DoubleReply>("double"))
