#include "pipeline_config.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

namespace plr::kernel {
namespace {

namespace fs = std::filesystem;

const char* kFile = "configs/x.yaml";

// The error message for a config that must be refused.
std::string error_of(const std::string& yaml, const std::vector<Override>& overrides = {}) {
  auto config = parse_pipeline_config(yaml, kFile, overrides);
  if (config) return "(accepted)";
  EXPECT_EQ(config.error().code, PLR_ERR_INVALID);
  return config.error().message;
}

PipelineConfig parse_ok(const std::string& yaml, const std::vector<Override>& overrides = {}) {
  auto config = parse_pipeline_config(yaml, kFile, overrides);
  EXPECT_TRUE(config) << config.error().message;
  return config ? std::move(config).value() : PipelineConfig{};
}

TEST(PipelineConfig, ParsesEveryField) {
  const PipelineConfig c = parse_ok(R"(pipeline: demo
plugin_paths: [../build/lib/plugins, /opt/plr/plugins]
clock: sim
hosts:
  sim: {restart: never, max_restarts: 3, backoff_ms: 50}
nodes:
  counter:
    plugin: demo_counter
    host: sim
    params: {period_ms: 50, gain: 0.5, on: true, label: hi, quoted: "3", none: ~,
             list: [1, two], nested: {a: 0x10}}
    remap: {count: demo/count}
  doubler:
    plugin: demo_doubler
topics:
  demo/count: {policy: reliable, depth: 16, slot_size: 65536, busy_poll: true}
remote:
  dds: {domain: 7, interfaces: [lo, eth0], export: ["telemetry/*"], import: [cmd/swap],
        allow_remote_control: true, security_dir: certs}
cpu_wake_latency_us: 0
)");
  const fs::path folder = fs::absolute("configs");
  EXPECT_EQ(c.file, (folder / "x.yaml").string());
  EXPECT_EQ(c.pipeline, "demo");
  EXPECT_EQ(c.plugin_paths,
            (std::vector<std::string>{(folder.parent_path() / "build/lib/plugins").string(),
                                      "/opt/plr/plugins"}));
  EXPECT_EQ(c.clock, "sim");

  ASSERT_EQ(c.hosts.size(), 2u);
  ASSERT_NE(c.host("main"), nullptr);
  const HostConfig* sim = c.host("sim");
  ASSERT_NE(sim, nullptr);
  EXPECT_EQ(sim->restart, RestartPolicy::Never);
  EXPECT_EQ(sim->max_restarts, 3);
  EXPECT_EQ(sim->backoff_ms, 50);
  EXPECT_EQ(sim->where.str(), "configs/x.yaml:5:3");

  ASSERT_EQ(c.nodes.size(), 2u);
  const NodeConfig* counter = c.node("counter");
  ASSERT_NE(counter, nullptr);
  EXPECT_EQ(counter->plugin, "demo_counter");
  EXPECT_EQ(counter->host, "sim");
  EXPECT_EQ(counter->where.str(), "configs/x.yaml:7:3");
  EXPECT_EQ(counter->params, nlohmann::json::parse(R"({"period_ms": 50, "gain": 0.5, "on": true,
      "label": "hi", "quoted": "3", "none": null, "list": [1, "two"], "nested": {"a": 16}})"));
  EXPECT_TRUE(counter->params["period_ms"].is_number_integer());
  EXPECT_TRUE(counter->params["gain"].is_number_float());
  EXPECT_EQ(counter->remap, (std::map<std::string, std::string>{{"count", "demo/count"}}));
  EXPECT_EQ(c.node("doubler")->host, "main");
  EXPECT_TRUE(c.node("doubler")->params.is_object());
  EXPECT_EQ(c.node("nobody"), nullptr);

  const TopicSettings count = c.topic("demo/count");
  EXPECT_EQ(count.policy, TopicPolicy::Reliable);
  EXPECT_EQ(count.depth, 16u);
  EXPECT_EQ(count.slot_size, 65536u);
  EXPECT_TRUE(count.busy_poll);

  EXPECT_TRUE(c.dds.enabled);
  EXPECT_EQ(c.dds.domain, 7);
  EXPECT_EQ(c.dds.interfaces, (std::vector<std::string>{"lo", "eth0"}));
  EXPECT_EQ(c.dds.export_patterns, std::vector<std::string>{"telemetry/*"});
  EXPECT_EQ(c.dds.import_patterns, std::vector<std::string>{"cmd/swap"});
  EXPECT_TRUE(c.dds.allow_remote_control);
  EXPECT_EQ(c.dds.security_dir, (folder / "certs").string());
  EXPECT_EQ(c.cpu_wake_latency_us, 0);
}

TEST(PipelineConfig, DefaultsForOptionalKeys) {
  const PipelineConfig c = parse_ok("nodes:\n  counter: {plugin: demo_counter}\n");
  EXPECT_EQ(c.pipeline, "x");
  EXPECT_TRUE(c.plugin_paths.empty());
  EXPECT_EQ(c.clock, "wall");
  EXPECT_FALSE(c.cpu_wake_latency_us);
  ASSERT_EQ(c.hosts.size(), 1u);
  EXPECT_EQ(c.hosts[0].name, "main");
  EXPECT_EQ(c.hosts[0].restart, RestartPolicy::OnFailure);
  const TopicSettings t = c.topic("any/topic");
  EXPECT_EQ(t.name, "any/topic");
  EXPECT_EQ(t.policy, TopicPolicy::KeepLast);
  EXPECT_EQ(t.depth, 64u);
  EXPECT_FALSE(t.slot_size) << "unset: sized from the message types";
  EXPECT_FALSE(c.dds.enabled);
}

TEST(PipelineConfig, SyntaxErrorHasYamlPosition) {
  EXPECT_EQ(error_of("nodes:\n  a: {plugin: x\n  b: 1\n"),
            "configs/x.yaml:3:4: syntax error: end of map flow not found");
}

TEST(PipelineConfig, UnknownKeySuggestsClosest) {
  EXPECT_EQ(error_of("nodes:\n  a:\n    plugn: x\n"),
            "configs/x.yaml:2:3: nodes.a: missing required key 'plugin'\n"
            "configs/x.yaml:3:5: nodes.a.plugn: unknown key 'plugn' (did you mean 'plugin'?)");
  EXPECT_EQ(error_of("nodes: {a: {plugin: x}}\ntopics:\n  t: {polcy: reliable, dpeth: 2}\n"),
            "configs/x.yaml:3:7: topics.t.polcy: unknown key 'polcy' (did you mean 'policy'?)\n"
            "configs/x.yaml:3:24: topics.t.dpeth: unknown key 'dpeth' (did you mean 'depth'?)");
}

// configs/evaluate.yaml given to `plr validate` listed a dozen unknown keys.
TEST(PipelineConfig, AnotherPlrFileIsNamedNotReadAsAPipeline) {
  EXPECT_EQ(error_of("# settings\nformat: plr-evaluation\nseeds: 10\n"),
            "configs/x.yaml:2:9: format: a 'plr-evaluation' file, not a pipeline config "
            "(`plr evaluate FILE` reads it)");
  EXPECT_EQ(error_of("format: plr-something\nnodes: {a: {plugin: x}}\n"),
            "configs/x.yaml:1:9: format: a 'plr-something' file, not a pipeline config");
}

TEST(PipelineConfig, UnknownKeyWithoutNearMatchListsKnownKeys) {
  EXPECT_EQ(error_of("nodes: {a: {plugin: x}}\nwhatever: 1\n"),
            "configs/x.yaml:2:1: whatever: unknown key 'whatever' (known keys: pipeline, "
            "plugin_paths, clock, cpu_wake_latency_us, hosts, nodes, topics, remote, shared)");
  EXPECT_EQ(error_of("nodes: {a: {plugin: x}}\nhosts: {h: {retries: 1}}\n"),
            "configs/x.yaml:2:13: hosts.h.retries: unknown key 'retries' (known keys: restart, "
            "max_restarts, restart_window_s, backoff_ms)");
  EXPECT_EQ(error_of("nodes: {a: {plugin: x}}\nremote: {dds: {domian: 1}}\n"),
            "configs/x.yaml:2:16: remote.dds.domian: unknown key 'domian' (did you mean "
            "'domain'?)");
}

TEST(PipelineConfig, WrongTypes) {
  EXPECT_EQ(error_of("nodes:\n  planner:\n    plugin: {name: x}\n"),
            "configs/x.yaml:3:13: nodes.planner.plugin: expected a string, got a map");
  EXPECT_EQ(error_of("nodes:\n  planner:\n    plugin:\n"),
            "configs/x.yaml:3:5: nodes.planner.plugin: expected a string, got nothing");
  EXPECT_EQ(error_of("nodes: {a: {plugin: x}}\ntopics: {t: {depth: many}}\n"),
            "configs/x.yaml:2:21: topics.t.depth: expected an integer, got 'many'");
  EXPECT_EQ(error_of("nodes: {a: {plugin: x}}\ntopics: {t: {depth: \"16\"}}\n"),
            "configs/x.yaml:2:21: topics.t.depth: expected an integer, got the string '16'");
  EXPECT_EQ(error_of("nodes: {a: {plugin: x}}\ntopics: {t: {busy_poll: yes}}\n"),
            "configs/x.yaml:2:25: topics.t.busy_poll: expected true or false, got 'yes'");
  EXPECT_EQ(error_of("nodes: {a: {plugin: x, params: [1]}}\n"),
            "configs/x.yaml:1:32: nodes.a.params: expected a map of parameters, got a list");
  EXPECT_EQ(error_of("plugin_paths: lib\nnodes: {a: {plugin: x}}\n"),
            "configs/x.yaml:1:15: plugin_paths: expected a list of folder paths, got 'lib'");
  EXPECT_EQ(error_of("nodes: [a, b]\n"),
            "configs/x.yaml:1:8: nodes: expected a map of node name -> node, got a list");
}

TEST(PipelineConfig, MissingRequiredKeys) {
  EXPECT_EQ(error_of("pipeline: p\n"), "configs/x.yaml:1:1: missing required key 'nodes'");
  EXPECT_EQ(error_of("nodes:\n  a: {host: main}\n"),
            "configs/x.yaml:2:3: nodes.a: missing required key 'plugin'");
  EXPECT_EQ(error_of("nodes:\n  a:\n"),
            "configs/x.yaml:2:3: nodes.a: missing required key 'plugin'");
}

TEST(PipelineConfig, EmptyNodes) {
  EXPECT_EQ(error_of("nodes: {}\n"),
            "configs/x.yaml:1:8: nodes: no nodes defined (at least one is required)");
  EXPECT_EQ(error_of("nodes:\n"),
            "configs/x.yaml:1:1: nodes: no nodes defined (at least one is required)");
}

TEST(PipelineConfig, EmptyOrNonMapDocument) {
  EXPECT_EQ(error_of(""),
            "configs/x.yaml:1:1: the config is empty (expected a map with a 'nodes' key)");
  EXPECT_EQ(error_of("- a\n- b\n"),
            "configs/x.yaml:1:1: expected a map at the top level, got a list");
}

TEST(PipelineConfig, NodeOnUndefinedHost) {
  EXPECT_EQ(error_of("hosts: {sim: {}}\nnodes:\n  a: {plugin: x, host: simm}\n"),
            "configs/x.yaml:3:24: nodes.a.host: host 'simm' is not defined in 'hosts' (did you "
            "mean 'sim'?)");
  EXPECT_EQ(error_of("hosts: {sim: {}}\nnodes:\n  a: {plugin: x, host: robot}\n"),
            "configs/x.yaml:3:24: nodes.a.host: host 'robot' is not defined in 'hosts' "
            "(defined: main, sim)");
}

TEST(PipelineConfig, BadEnumValuesListAllowedOnes) {
  EXPECT_EQ(error_of("clock: gps\nnodes: {a: {plugin: x}}\n"),
            "configs/x.yaml:1:8: clock: 'gps' is not one of: wall, sim");
  EXPECT_EQ(error_of("hosts: {sim: {restart: always}}\nnodes: {a: {plugin: x}}\n"),
            "configs/x.yaml:1:24: hosts.sim.restart: 'always' is not one of: never, on-failure");
  EXPECT_EQ(error_of("nodes: {a: {plugin: x}}\ntopics: {t: {policy: [a]}}\n"),
            "configs/x.yaml:2:22: topics.t.policy: expected one of: keep_last, reliable, got a "
            "list");
}

TEST(PipelineConfig, SizesMustBePositive) {
  EXPECT_EQ(error_of("nodes: {a: {plugin: x}}\ntopics:\n  t: {depth: 0, slot_size: -1}\n"),
            "configs/x.yaml:3:14: topics.t.depth: must be positive, got 0\n"
            "configs/x.yaml:3:28: topics.t.slot_size: must be positive, got -1");
  EXPECT_EQ(error_of("hosts: {h: {max_restarts: -1}}\nnodes: {a: {plugin: x}}\n"),
            "configs/x.yaml:1:27: hosts.h.max_restarts: must not be negative, got -1");
  EXPECT_EQ(error_of("nodes: {a: {plugin: x}}\nremote: {dds: {domain: 300}}\n"),
            "configs/x.yaml:2:24: remote.dds.domain: must be between 0 and 232, got 300");
  EXPECT_EQ(error_of("nodes: {a: {plugin: x}}\ntopics: {t: {depth: 99999999999999999999}}\n"),
            "configs/x.yaml:2:21: topics.t.depth: must be between 1 and 4096, "
            "got 99999999999999999999");
  EXPECT_EQ(error_of("cpu_wake_latency_us: -5\nnodes: {a: {plugin: x}}\n"),
            "configs/x.yaml:1:22: cpu_wake_latency_us: must not be negative, got -5");
}

TEST(PipelineConfig, DuplicateKeys) {
  EXPECT_EQ(error_of("nodes:\n  a: {plugin: x}\n  a: {plugin: y}\n"),
            "configs/x.yaml:3:3: nodes.a: duplicate key 'a' (first defined at "
            "configs/x.yaml:2:3)");
  EXPECT_EQ(error_of("nodes: {a: {plugin: x, params: {k: 1, k: 2}}}\n"),
            "configs/x.yaml:1:39: nodes.a.params.k: duplicate key 'k' (first defined at "
            "configs/x.yaml:1:33)");
}

TEST(PipelineConfig, NamesMustUseAllowedCharacters) {
  EXPECT_EQ(error_of("nodes:\n  my-node: {plugin: x}\n"),
            "configs/x.yaml:2:3: nodes.my-node: node name 'my-node' may contain only letters, "
            "digits and '_'");
  EXPECT_EQ(error_of("nodes:\n  a: {plugin: ../evil}\n"),
            "configs/x.yaml:2:15: nodes.a.plugin: plug-in name '../evil' may contain only "
            "letters, digits, '_' and '-'");
  EXPECT_EQ(error_of("nodes:\n  a:\n    plugin: x\n    remap: {count: demo count, \"a.b\": c}\n"),
            "configs/x.yaml:4:20: nodes.a.remap.count: topic or service name 'demo count' may "
            "contain only letters, digits, '_' and '/'\n"
            "configs/x.yaml:4:32: nodes.a.remap.a.b: topic or service name 'a.b' may contain "
            "only letters, digits, '_' and '/'");
  EXPECT_EQ(error_of("nodes: {a: {plugin: x}}\ntopics: {\"a b\": {}}\n"),
            "configs/x.yaml:2:10: topics.a b: topic name 'a b' may contain only letters, digits, "
            "'_' and '/'");
  EXPECT_EQ(error_of("nodes: {a: {plugin: x}}\nremote: {dds: {export: [\"a;b\"]}}\n"),
            "configs/x.yaml:2:25: remote.dds.export[0]: 'a;b' may contain only letters, digits, "
            "'_', '/' and '*'");
}

TEST(PipelineConfig, RemoteControlNeedsSecurity) {
  EXPECT_EQ(error_of("nodes: {a: {plugin: x}}\nremote:\n  dds: {allow_remote_control: true}\n"),
            "configs/x.yaml:3:31: remote.dds.allow_remote_control: remote control needs "
            "'security_dir' (DDS Security material)");
}

TEST(PipelineConfig, ReportsAllErrorsOneLineEachInFileOrder) {
  const std::string message = error_of(R"(clock: gps
nodes:
  a: {plugin: x, host: nowhere}
topics:
  t: {depth: 0}
)");
  EXPECT_EQ(message,
            "configs/x.yaml:1:8: clock: 'gps' is not one of: wall, sim\n"
            "configs/x.yaml:3:24: nodes.a.host: host 'nowhere' is not defined in 'hosts' "
            "(defined: main)\n"
            "configs/x.yaml:5:14: topics.t.depth: must be positive, got 0");
}

TEST(PipelineConfig, OverridesApplyBeforeValidation) {
  const std::string yaml = "nodes:\n  sim: {plugin: x, params: {seed: 1, name: a}}\n";
  const PipelineConfig c = parse_ok(yaml, {{"nodes.sim.params.seed", "3"},
                                           {"nodes.sim.params.gains", "[1.5, 2]"},
                                           {"nodes.extra.plugin", "y"},
                                           {"topics.t.depth", "8"}});
  EXPECT_EQ(c.node("sim")->params,
            nlohmann::json::parse(R"({"seed": 3, "name": "a", "gains": [1.5, 2]})"));
  EXPECT_TRUE(c.node("sim")->params["seed"].is_number_integer());
  ASSERT_NE(c.node("extra"), nullptr);
  EXPECT_EQ(c.node("extra")->plugin, "y");
  EXPECT_EQ(c.node("extra")->where.str(), "--set nodes.extra.plugin");
  EXPECT_EQ(c.topic("t").depth, 8u);
  // Starting from an empty file works too.
  EXPECT_EQ(parse_ok("", {{"nodes.a.plugin", "x"}}).node("a")->plugin, "x");
}

TEST(PipelineConfig, OverrideErrorsNameTheOverride) {
  const std::string yaml = "nodes:\n  sim: {plugin: x, params: {seed: 1}}\n";
  EXPECT_EQ(error_of(yaml, {{"nodes.sim.host", "nowhere"}}),
            "--set nodes.sim.host: nodes.sim.host: host 'nowhere' is not defined in 'hosts' "
            "(defined: main)");
  EXPECT_EQ(error_of(yaml, {{"nodes.sim.plugn", "y"}}),
            "--set nodes.sim.plugn: nodes.sim.plugn: unknown key 'plugn' (did you mean "
            "'plugin'?)");
  EXPECT_EQ(error_of(yaml, {{"nodes.other.params.seed", "3"}}),
            "--set nodes.other.params.seed: nodes.other: missing required key 'plugin'");
  EXPECT_EQ(error_of(yaml, {{"topics.t.depth", "{a: 1}"}}),
            "--set topics.t.depth: topics.t.depth: expected an integer, got a map");
  EXPECT_EQ(error_of(yaml, {{"nodes.sim.plugin.name", "x"}}),
            "--set nodes.sim.plugin.name: nodes.sim.plugin: expected a map to set 'name' in, got "
            "'x'");
  EXPECT_EQ(error_of(yaml, {{"nodes.sim.params.seed", "[1, 2"}}),
            "--set nodes.sim.params.seed: nodes.sim.params.seed: invalid YAML value '[1, 2': end "
            "of sequence flow not found");
  EXPECT_EQ(error_of(yaml, {{"nodes..x", "1"}}), "--set nodes..x: empty key in the path");
  EXPECT_EQ(error_of(yaml, {{"remote.dds.export", "[ok, \"a;b\"]"}}),
            "--set remote.dds.export: remote.dds.export[1]: 'a;b' may contain only letters, "
            "digits, '_', '/' and '*'");
  // A problem outside every override still points into the file.
  EXPECT_EQ(error_of("pipeline: p\n", {{"topics.t.depth", "1"}}),
            "configs/x.yaml:1:1: missing required key 'nodes'");
}

// The name becomes the control socket's file: `plr run` of
// `pipeline: ../../dir/victim` deleted dir/victim.sock and bound its own there.
TEST(PipelineConfig, APipelineNameIsANameNotAPath) {
  EXPECT_EQ(error_of("pipeline: ../../some/dir/victim\nnodes: {a: {plugin: x}}\n"),
            "configs/x.yaml:1:11: pipeline: '../../some/dir/victim' is not a name: 1 to 64 "
            "letters, digits, '_', '-' and '.', not starting with '.'");
  EXPECT_EQ(error_of("pipeline: ..\nnodes: {a: {plugin: x}}\n"),
            "configs/x.yaml:1:11: pipeline: '..' is not a name: 1 to 64 letters, digits, '_', "
            "'-' and '.', not starting with '.'");
  EXPECT_EQ(error_of("pipeline: \"a\\x1b[2Jb\"\nnodes: {a: {plugin: x}}\n"),
            "configs/x.yaml:1:11: pipeline: 'a\\x1b[2Jb' is not a name: 1 to 64 letters, "
            "digits, '_', '-' and '.', not starting with '.'");
  EXPECT_EQ(parse_ok("pipeline: unload-sim.v2_b\nnodes: {a: {plugin: x}}\n").pipeline,
            "unload-sim.v2_b");
}

// 4294967297 validated, was cut to 32 bits (1 byte) and delivered nothing.
TEST(PipelineConfig, SlotSizesAndDepthsAreBounded) {
  EXPECT_EQ(error_of("nodes: {a: {plugin: x}}\ntopics: {t: {slot_size: 4294967297}}\n"),
            "configs/x.yaml:2:25: topics.t.slot_size: must be between 1 and 268435456, got "
            "4294967297");
  EXPECT_EQ(error_of("nodes: {a: {plugin: x}}\ntopics: {t: {depth: 100000}}\n"),
            "configs/x.yaml:2:21: topics.t.depth: must be between 1 and 4096, got 100000");
}

// Cyclone reads no interface as "choose one", and chose the first real one.
TEST(PipelineConfig, AnEmptyDdsInterfaceListIsRefused) {
  EXPECT_EQ(error_of("nodes: {a: {plugin: x}}\nremote: {dds: {interfaces: []}}\n"),
            "configs/x.yaml:2:28: remote.dds.interfaces: an empty list would let DDS choose a "
            "network interface; name at least one ('lo': this machine only)");
  EXPECT_EQ(parse_ok("nodes: {a: {plugin: x}}\nremote: {dds: {}}\n").dds.interfaces,
            std::vector<std::string>{"lo"});
}

TEST(PipelineConfig, ParseOverride) {
  auto o = parse_override("nodes.sim.params.seed=3");
  ASSERT_TRUE(o) << o.error().message;
  EXPECT_EQ(o->path, "nodes.sim.params.seed");
  EXPECT_EQ(o->value, "3");
  auto with_equals = parse_override("nodes.a.params.expr=a=b");
  ASSERT_TRUE(with_equals);
  EXPECT_EQ(with_equals->value, "a=b");
  EXPECT_EQ(parse_override("seed").error().message, "--set seed: expected key.path=value");
  EXPECT_EQ(parse_override("=3").error().message, "--set =3: expected key.path=value");
  EXPECT_EQ(parse_override("a.=3").error().message, "--set a.: empty key in the path");
}

class ConfigFile : public ::testing::Test {
 protected:
  void SetUp() override {
    std::string pattern = (fs::temp_directory_path() / "plr_config_test_XXXXXX").string();
    ASSERT_NE(mkdtemp(pattern.data()), nullptr);
    dir_ = pattern;
  }
  void TearDown() override { fs::remove_all(dir_); }
  fs::path dir_;
};

TEST_F(ConfigFile, LoadsFileAndResolvesPathsAgainstItsFolder) {
  fs::create_directories(dir_ / "configs");
  const fs::path file = dir_ / "configs" / "unload.yaml";
  std::ofstream(file) << "plugin_paths: [../lib/plugins]\nnodes: {a: {plugin: x}}\n";
  auto c = load_pipeline_config(file.string(), {{"nodes.a.params.seed", "3"}});
  ASSERT_TRUE(c) << c.error().message;
  EXPECT_EQ(c->file, file.string());
  EXPECT_EQ(c->pipeline, "unload");
  EXPECT_EQ(c->plugin_paths, std::vector<std::string>{(dir_ / "lib" / "plugins").string()});
  EXPECT_EQ(c->node("a")->params["seed"], 3);
}

TEST_F(ConfigFile, ErrorsNameTheFileAsGiven) {
  const fs::path file = dir_ / "bad.yaml";
  std::ofstream(file) << "nodes:\n  a: {plugin: x, hots: main}\n";
  auto c = load_pipeline_config(file.string());
  ASSERT_FALSE(c);
  EXPECT_EQ(c.error().message,
            file.string() + ":2:18: nodes.a.hots: unknown key 'hots' (did you mean 'host'?)");
}

TEST_F(ConfigFile, MissingOrUnreadableFile) {
  const std::string missing = (dir_ / "missing.yaml").string();
  auto c = load_pipeline_config(missing);
  ASSERT_FALSE(c);
  EXPECT_EQ(c.error().message, missing + ": cannot read the config: No such file or directory");
  auto folder = load_pipeline_config(dir_.string());
  ASSERT_FALSE(folder);
  EXPECT_EQ(folder.error().message, dir_.string() + ": cannot read the config: it is a folder");
}

}  // namespace
}  // namespace plr::kernel
