// The located YAML reader: typed getters, the messages they record (with
// file:line:column and the key path), limits, and Document::set.
#include <plr/yaml_reader.hpp>

#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <fstream>

namespace plr::yaml {
namespace {

Document parse(const std::string& text, Limits limits = {}) {
  auto doc = Document::parse(text, "w.yaml", limits);
  EXPECT_TRUE(doc) << doc.error().message;
  return std::move(doc).value();
}

// The error a document ends with after `read` ran over its top value.
template <class Read>
std::string error_after(const std::string& text, Read read, Limits limits = {}) {
  const Document doc = parse(text, limits);
  read(doc.root());
  if (doc.ok()) return "(accepted)";
  EXPECT_EQ(doc.error().code, PLR_ERR_INVALID);
  return doc.error().message;
}

TEST(YamlReader, ReadsTypedValues) {
  const Document doc = parse(R"(name: box
count: 0x10
mass: 2.5
whole: 3
on: true
kind: wall
sizes: [1, 2.5, 3]
)");
  const Map m = doc.root().map("a box", {"name", "count", "mass", "whole", "on", "kind", "sizes"});
  ASSERT_TRUE(m);
  EXPECT_EQ(m.required("name").string(), "box");
  EXPECT_EQ(m.required("count").integer(0, 100), 16);
  EXPECT_EQ(m.required("mass").number(0, 10), 2.5);
  EXPECT_EQ(m.required("whole").positive(), 3.0) << "an integer is a number too";
  EXPECT_EQ(m.required("on").boolean(), true);
  EXPECT_EQ(m.required("kind").one_of({"pile", "wall"}), "wall");
  const List sizes = m.required("sizes").list("a list of 3 sizes", 3, 3);
  ASSERT_TRUE(sizes);
  EXPECT_EQ(sizes[1].number(), 2.5);
  EXPECT_EQ(sizes[2].path(), "sizes[2]");
  EXPECT_EQ(m.size(), 7u);
  EXPECT_TRUE(doc.ok());
  EXPECT_EQ(doc.result(42).value(), 42);
}

TEST(YamlReader, ErrorsNameFileLineColumnAndKeyPath) {
  EXPECT_EQ(error_after("boxes:\n  - {size: [1, 2]}\n",
                        [](const Node& top) {
                          (void)top.map().required("boxes").list()[0].map().required("size").list(
                              "3 positive numbers", 3, 3);
                        }),
            "w.yaml:2:12: boxes[0].size: must have exactly 3 items, got 2");
  EXPECT_EQ(error_after("trailer: {width: -2}\n",
                        [](const Node& top) {
                          (void)top.map().required("trailer").map().required("width").positive();
                        }),
            "w.yaml:1:18: trailer.width: must be positive, got -2");
  EXPECT_EQ(error_after("depth: many\n",
                        [](const Node& top) { (void)top.map().required("depth").number(); }),
            "w.yaml:1:8: depth: expected a number, got 'many'");
  EXPECT_EQ(error_after("depth: \"16\"\n",
                        [](const Node& top) { (void)top.map().required("depth").integer(); }),
            "w.yaml:1:8: depth: expected an integer, got the string '16'");
  EXPECT_EQ(
      error_after("on: yes\n", [](const Node& top) { (void)top.map().required("on").boolean(); }),
      "w.yaml:1:5: on: expected true or false, got 'yes'");
  EXPECT_EQ(error_after("kind: gps\n",
                        [](const Node& top) {
                          (void)top.map().required("kind").one_of({"wall", "pile"});
                        }),
            "w.yaml:1:7: kind: 'gps' is not one of: wall, pile");
  EXPECT_EQ(
      error_after("x: .inf\n", [](const Node& top) { (void)top.map().required("x").number(); }),
      "w.yaml:1:4: x: expected a finite number, got '.inf'");
}

TEST(YamlReader, RangesSayWhichBound) {
  const auto integer = [](const std::string& text, std::int64_t min, std::int64_t max) {
    return error_after(text, [&](const Node& n) { (void)n.integer(min, max); });
  };
  EXPECT_EQ(integer("0", 1, 10), "w.yaml:1:1: must be positive, got 0");
  EXPECT_EQ(integer("-1", 0, 10), "w.yaml:1:1: must not be negative, got -1");
  EXPECT_EQ(integer("300", 0, 232), "w.yaml:1:1: must be between 0 and 232, got 300");
  EXPECT_EQ(integer("99999999999999999999", 1, 5),
            "w.yaml:1:1: must be between 1 and 5, got 99999999999999999999");
  const auto number = [](const std::string& text, double min, double max) {
    return error_after(text, [&](const Node& n) { (void)n.number(min, max); });
  };
  constexpr double kInf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(number("-0.5", 0, kInf), "w.yaml:1:1: must not be negative, got -0.5");
  EXPECT_EQ(number("0.5", 1.5, kInf), "w.yaml:1:1: must be at least 1.5, got 0.5");
  EXPECT_EQ(number("7", -kInf, 2), "w.yaml:1:1: must be at most 2, got 7");
  EXPECT_EQ(number("7", 0, 2.5), "w.yaml:1:1: must be between 0 and 2.5, got 7");
  EXPECT_EQ(error_after("[1, 2, 3]", [](const Node& n) { (void)n.list("a list", 0, 2); }),
            "w.yaml:1:1: must have at most 2 items, got 3");
  EXPECT_EQ(error_after("[]", [](const Node& n) { (void)n.list("a list", 1, 2); }),
            "w.yaml:1:1: must have at least 1 items, got 0");
}

TEST(YamlReader, RequiredOptionalUnknownAndDuplicateKeys) {
  EXPECT_EQ(
      error_after("a: {host: main}\n",
                  [](const Node& top) { (void)top.map().required("a").map().required("plugin"); }),
      "w.yaml:1:1: a: missing required key 'plugin'");
  EXPECT_EQ(error_after("a: 1\n",
                        [](const Node& top) {
                          EXPECT_FALSE(top.map().find("b").present());
                          EXPECT_EQ(top.map().find("b").number(), std::nullopt)
                              << "an absent key reads as nothing, quietly";
                        }),
            "(accepted)");
  EXPECT_EQ(error_after("polcy: 1\nwhatever: 2\n",
                        [](const Node& top) {
                          (void)top.map("a topic", {"policy", "depth"});
                        }),
            "w.yaml:1:1: polcy: unknown key 'polcy' (did you mean 'policy'?)");
  Limits all;
  all.max_errors = 0;
  EXPECT_EQ(error_after(
                "polcy: 1\nwhatever: 2\n",
                [](const Node& top) {
                  (void)top.map("a topic", {"policy", "depth"});
                },
                all),
            "w.yaml:1:1: polcy: unknown key 'polcy' (did you mean 'policy'?)\n"
            "w.yaml:2:1: whatever: unknown key 'whatever' (known keys: policy, depth)");
  EXPECT_EQ(error_after("a: 1\nb: 2\na: 3\n", [](const Node& top) { (void)top.map(); }),
            "w.yaml:3:1: a: duplicate key 'a' (first defined at w.yaml:1:1)");
  EXPECT_EQ(error_after("[a]: 1\n", [](const Node& top) { (void)top.map(); }),
            "w.yaml:1:1: a key must be a plain name, got a list");
}

TEST(YamlReader, FirstErrorInFileOrderWinsUnlessAllAreAskedFor) {
  const auto read = [](const Node& top) {
    const Map m = top.map();
    (void)m.required("z").integer(0, 1);
    (void)m.required("a").integer(0, 1);
  };
  EXPECT_EQ(error_after("a: 5\nz: 7\n", read), "w.yaml:1:4: a: must be between 0 and 1, got 5");
  Limits all;
  all.max_errors = 0;
  EXPECT_EQ(error_after("a: 5\nz: 7\n", read, all),
            "w.yaml:1:4: a: must be between 0 and 1, got 5\n"
            "w.yaml:2:4: z: must be between 0 and 1, got 7");
}

TEST(YamlReader, NullValuesPointAtTheirKey) {
  EXPECT_EQ(error_after("plugin:\n",
                        [](const Node& top) { (void)top.map().required("plugin").string(); }),
            "w.yaml:1:1: plugin: expected a string, got nothing");
  EXPECT_EQ(error_after("list: [a, ~]\n",
                        [](const Node& top) {
                          for (const Node& item : top.map().required("list").list())
                            (void)item.string("a name");
                        }),
            "w.yaml:1:7: list[1]: expected a name, got nothing");
  EXPECT_EQ(
      error_after("name: ''\n", [](const Node& top) { (void)top.map().required("name").string(); }),
      "w.yaml:1:7: name: expected a string, got an empty string");
}

TEST(YamlReader, ErrorLinesStayOneLine) {
  EXPECT_EQ(error_after("k: \"two\\nlines\"\n",
                        [](const Node& top) { (void)top.map().required("k").integer(); }),
            "w.yaml:1:4: k: expected an integer, got the string 'two\\nlines'");
}

TEST(YamlReader, ToJsonFollowsTheCoreSchema) {
  const Document doc =
      parse("{i: 0x10, f: 0.5, b: true, s: yes, q: \"3\", n: ~, l: [1, two], m: {a: 0o17}}");
  EXPECT_EQ(doc.root().to_json(),
            nlohmann::json::parse(
                R"({"i": 16, "f": 0.5, "b": true, "s": "yes", "q": "3", "n": null,
                    "l": [1, "two"], "m": {"a": 15}})"));
  EXPECT_TRUE(doc.ok());
  EXPECT_EQ(error_after(
                "{a: .nan, b: 99999999999999999999}", [](const Node& n) { (void)n.to_json(); },
                Limits{.max_errors = 0}),
            "w.yaml:1:5: a: '.nan' (infinity or NaN) has no JSON form\n"
            "w.yaml:1:14: b: integer 99999999999999999999 is out of range (64 bits, signed)");
}

TEST(YamlReader, SyntaxErrorsAndLimits) {
  auto bad = Document::parse("a: {b: 1\nc: 2\n", "w.yaml");
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error().message, "w.yaml:2:2: syntax error: end of map flow not found");

  auto big = Document::parse(std::string(100, 'a'), "w.yaml", Limits{.max_bytes = 10});
  ASSERT_FALSE(big);
  EXPECT_EQ(big.error().message, "w.yaml: larger than 10 bytes");

  auto deep = Document::parse("[[[[1]]]]", "w.yaml", Limits{.max_depth = 3});
  ASSERT_FALSE(deep);
  EXPECT_EQ(deep.error().message, "w.yaml:1:4: nested deeper than 3 levels");

  auto many = Document::parse("[1, 2, 3, 4]", "w.yaml", Limits{.max_values = 3});
  ASSERT_FALSE(many);
  EXPECT_EQ(many.error().message, "w.yaml:1:8: more than 3 values");

  auto cycle = Document::parse("&a [*a]", "w.yaml");
  ASSERT_FALSE(cycle);
  EXPECT_EQ(cycle.error().message, "w.yaml:1:5: an alias refers to a value that holds it");
}

TEST(YamlReader, AliasesAreSharedAndBoundedWhenExpanded) {
  // Each level doubles the previous one: expanded, 2^20 values.
  std::string text = "a0: &a0 [x, y]\n";
  for (int i = 1; i <= 20; ++i)
    text += "a" + std::to_string(i) + ": &a" + std::to_string(i) + " [*a" + std::to_string(i - 1) +
            ", *a" + std::to_string(i - 1) + "]\n";
  const Document doc = parse(text, Limits{.max_values = 10'000});
  (void)doc.root().to_json();
  ASSERT_FALSE(doc.ok());
  EXPECT_NE(doc.error().message.find("more than 10000 values with aliases expanded"),
            std::string::npos)
      << doc.error().message;
}

TEST(YamlReader, AliasesNestedInEachOtherAreBoundedInDepth) {
  // Each anchor wraps the one before in a list: shallow as written, 100 deep expanded.
  std::string text = "a0: &a0 [1]\n";
  for (int i = 1; i <= 100; ++i)
    text += "a" + std::to_string(i) + ": &a" + std::to_string(i) + " [*a" + std::to_string(i - 1) +
            "]\n";
  const Document doc = parse(text);
  (void)doc.root().to_json();
  ASSERT_FALSE(doc.ok());
  EXPECT_NE(doc.error().message.find("nested deeper than 64 levels with aliases expanded"),
            std::string::npos)
      << doc.error().message;
}

TEST(YamlReader, EmptyDocumentIsNullAtTheStart) {
  EXPECT_EQ(error_after("", [](const Node& n) { n.error("the config is empty"); }),
            "w.yaml:1:1: the config is empty");
}

TEST(YamlReader, SetPutsLabelledValuesBeforeReading) {
  Document doc = parse("nodes:\n  sim: {plugin: x, params: {seed: 1}}\n");
  doc.set("nodes.sim.params.seed", "3", "--set nodes.sim.params.seed");
  doc.set("nodes.extra.plugin", "y", "--set nodes.extra.plugin");
  ASSERT_TRUE(doc.ok()) << doc.error().message;
  const Map nodes = doc.root().map().required("nodes").map();
  const Node seed = nodes.required("sim").map().required("params").map().required("seed");
  EXPECT_EQ(seed.integer(), 3);
  EXPECT_EQ(seed.location().str(), "--set nodes.sim.params.seed");
  const Node extra = nodes.required("extra");
  EXPECT_EQ(extra.key_location().str(), "--set nodes.extra.plugin");
  EXPECT_EQ(extra.map().required("plugin").string(), "y");
  EXPECT_EQ(nodes.required("sim").key_location().str(), "w.yaml:2:3");
  // Labelled problems come after those of the file.
  (void)extra.map().required("plugin").integer();
  (void)nodes.required("sim").map().required("plugin").integer();
  EXPECT_EQ(doc.error().message, "w.yaml:2:17: nodes.sim.plugin: expected an integer, got 'x'");
}

TEST(YamlReader, SetReportsWhatItCannotDo) {
  const auto after_set = [](const std::string& path, const std::string& value) {
    Document doc = parse("a: {b: x}\n");
    doc.set(path, value, "--set " + path);
    return doc.ok() ? std::string("(accepted)") : doc.error().message;
  };
  EXPECT_EQ(after_set("a.b.c", "1"), "--set a.b.c: a.b: expected a map to set 'c' in, got 'x'");
  EXPECT_EQ(after_set("a..c", "1"), "--set a..c: empty key in the path");
  EXPECT_EQ(after_set("a.b", "[1, 2"),
            "--set a.b: a.b: invalid YAML value '[1, 2': end of sequence flow not found");
  Document empty = parse("");
  empty.set("nodes.a.plugin", "x", "--set nodes.a.plugin");
  EXPECT_EQ(
      empty.root().map().required("nodes").map().required("a").map().required("plugin").string(),
      "x");
  EXPECT_EQ(empty.root().location().str(), "w.yaml:1:1") << "the top keeps its place";
}

TEST(YamlReader, OpenReadsFilesBoundedAndSaysWhyNot) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("plr_yaml_reader_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  const auto file = (dir / "w.yaml").string();
  std::ofstream(file) << "a: 1\n";
  auto doc = Document::open(file, "the world");
  ASSERT_TRUE(doc) << doc.error().message;
  EXPECT_EQ(doc->root().map().required("a").integer(), 1);
  EXPECT_EQ(Document::open(file, "the world", Limits{.max_bytes = 2}).error().message,
            file + ": cannot read the world: larger than 2 bytes");
  EXPECT_EQ(Document::open(dir.string(), "the world").error().message,
            dir.string() + ": cannot read the world: it is a folder");
  EXPECT_EQ(Document::open((dir / "none.yaml").string(), "the world").error().message,
            (dir / "none.yaml").string() + ": cannot read the world: No such file or directory");
  std::filesystem::remove_all(dir);
}

TEST(YamlReader, DidYouMean) {
  EXPECT_EQ(did_you_mean("plugn", {"plugin", "host"}, "known keys"), " (did you mean 'plugin'?)");
  EXPECT_EQ(did_you_mean("hsot", {"plugin", "host"}, "known keys"), " (did you mean 'host'?)");
  EXPECT_EQ(did_you_mean("robot", {"main", "sim"}, "defined"), " (defined: main, sim)");
}

}  // namespace
}  // namespace plr::yaml
