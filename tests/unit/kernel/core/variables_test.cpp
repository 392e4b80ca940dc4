// ${name} placeholders in node parameters: filled in everywhere in the
// parameters, and an unknown name is an error naming where it stands.
#include "variables.hpp"

#include <gtest/gtest.h>

namespace plr::kernel {
namespace {

PipelineConfig config(const std::string& params) {
  auto c = parse_pipeline_config("nodes:\n  sim: {plugin: x, params: " + params + "}\n", "v.yaml");
  EXPECT_TRUE(c) << c.error().message;
  return std::move(c).value();
}

const std::map<std::string, std::string> kValues = {
    {"report_dir", "/tmp/run"}, {"config_dir", "/etc/plr"}, {"run_id", "r7"}};

TEST(Variables, FillsEveryStringInTheParameters) {
  PipelineConfig c = config(
      R"({out: "${report_dir}/log.csv", both: "${config_dir}:${run_id}:${run_id}",
          list: [a, "${run_id}"], nested: {deep: "${report_dir}"}, n: 3, flag: true})");
  ASSERT_TRUE(substitute_variables(c, kValues));
  EXPECT_EQ(c.node("sim")->params, nlohmann::json::parse(R"({
      "out": "/tmp/run/log.csv", "both": "/etc/plr:r7:r7", "list": ["a", "r7"],
      "nested": {"deep": "/tmp/run"}, "n": 3, "flag": true})"));
}

TEST(Variables, AValueIsNotSubstitutedAgain) {
  PipelineConfig c = config(R"({a: "${x}"})");
  ASSERT_TRUE(substitute_variables(c, {{"x", "${x}${x}"}}));
  EXPECT_EQ(c.node("sim")->params["a"], "${x}${x}");
}

TEST(Variables, AnUnterminatedPlaceholderStaysAsItIs) {
  PipelineConfig c = config(R"({a: "cost ${5"})");
  ASSERT_TRUE(substitute_variables(c, kValues));
  EXPECT_EQ(c.node("sim")->params["a"], "cost ${5");
}

TEST(Variables, AnUnknownNameIsAnErrorNamingTheNodeAndKey) {
  PipelineConfig c = config(R"({paths: {log: "${report_dri}/x"}})");
  const Status s = substitute_variables(c, kValues);
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code, PLR_ERR_INVALID);
  EXPECT_EQ(s.error().message,
            "v.yaml:2:3: nodes.sim.params.paths.log: unknown variable '${report_dri}'");
}

}  // namespace
}  // namespace plr::kernel
