#include "plr/pomdp/policy_tree.hpp"

#include <algorithm>
#include <sstream>

#include <fmt/format.h>

#include "plr/pomdp/text.hpp"

namespace plr::pomdp {

std::optional<std::uint32_t> PolicyTree::next(std::uint32_t node, ObsId observation) const {
  const auto& ch = nodes[node].children;
  const auto it = std::lower_bound(ch.begin(), ch.end(), observation,
                                   [](const auto& c, ObsId o) { return c.first < o; });
  if (it == ch.end() || it->first != observation) return std::nullopt;
  return it->second;
}

std::size_t PolicyTree::depth() const {
  if (nodes.empty()) return 0;
  std::size_t best = 0;
  std::vector<std::pair<std::uint32_t, std::size_t>> stack{{root, 1}};
  while (!stack.empty()) {
    const auto [n, d] = stack.back();
    stack.pop_back();
    best = std::max(best, d);
    for (const auto& [o, c] : nodes[n].children) stack.emplace_back(c, d + 1);
  }
  return best;
}

std::string format_policy_tree(const PolicyTree& tree) {
  std::string out =
      fmt::format("plr-policy-tree 1\nnodes {} root {}\n", tree.nodes.size(), tree.root);
  for (std::size_t i = 0; i < tree.nodes.size(); ++i) {
    const PolicyNode& n = tree.nodes[i];
    out += fmt::format("{} {} {:.17g} {:.17g}", i, n.action, n.lower, n.upper);
    for (const auto& [o, c] : n.children) out += fmt::format(" {}:{}", o, c);
    out += '\n';
  }
  return out;
}

namespace {

template <class T>
bool parse_number(std::string_view s, T& out) {
  std::optional<T> v;
  if constexpr (std::is_floating_point_v<T>) {
    v = text::to_number(s);
  } else {
    v = text::to_integer<T>(s);
  }
  if (v) out = *v;
  return v.has_value();
}

}  // namespace

plr::Expected<PolicyTree> parse_policy_tree(std::string_view text, const std::string& origin) {
  const auto error = [&origin](int line, const std::string& what) {
    return plr::make_error(PLR_ERR_INVALID, fmt::format("{}:{}: {}", origin, line, what));
  };
  std::vector<std::string_view> lines;
  for (std::size_t start = 0; start <= text.size();) {
    const std::size_t end = std::min(text.find('\n', start), text.size());
    lines.push_back(text.substr(start, end - start));
    start = end + 1;
  }
  if (lines.empty() ||
      text::words(lines[0]) != std::vector<std::string_view>{"plr-policy-tree", "1"}) {
    return error(1, "expected 'plr-policy-tree 1'");
  }
  const auto head = lines.size() > 1 ? text::words(lines[1]) : std::vector<std::string_view>{};
  PolicyTree tree;
  std::size_t count = 0;
  if (head.size() != 4 || head[0] != "nodes" || head[2] != "root" ||
      !parse_number(head[1], count) || !parse_number(head[3], tree.root)) {
    return error(2, "expected 'nodes <count> root <index>'");
  }
  if (count + 2 > lines.size())
    return error(2, fmt::format("{} nodes announced, fewer lines follow", count));
  if (count == 0 || tree.root >= count) return error(2, "the root is not a node");
  tree.nodes.resize(count);
  std::vector<int> parents(count, 0);
  for (std::size_t i = 0; i < count; ++i) {
    const int line = static_cast<int>(i) + 3;
    const auto f = text::words(lines[i + 2]);
    std::size_t index = 0;
    PolicyNode& n = tree.nodes[i];
    if (f.size() < 4 || !parse_number(f[0], index) || index != i || !parse_number(f[1], n.action) ||
        n.action < 0 || !parse_number(f[2], n.lower) || !parse_number(f[3], n.upper)) {
      return error(line, fmt::format("expected '{} <action> <lower> <upper> [obs:child ...]'", i));
    }
    for (std::size_t k = 4; k < f.size(); ++k) {
      const auto colon = f[k].find(':');
      ObsId o = 0;
      std::uint32_t c = 0;
      if (colon == std::string_view::npos || !parse_number(f[k].substr(0, colon), o) || o < 0 ||
          !parse_number(f[k].substr(colon + 1), c) || c >= count) {
        return error(line, fmt::format("bad child '{}'", f[k]));
      }
      if (!n.children.empty() && n.children.back().first >= o) {
        return error(line, "children must be sorted by observation, each once");
      }
      if (c == tree.root || ++parents[c] > 1) {
        return error(line, fmt::format("node {} has more than one parent", c));
      }
      n.children.emplace_back(o, c);
    }
  }
  // One parent each is not enough: a cycle apart from the root has that too.
  std::vector<char> reached(count, 0);
  std::vector<std::uint32_t> stack{tree.root};
  while (!stack.empty()) {
    const std::uint32_t n = stack.back();
    stack.pop_back();
    reached[n] = 1;
    for (const auto& [o, c] : tree.nodes[n].children) stack.push_back(c);
  }
  for (std::size_t i = 0; i < count; ++i) {
    if (!reached[i]) return error(static_cast<int>(i) + 3, "node not reached from the root");
  }
  for (std::size_t i = count + 2; i < lines.size(); ++i) {
    if (!text::words(lines[i]).empty())
      return error(static_cast<int>(i) + 1, "text after the last node");
  }
  return tree;
}

}  // namespace plr::pomdp
