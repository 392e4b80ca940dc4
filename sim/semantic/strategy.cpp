#include "plr/sim/strategy.hpp"

#include <yaml-cpp/yaml.h>
#include <plr/atomic_file.hpp>
#include <plr/yaml_reader.hpp>

#include <algorithm>
#include <array>
#include <cctype>
#include <fstream>
#include <sstream>

namespace plr::sim {

namespace {

constexpr std::array<const char*, 3> kHeights = {"low", "mid", "high"};
constexpr std::array<const char*, 3> kSides = {"left", "center", "right"};

template <std::size_t N>
std::optional<int> index_of(const std::array<const char*, N>& names, std::string_view s) {
  for (std::size_t i = 0; i < N; ++i)
    if (s == names[i]) return static_cast<int>(i);
  return std::nullopt;
}

std::string trim(std::string_view s) {
  std::string out;
  for (char c : s)
    if (!std::isspace(static_cast<unsigned char>(c)))
      out.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(c))));
  return out;
}

bool valid_action(Action a) {
  return static_cast<int>(a) < kNumActions;
}
bool valid_observation(Observation o) {
  return static_cast<int>(o) < kNumObservations;
}

}  // namespace

const char* to_string(Height h) {
  return kHeights[static_cast<int>(h)];
}
const char* to_string(Side s) {
  return kSides[static_cast<int>(s)];
}
const char* to_string(Structure s) {
  return s == Structure::kPile ? "pile" : "wall";
}

Action make_pick(Height h, Side s) {
  return static_cast<Action>(static_cast<int>(h) * 3 + static_cast<int>(s));
}
Action make_sweep(Height h) {
  return static_cast<Action>(static_cast<int>(Action::SweepLow) + static_cast<int>(h));
}
ActionKind kind(Action a) {
  return static_cast<int>(a) >= static_cast<int>(Action::SweepLow) ? ActionKind::kSweep
                                                                   : ActionKind::kPick;
}
Height height(Action a) {
  const int i = static_cast<int>(a);
  if (kind(a) == ActionKind::kSweep)
    return static_cast<Height>(i - static_cast<int>(Action::SweepLow));
  return static_cast<Height>(i / 3);
}
Side side(Action a) {
  if (kind(a) == ActionKind::kSweep) return Side::kCenter;
  return static_cast<Side>(static_cast<int>(a) % 3);
}

std::string to_string(Action a) {
  if (!valid_action(a)) return "Action(" + std::to_string(static_cast<int>(a)) + ")";
  if (kind(a) == ActionKind::kSweep) return std::string("Sweep(") + to_string(height(a)) + ")";
  return std::string("Pick(") + to_string(height(a)) + ", " + to_string(side(a)) + ")";
}

std::optional<Action> parse_action(std::string_view text) {
  const std::string t = trim(text);
  const auto open = t.find('(');
  if (open == std::string::npos || t.back() != ')') return std::nullopt;
  const std::string verb = t.substr(0, open);
  const std::string args = t.substr(open + 1, t.size() - open - 2);
  if (verb == "sweep") {
    const auto h = index_of(kHeights, args);
    if (!h) return std::nullopt;
    return make_sweep(static_cast<Height>(*h));
  }
  if (verb != "pick") return std::nullopt;
  const auto comma = args.find(',');
  if (comma == std::string::npos) return std::nullopt;
  const auto h = index_of(kHeights, std::string_view(args).substr(0, comma));
  const auto s = index_of(kSides, std::string_view(args).substr(comma + 1));
  if (!h || !s) return std::nullopt;
  return make_pick(static_cast<Height>(*h), static_cast<Side>(*s));
}

Observation make_observation(Structure st, Height h, Side s) {
  return static_cast<Observation>(static_cast<int>(st) * 9 + static_cast<int>(h) * 3 +
                                  static_cast<int>(s));
}
Structure structure(Observation o) {
  return static_cast<int>(o) >= 9 ? Structure::kWall : Structure::kPile;
}
Height height(Observation o) {
  return static_cast<Height>(static_cast<int>(o) % 9 / 3);
}
Side side(Observation o) {
  return static_cast<Side>(static_cast<int>(o) % 3);
}

std::string to_string(Observation o) {
  if (!valid_observation(o)) return "Observation(" + std::to_string(static_cast<int>(o)) + ")";
  return std::string(to_string(structure(o))) + "/" + to_string(height(o)) + "/" +
         to_string(side(o));
}

std::optional<Observation> parse_observation(std::string_view text) {
  const std::string t = trim(text);
  const auto a = t.find('/');
  const auto b = a == std::string::npos ? a : t.find('/', a + 1);
  if (b == std::string::npos) return std::nullopt;
  const std::string st = t.substr(0, a);
  if (st != "pile" && st != "wall") return std::nullopt;
  const auto h = index_of(kHeights, std::string_view(t).substr(a + 1, b - a - 1));
  const auto s = index_of(kSides, std::string_view(t).substr(b + 1));
  if (!h || !s) return std::nullopt;
  return make_observation(st == "pile" ? Structure::kPile : Structure::kWall,
                          static_cast<Height>(*h), static_cast<Side>(*s));
}

std::optional<std::uint32_t> Strategy::next(std::uint32_t node, Observation observation) const {
  if (node >= nodes.size()) return std::nullopt;
  for (const auto& [o, child] : nodes[node].children)
    if (o == observation) return child;
  return std::nullopt;
}

std::size_t Strategy::depth() const {
  if (nodes.empty()) return 0;
  // Breadth-first by levels; validate() guarantees a tree, so this ends.
  std::vector<std::uint32_t> level{root};
  std::size_t d = 0;
  while (!level.empty()) {
    ++d;
    std::vector<std::uint32_t> next_level;
    for (auto n : level)
      for (const auto& edge : nodes[n].children) next_level.push_back(edge.second);
    level = std::move(next_level);
  }
  return d;
}

Strategy single_action(Action action, std::string name) {
  Strategy s;
  s.name = std::move(name);
  s.nodes.push_back(StrategyNode{action, {}});
  return s;
}

plr::Status validate(const Strategy& s) {
  auto bad = [](std::string why) { return plr::make_error(PLR_ERR_INVALID, std::move(why)); };
  if (s.nodes.empty()) return bad("strategy has no nodes");
  if (s.root >= s.nodes.size())
    return bad("root " + std::to_string(s.root) + " out of range (" +
               std::to_string(s.nodes.size()) + " nodes)");
  std::vector<int> parents(s.nodes.size(), 0);
  for (std::size_t i = 0; i < s.nodes.size(); ++i) {
    const auto& n = s.nodes[i];
    if (!valid_action(n.action))
      return bad("node " + std::to_string(i) + ": invalid action " +
                 std::to_string(static_cast<int>(n.action)));
    std::array<bool, kNumObservations> seen{};
    for (const auto& [o, child] : n.children) {
      if (!valid_observation(o))
        return bad("node " + std::to_string(i) + ": invalid observation " +
                   std::to_string(static_cast<int>(o)));
      if (seen[static_cast<int>(o)])
        return bad("node " + std::to_string(i) + ": two edges for " + to_string(o));
      seen[static_cast<int>(o)] = true;
      if (child >= s.nodes.size())
        return bad("node " + std::to_string(i) + ": child " + std::to_string(child) +
                   " out of range");
      ++parents[child];
    }
  }
  if (parents[s.root] != 0) return bad("root " + std::to_string(s.root) + " has a parent");
  for (std::size_t i = 0; i < s.nodes.size(); ++i) {
    if (i != s.root && parents[i] != 1)
      return bad("node " + std::to_string(i) + " has " + std::to_string(parents[i]) +
                 " parents (a tree needs exactly one)");
  }
  // One parent each and a parentless root can still hide a cycle cut off from
  // the root; count what the root reaches.
  std::vector<std::uint32_t> stack{s.root};
  std::size_t reached = 0;
  while (!stack.empty() && reached <= s.nodes.size()) {
    const auto n = stack.back();
    stack.pop_back();
    ++reached;
    for (const auto& edge : s.nodes[n].children) stack.push_back(edge.second);
  }
  if (reached != s.nodes.size())
    return bad(std::to_string(s.nodes.size() - std::min(reached, s.nodes.size())) +
               " nodes are not reachable from the root");
  return {};
}

flatbuffers::Offset<plr::msg::Strategy> build(flatbuffers::FlatBufferBuilder& fbb,
                                              const Strategy& s) {
  std::vector<flatbuffers::Offset<plr::msg::StrategyNode>> nodes;
  nodes.reserve(s.nodes.size());
  for (const auto& n : s.nodes) {
    std::vector<flatbuffers::Offset<plr::msg::StrategyEdge>> edges;
    for (const auto& [o, child] : n.children)
      edges.push_back(plr::msg::CreateStrategyEdge(fbb, o, child));
    nodes.push_back(plr::msg::CreateStrategyNodeDirect(fbb, n.action, &edges));
  }
  return plr::msg::CreateStrategyDirect(fbb, s.name.c_str(), s.root, &nodes);
}

plr::Expected<Strategy> from_message(const plr::msg::Strategy& m, const std::string& origin) {
  Strategy s;
  if (m.name() != nullptr) s.name = m.name()->str();
  s.root = m.root();
  if (m.nodes() != nullptr) {
    for (const auto* n : *m.nodes()) {
      if (n == nullptr) return plr::make_error(PLR_ERR_INVALID, origin + ": null node");
      StrategyNode node{n->action(), {}};
      if (n->children() != nullptr)
        for (const auto* e : *n->children())
          if (e != nullptr) node.children.emplace_back(e->observation(), e->child());
      s.nodes.push_back(std::move(node));
    }
  }
  if (const auto ok = validate(s); !ok)
    return plr::make_error(PLR_ERR_INVALID, origin + ": " + ok.error().message);
  return s;
}

std::vector<std::uint8_t> serialize(const Strategy& s) {
  flatbuffers::FlatBufferBuilder fbb;
  plr::msg::FinishStrategyBuffer(fbb, build(fbb, s));
  return {fbb.GetBufferPointer(), fbb.GetBufferPointer() + fbb.GetSize()};
}

plr::Expected<Strategy> deserialize(const std::uint8_t* data, std::size_t size,
                                    const std::string& origin) {
  if (size < 8 || !flatbuffers::BufferHasIdentifier(data, plr::msg::StrategyIdentifier()))
    return plr::make_error(PLR_ERR_INVALID,
                           origin + ": not a strategy file (no \"PLRS\" identifier)");
  flatbuffers::Verifier verifier(data, size);
  if (!plr::msg::VerifyStrategyBuffer(verifier))
    return plr::make_error(PLR_ERR_INVALID,
                           origin + ": corrupt strategy file (verification failed)");
  return from_message(*plr::msg::GetStrategy(data), origin);
}

std::string format_yaml(const Strategy& s) {
  YAML::Emitter out;
  out << YAML::BeginMap << YAML::Key << "format" << YAML::Value << "plr-strategy";
  out << YAML::Key << "version" << YAML::Value << 1;
  out << YAML::Key << "name" << YAML::Value << s.name;
  out << YAML::Key << "root" << YAML::Value << s.root;
  out << YAML::Key << "nodes" << YAML::Value << YAML::BeginSeq;
  for (const auto& n : s.nodes) {
    out << YAML::Flow << YAML::BeginMap << YAML::Key << "action" << YAML::Value
        << to_string(n.action);
    if (!n.children.empty()) {
      out << YAML::Key << "children" << YAML::Value << YAML::BeginMap;
      for (const auto& [o, child] : n.children)
        out << YAML::Key << to_string(o) << YAML::Value << child;
      out << YAML::EndMap;
    }
    out << YAML::EndMap;
  }
  out << YAML::EndSeq << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

namespace {

// A tree of 18-way branches grows fast, but a strategy file of more nodes
// than this is a mistake (and its YAML is far past yaml::Limits anyway).
constexpr std::size_t kMaxNodes = 1'000'000;

std::optional<StrategyNode> read_node(const yaml::Node& item, std::size_t num_nodes) {
  const yaml::Map fields = item.map("a node", {"action", "children"});
  if (!fields) return std::nullopt;
  const yaml::Node action_node = fields.required("action");
  const auto text = action_node.string("an action");
  std::optional<Action> action;
  if (text) {
    action = parse_action(*text);
    if (!action) action_node.error("'" + *text + "' is not Pick(h, s) or Sweep(h)");
  }
  StrategyNode node{action.value_or(Action::PickLowLeft), {}};
  bool ok = action.has_value();
  for (const yaml::Node& edge : fields.find("children").map("a map of observation -> node index")) {
    const auto observation = parse_observation(edge.name());
    if (!observation)
      edge.key_error("'" + edge.name() + "' is not pile|wall/low|mid|high/left|center|right");
    const auto child = edge.integer(0, static_cast<std::int64_t>(num_nodes) - 1);
    if (observation && child)
      node.children.emplace_back(*observation, static_cast<std::uint32_t>(*child));
    else
      ok = false;
  }
  if (!ok) return std::nullopt;
  return node;
}

}  // namespace

plr::Expected<Strategy> parse_yaml(const std::string& text, const std::string& origin) {
  auto doc = yaml::Document::parse(text, origin);
  if (!doc) return doc.error();
  const yaml::Map top =
      doc->root().map("a strategy", {"format", "version", "name", "root", "nodes"});
  Strategy s;
  if (top) {
    const yaml::Node format = top.required("format");
    if (const auto f = format.string(); f && *f != "plr-strategy")
      format.error("expected 'plr-strategy', got '" + *f + "'");
    const yaml::Node version = top.required("version");
    if (const auto v = version.integer(); v && *v != 1)
      version.error("unsupported version " + std::to_string(*v) + " (this reader knows 1)");
    // The name may be empty ("" is what format_yaml writes for no name).
    const yaml::Node name = top.find("name");
    if (name.is_scalar())
      s.name = name.text();
    else if (name.present() && !name.is_null())
      name.error("expected a string, got " + name.describe());
    const yaml::Node nodes_node = top.required("nodes");
    const yaml::List nodes = nodes_node.list("a list of nodes", 0, kMaxNodes);
    if (nodes && nodes.size() == 0) nodes_node.error("a strategy needs at least one node");
    // The root is checked against the nodes when there are any.
    const std::int64_t last =
        nodes.size() > 0 ? static_cast<std::int64_t>(nodes.size()) - 1 : std::int64_t{kMaxNodes};
    if (const auto root = top.find("root").integer(0, last))
      s.root = static_cast<std::uint32_t>(*root);
    for (const yaml::Node& item : nodes)
      if (auto node = read_node(item, nodes.size())) s.nodes.push_back(std::move(*node));
    // What only the whole tree shows (two parents, unreachable nodes).
    if (doc->ok())
      if (const auto valid = validate(s); !valid) nodes_node.error(valid.error().message);
  }
  return doc->result(std::move(s));
}

namespace {
bool is_yaml(const std::filesystem::path& file) {
  const auto ext = file.extension().string();
  return ext == ".yaml" || ext == ".yml";
}
}  // namespace

plr::Status save_strategy(const Strategy& s, const std::filesystem::path& file) {
  if (const auto ok = validate(s); !ok)
    return plr::make_error(
        PLR_ERR_INVALID,
        file.string() + ": refusing to write an invalid strategy: " + ok.error().message);
  std::string content;
  if (is_yaml(file)) {
    content = format_yaml(s);
  } else {
    const auto bytes = serialize(s);
    content.assign(bytes.begin(), bytes.end());
  }
  return write_file_atomically(file.string(), content);
}

plr::Expected<Strategy> load_strategy(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return plr::make_error(PLR_ERR_INVALID, file.string() + ": cannot open");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) return plr::make_error(PLR_ERR_INVALID, file.string() + ": read error");
  const std::string content = ss.str();
  if (is_yaml(file)) return parse_yaml(content, file.string());
  return deserialize(reinterpret_cast<const std::uint8_t*>(content.data()), content.size(),
                     file.string());
}

}  // namespace plr::sim
