// PLR_PLUGIN: the C entry point it makes (plr/plugin_abi.h), and trampolines
// that keep C++ on the plug-in's side: a failing hook's reason goes into the
// kernel's buffer, cut to fit; a constructor that throws makes create() fail.
#include <plr/plugin.hpp>
#include <plr/testing/fake_kernel.hpp>

#include <gtest/gtest.h>

#include <cstring>
#include <stdexcept>

namespace {

class Refuser : public plr::Node {
 public:
  explicit Refuser(const plr_host_api* host) : Node(host) {
    if (params().get<bool>("explode", false)) throw std::runtime_error("constructor threw");
  }

 protected:
  plr::Status on_configure() override {
    return plr::make_error(PLR_ERR_INVALID, "a reason longer than the kernel's buffer");
  }
};

}  // namespace

PLR_PLUGIN(Refuser, "refuser", "2.3.4", PLR_KIND_PLANNER, "refuses to configure")

namespace {

TEST(Plugin, TheEntryPointDescribesThePlugin) {
  const plr_plugin_descriptor* d = plr_plugin_entry();
  ASSERT_NE(d, nullptr);
  EXPECT_EQ(d->abi_major, PLR_ABI_MAJOR);
  EXPECT_EQ(d->abi_minor, PLR_ABI_MINOR);
  EXPECT_STREQ(d->name, "refuser");
  EXPECT_STREQ(d->version, "2.3.4");
  EXPECT_STREQ(d->description, "refuses to configure");
  EXPECT_EQ(d->kind, PLR_KIND_PLANNER);
  EXPECT_EQ(plr_plugin_entry(), d) << "one descriptor for the library's life";
}

TEST(Plugin, AFailingHookWritesItsReasonCutToTheBuffer) {
  plr::testing::FakeKernel k;
  const plr_plugin_descriptor* d = plr_plugin_entry();
  void* node = d->node.create(k.test_api());
  ASSERT_NE(node, nullptr);
  char err[9];
  std::memset(err, 'x', sizeof err);
  EXPECT_EQ(d->node.configure(node, err, sizeof err), PLR_ERR_INVALID);
  EXPECT_STREQ(err, "a reason");
  EXPECT_EQ(d->node.activate(node, nullptr, 0), PLR_ERR_STATE) << "no buffer is fine";
  d->node.destroy(node);
}

TEST(Plugin, AConstructorThatThrowsMakesCreateFail) {
  plr::testing::FakeKernel k;
  auto node = k.load_node("", plr::testing::NodeOptions());  // not a library
  EXPECT_FALSE(node);
  const plr_plugin_descriptor* d = plr_plugin_entry();
  auto exploding = k.create(plr::testing::PluginRef{d, "(this test)"},
                            plr::testing::NodeOptions().with_params(R"({"explode": true})"));
  ASSERT_FALSE(exploding);
  EXPECT_NE(exploding.error().message.find("create() returned no node"), std::string::npos)
      << exploding.error().message;
}

TEST(PluginAbi, KindsHaveNames) {
  EXPECT_STREQ(plr_kind_name(PLR_KIND_PLANNER), "planner");
  EXPECT_STREQ(plr_kind_name(PLR_KIND_EXECUTOR), "executor");
  EXPECT_STREQ(plr_kind_name(PLR_KIND_GENERATOR), "generator");
  EXPECT_STREQ(plr_kind_name(PLR_KIND_CHOOSER), "chooser");
  EXPECT_STREQ(plr_kind_name(PLR_KIND_SIMULATOR), "simulator");
  EXPECT_STREQ(plr_kind_name(PLR_KIND_DRIVER), "driver");
  EXPECT_STREQ(plr_kind_name(PLR_KIND_MONITOR), "monitor");
  EXPECT_STREQ(plr_kind_name(PLR_KIND_OTHER), "other");
  EXPECT_STREQ(plr_kind_name(static_cast<plr_kind>(99)), "unknown");
}

}  // namespace
