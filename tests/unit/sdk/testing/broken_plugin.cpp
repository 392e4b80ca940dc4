// Deliberately broken plug-ins, one flaw each (BROKEN_*): the conformance
// suite must catch every one of them.
#include <plr/interface.hpp>
#include <plr/messages.hpp>
#include <plr/node.hpp>
#include <plr/plugin.hpp>

namespace {

#if defined(BROKEN_STATE) || defined(BROKEN_ABI)

// Raw C table, without the SDK's state checks: every transition succeeds.
void* create(const plr_host_api*) {
  return new int(0);
}
void destroy(void* node) {
  delete static_cast<int*>(node);
}
plr_status accept(void*, char*, size_t) {
  return PLR_OK;
}

#ifdef BROKEN_ABI
constexpr std::uint32_t kAbiMajor = PLR_ABI_MAJOR + 1;
#else
constexpr std::uint32_t kAbiMajor = PLR_ABI_MAJOR;
#endif

const plr_plugin_descriptor descriptor = {kAbiMajor,
                                          PLR_ABI_MINOR,
                                          PLUGIN_NAME,
                                          "0.0.1",
                                          "broken on purpose",
                                          PLR_KIND_OTHER,
                                          {&create, &destroy, &accept, &accept, &accept, &accept}};

}  // namespace

extern "C" __attribute__((visibility("default"))) const plr_plugin_descriptor* plr_plugin_entry() {
  return &descriptor;
}

#else

#ifdef BROKEN_LEAK
// A buffer taken from the kernel and never released.
plr_msg* kept = nullptr;
#endif

class Broken : public plr::Node {
 public:
  using Node::Node;

 protected:
  plr::Status on_configure() override {
#ifdef BROKEN_PARAMS
    rate_ = params().get<int>("rate", 1);  // and never refuses keys it does not know
#else
    params().allow_only({"rate"});
    rate_ = params().get<int>("rate", 1);
#endif
#ifdef BROKEN_INTERFACE
    // Advertised, and left out of the declaration below.
    if (auto undeclared = ctx().advertise<plr::msg::Count>("undeclared"); !undeclared)
      return undeclared.error();
#endif
#ifdef BROKEN_LEAK
    std::uint8_t* data = nullptr;
    kept = ctx().api()->msg_alloc(ctx().api()->ctx, 8, &data);
#endif
    return {};
  }

 private:
  int rate_ = 1;
};

}  // namespace

PLR_PLUGIN(Broken, PLUGIN_NAME, "0.0.1", PLR_KIND_OTHER, "broken on purpose")
PLR_INTERFACE()

#endif
