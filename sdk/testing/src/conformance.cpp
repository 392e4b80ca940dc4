#include <plr/testing/conformance.hpp>
#include <plr/testing/fake_kernel.hpp>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <functional>

namespace plr::testing {
namespace {

using namespace std::chrono_literals;

#define PLR_ASSERT_OK(expr)                                                \
  do {                                                                     \
    const ::plr::Status plr_s_ = (expr);                                   \
    ASSERT_TRUE(plr_s_) << #expr << " failed: " << plr_s_.error().message; \
  } while (0)

const char* status_name(plr_status s) {
  switch (s) {
    case PLR_OK:
      return "PLR_OK";
    case PLR_ERR_STATE:
      return "PLR_ERR_STATE";
    case PLR_ERR_INVALID:
      return "PLR_ERR_INVALID";
    case PLR_ERR_TIMEOUT:
      return "PLR_ERR_TIMEOUT";
    case PLR_ERR_UNAVAILABLE:
      return "PLR_ERR_UNAVAILABLE";
    case PLR_ERR_CANCELLED:
      return "PLR_ERR_CANCELLED";
    case PLR_ERR_INTERNAL:
      return "PLR_ERR_INTERNAL";
  }
  return "an unknown status";
}

// A refusal must carry the right code and a one-line reason.
void expect_refused(const Status& s, plr_status code, const std::string& what) {
  ASSERT_FALSE(s) << what << " was accepted; it must be refused with " << status_name(code);
  EXPECT_EQ(s.error().code, code) << what << " refused with " << status_name(s.error().code)
                                  << " instead of " << status_name(code) << ": "
                                  << s.error().message;
  EXPECT_FALSE(s.error().message.empty()) << what << " refused without an error text";
  EXPECT_EQ(s.error().message.find('\n'), std::string::npos)
      << what << ": the error text must be one line: " << s.error().message;
}

KernelOptions quiet() {
  return {.start_ns = 0, .echo_level = PLR_LOG_ERROR};
}

// Lets an active node do some work: time passes and queued callbacks run.
void exercise(FakeKernel& k) {
  for (int i = 0; i < 5; ++i) {
    k.advance(10ms);
    k.spin();
  }
}

class Check : public ::testing::Test {
 public:
  using Body = std::function<void(const ConformanceOptions&)>;
  Check(Body body, ConformanceOptions options)
      : body_(std::move(body)), options_(std::move(options)) {}
  void TestBody() override { body_(options_); }

 private:
  Body body_;
  ConformanceOptions options_;
};

void descriptor_is_sane(const ConformanceOptions& o) {
  FakeKernel k(quiet());
  auto plugin = k.load(o.plugin_path);
  ASSERT_TRUE(plugin) << plugin.error().message;
  const plr_plugin_descriptor& d = *plugin->descriptor;
  EXPECT_EQ(d.abi_major, PLR_ABI_MAJOR);
  ASSERT_NE(d.name, nullptr);
  EXPECT_STRNE(d.name, "") << "descriptor name is empty";
  ASSERT_NE(d.version, nullptr);
  EXPECT_STRNE(d.version, "") << "descriptor version is empty";
  EXPECT_NE(d.description, nullptr);
  EXPECT_STRNE(plr_kind_name(d.kind), "unknown") << "unknown kind " << static_cast<int>(d.kind);
  // The kernel loads <name>.so and refuses a descriptor naming another plug-in.
  EXPECT_EQ(std::filesystem::path(o.plugin_path).stem().string(), d.name)
      << "the library file must be named after the plug-in";
  EXPECT_NE(d.node.create, nullptr);
  EXPECT_NE(d.node.destroy, nullptr);
  EXPECT_NE(d.node.configure, nullptr);
  EXPECT_NE(d.node.activate, nullptr);
  EXPECT_NE(d.node.deactivate, nullptr);
  EXPECT_NE(d.node.cleanup, nullptr);
}

void life_cycle_in_order(const ConformanceOptions& o) {
  FakeKernel k(quiet());
  auto node = k.load_node(o.plugin_path, NodeOptions().with_params(o.params_json));
  ASSERT_TRUE(node) << node.error().message;
  PLR_ASSERT_OK(node->configure());
  PLR_ASSERT_OK(node->activate());
  exercise(k);
  PLR_ASSERT_OK(node->deactivate());
  exercise(k);
  PLR_ASSERT_OK(node->cleanup());
  EXPECT_EQ(node->state(), NodeState::Unconfigured);
}

void repeated_cycles(const ConformanceOptions& o) {
  FakeKernel k(quiet());
  auto node = k.load_node(o.plugin_path, NodeOptions().with_params(o.params_json));
  ASSERT_TRUE(node) << node.error().message;
  for (int cycle = 0; cycle < 3; ++cycle) {
    SCOPED_TRACE("cycle " + std::to_string(cycle));
    PLR_ASSERT_OK(node->configure());
    for (int run = 0; run < 2; ++run) {
      PLR_ASSERT_OK(node->activate());
      exercise(k);
      PLR_ASSERT_OK(node->deactivate());
    }
    PLR_ASSERT_OK(node->cleanup());
  }
}

void wrong_order_refused(const ConformanceOptions& o) {
  FakeKernel k(quiet());
  auto node = k.load_node(o.plugin_path, NodeOptions().with_params(o.params_json));
  ASSERT_TRUE(node) << node.error().message;
  expect_refused(node->activate(), PLR_ERR_STATE, "activate when unconfigured");
  expect_refused(node->cleanup(), PLR_ERR_STATE, "cleanup when unconfigured");
  PLR_ASSERT_OK(node->configure());
  expect_refused(node->configure(), PLR_ERR_STATE, "configure when configured");
  PLR_ASSERT_OK(node->activate());
  exercise(k);
  expect_refused(node->configure(), PLR_ERR_STATE, "configure when active");
  expect_refused(node->activate(), PLR_ERR_STATE, "activate when active");
  expect_refused(node->cleanup(), PLR_ERR_STATE, "cleanup when active");
  PLR_ASSERT_OK(node->deactivate());
  PLR_ASSERT_OK(node->cleanup());
  expect_refused(node->activate(), PLR_ERR_STATE, "activate after cleanup");
  // The refusals changed nothing: a full cycle still works.
  PLR_ASSERT_OK(node->configure());
  PLR_ASSERT_OK(node->activate());
  PLR_ASSERT_OK(node->deactivate());
  PLR_ASSERT_OK(node->cleanup());
}

void deactivate_idempotent(const ConformanceOptions& o) {
  FakeKernel k(quiet());
  auto node = k.load_node(o.plugin_path, NodeOptions().with_params(o.params_json));
  ASSERT_TRUE(node) << node.error().message;
  PLR_ASSERT_OK(node->deactivate());  // unconfigured
  PLR_ASSERT_OK(node->configure());
  PLR_ASSERT_OK(node->deactivate());  // configured, never active
  PLR_ASSERT_OK(node->activate());
  exercise(k);
  PLR_ASSERT_OK(node->deactivate());
  PLR_ASSERT_OK(node->deactivate());  // again
  // Still configured: cleanup is allowed, activate works again.
  PLR_ASSERT_OK(node->activate());
  PLR_ASSERT_OK(node->deactivate());
  PLR_ASSERT_OK(node->cleanup());
}

void no_leaks(const ConformanceOptions& o) {
  FakeKernel k(quiet());
  {
    auto idle =
        k.load_node(o.plugin_path, NodeOptions().with_name("idle").with_params(o.params_json));
    ASSERT_TRUE(idle) << idle.error().message;
    idle->destroy();
  }
  auto node = k.load_node(o.plugin_path, NodeOptions().with_params(o.params_json));
  ASSERT_TRUE(node) << node.error().message;
  for (int cycle = 0; cycle < 2; ++cycle) {
    PLR_ASSERT_OK(node->configure());
    PLR_ASSERT_OK(node->activate());
    exercise(k);
    PLR_ASSERT_OK(node->deactivate());
    PLR_ASSERT_OK(node->cleanup());
    k.spin();
    EXPECT_EQ(node->pending_calls(), 0u) << "calls still in flight after cleanup";
    EXPECT_EQ(node->unanswered_requests(), 0u) << "requests left unanswered after cleanup";
  }
  node->destroy();
  k.spin();
  EXPECT_EQ(k.live_messages(), 0) << "message buffers still referenced after destroy";
  EXPECT_EQ(k.pending_calls(), 0u);
}

void refuses_unknown_parameter(const ConformanceOptions& o) {
  auto params = nlohmann::json::parse(o.params_json);
  params[kUnknownParam] = 1;
  FakeKernel k(quiet());
  auto bad = k.load_node(o.plugin_path, NodeOptions().with_params(params.dump()));
  ASSERT_TRUE(bad) << bad.error().message;
  const Status s = bad->configure();
  expect_refused(s, PLR_ERR_INVALID, std::string("configure with param '") + kUnknownParam + "'");
  if (!s) {
    EXPECT_NE(s.error().message.find(kUnknownParam), std::string::npos)
        << "the error must name the unknown key: " << s.error().message;
  }
  // Still unconfigured: activate is refused and configure refuses again.
  expect_refused(bad->activate(), PLR_ERR_STATE, "activate after a failed configure");
  expect_refused(bad->configure(), PLR_ERR_INVALID, "configure again with the same bad params");
  bad->destroy();
  EXPECT_EQ(k.live_messages(), 0);

  auto good = k.load_node(o.plugin_path, NodeOptions().with_params(o.params_json));
  ASSERT_TRUE(good) << good.error().message;
  PLR_ASSERT_OK(good->configure());
  PLR_ASSERT_OK(good->activate());
  PLR_ASSERT_OK(good->deactivate());
  PLR_ASSERT_OK(good->cleanup());
}

bool declared(const plr_interface& interface, const Offer& offer) {
  for (std::size_t i = 0; i < interface.port_count; ++i) {
    const plr_port& p = interface.ports[i];
    if (p.kind != offer.kind || p.name == nullptr || p.type == nullptr || offer.name != p.name ||
        fnv1a(p.type) != offer.type_id)
      continue;
    if (p.kind == PLR_PORT_TOPIC) return true;
    if (p.reply_type != nullptr && fnv1a(p.reply_type) == offer.reply_type_id) return true;
  }
  return false;
}

// The kernel sizes a run's shared memory from the declaration before any
// node starts: a topic or service offered but not declared gets no room.
void declares_what_it_offers(const ConformanceOptions& o) {
  FakeKernel k(quiet());
  auto plugin = k.load(o.plugin_path);
  ASSERT_TRUE(plugin) << plugin.error().message;
  ASSERT_NE(plugin->interface, nullptr)
      << "no PLR_INTERFACE(...): declare the topics the node advertises and the services it "
         "provides (PLR_INTERFACE() when there are none)";
  auto node = k.create(*plugin, NodeOptions().with_params(o.params_json));
  ASSERT_TRUE(node) << node.error().message;
  PLR_ASSERT_OK(node->configure());
  PLR_ASSERT_OK(node->activate());
  exercise(k);
  PLR_ASSERT_OK(node->deactivate());
  PLR_ASSERT_OK(node->cleanup());
  for (const Offer& offer : k.offers()) {
    EXPECT_TRUE(declared(*plugin->interface, offer))
        << (offer.kind == PLR_PORT_TOPIC ? "topic '" : "service '") << offer.name
        << "' is offered but not declared with its message types in PLR_INTERFACE(...)";
  }
}

}  // namespace

void register_conformance_tests(const ConformanceOptions& options) {
  const std::pair<const char*, Check::Body> checks[] = {
      {"DescriptorIsSane", &descriptor_is_sane},
      {"LifeCycleInOrder", &life_cycle_in_order},
      {"RepeatedCycles", &repeated_cycles},
      {"WrongOrderRefused", &wrong_order_refused},
      {"DeactivateIdempotent", &deactivate_idempotent},
      {"NoLeaks", &no_leaks},
      {"RefusesUnknownParameter", &refuses_unknown_parameter},
      {"DeclaresWhatItOffers", &declares_what_it_offers},
  };
  for (const auto& [name, body] : checks) {
    ::testing::RegisterTest(
        "Conformance", name, nullptr, options.plugin_path.c_str(), __FILE__, __LINE__,
        [body, options]() -> ::testing::Test* { return new Check(body, options); });
  }
}

int run_conformance(const std::string& plugin_path, const std::string& params_json) {
  register_conformance_tests({plugin_path, params_json});
  return RUN_ALL_TESTS();
}

}  // namespace plr::testing
