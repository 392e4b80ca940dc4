// A policy tree: an action at each node, a child per observation. The same
// shape as the project's strategies (plr/sim/strategy.hpp: an action index
// per node, children keyed by observation index), so a truck strategy is a
// relabelling of one of these.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include <plr/expected.hpp>

#include "plr/pomdp/belief.hpp"

namespace plr::pomdp {

struct PolicyNode {
  ActionId action = 0;
  std::vector<std::pair<ObsId, std::uint32_t>> children;  // observation -> node, sorted
  // Bounds on the value of the node's belief when the tree was made.
  double lower = 0.0, upper = 0.0;
};

struct PolicyTree {
  std::uint32_t root = 0;
  std::vector<PolicyNode> nodes;

  std::optional<std::uint32_t> next(std::uint32_t node, ObsId observation) const;
  std::size_t depth() const;
};

// Text form, one node a line:
//   plr-policy-tree 1
//   nodes <count> root <index>
//   <index> <action> <lower> <upper> [<observation>:<child> ...]
std::string format_policy_tree(const PolicyTree& tree);
// Errors: "origin:line: what is wrong".
plr::Expected<PolicyTree> parse_policy_tree(std::string_view text, const std::string& origin);

}  // namespace plr::pomdp
