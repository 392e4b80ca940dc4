#include "plr/sim/chain.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <string_view>
#include <unordered_map>

namespace plr::sim {

namespace {

struct Graft {
  std::size_t entry;
  std::uint32_t offset;  // where its nodes start in the chain's strategy
};

}  // namespace

plr::Expected<Chain> chain(const Library& library, std::size_t entry, std::size_t max_nodes) {
  Chain out;
  const LibraryEntry& first = library.entries.at(entry);
  out.strategy = first.strategy;
  out.entry_of_node.assign(first.strategy.nodes.size(), entry);
  // Each entry's continuations, found once.
  std::unordered_map<std::string_view, std::vector<std::size_t>> children;
  for (std::size_t i = 0; i < library.entries.size(); ++i)
    if (library.entries[i].is_continuation()) children[library.entries[i].parent].push_back(i);
  // Breadth first: a parent's nodes are in place before its continuations'.
  std::vector<Graft> queue{{entry, 0}};
  for (std::size_t k = 0; k < queue.size(); ++k) {
    const Graft parent = queue[k];
    const Strategy& tree = library.entries[parent.entry].strategy;
    const auto found = children.find(library.entries[parent.entry].name);
    if (found == children.end()) continue;
    for (const std::size_t c : found->second) {
      const LibraryEntry& next = library.entries[c];
      const auto bad = [&](const std::string& why) {
        return plr::make_error(PLR_ERR_INVALID,
                               fmt::format("continuation '{}' of '{}': {}", next.name,
                                           library.entries[parent.entry].name, why));
      };
      // The leaf: the node whose action ends the parent's tree, reached by
      // all but the last observation.
      std::uint32_t node = tree.root;
      for (std::size_t i = 0; i + 1 < next.leaf.size(); ++i) {
        const auto child = tree.next(node, next.leaf[i]);
        if (!child) return bad(fmt::format("no edge for observation {} of its leaf", i + 1));
        node = *child;
      }
      if (next.leaf.empty() || tree.next(node, next.leaf.back()))
        return bad("its leaf is not where the parent's tree ends");
      if (out.strategy.nodes.size() + next.strategy.nodes.size() > max_nodes) continue;
      const auto offset = static_cast<std::uint32_t>(out.strategy.nodes.size());
      for (StrategyNode n : next.strategy.nodes) {
        for (auto& edge : n.children) edge.second += offset;
        out.strategy.nodes.push_back(std::move(n));
        out.entry_of_node.push_back(c);
      }
      auto& edges = out.strategy.nodes[parent.offset + node].children;
      edges.emplace_back(next.leaf.back(), offset + next.strategy.root);
      std::sort(edges.begin(), edges.end());
      queue.push_back({c, offset});
      ++out.links;
    }
  }
  if (auto ok = validate(out.strategy); !ok)
    return plr::make_error(PLR_ERR_INVALID, first.name + ": chained: " + ok.error().message);
  return out;
}

}  // namespace plr::sim
