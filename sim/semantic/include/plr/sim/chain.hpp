// A library strategy with its continuations: the paper's sequence of
// precomputed strategies as one tree. Each continuation's tree is grafted
// where its parent's ends after the observations of its leaf (the edge for
// the leaf's last observation goes to the continuation's root), and so on
// down the chain, so that a run following the tree takes, where a strategy
// ends, the continuation for the leaf it actually reached; where none was
// made, the tree ends there as the strategy alone did.
#pragma once

#include <plr/expected.hpp>

#include <cstddef>
#include <vector>

#include "plr/sim/library.hpp"
#include "plr/sim/strategy.hpp"

namespace plr::sim {

struct Chain {
  Strategy strategy;  // named as the entry
  // The library entry each node of `strategy` comes from.
  std::vector<std::size_t> entry_of_node;
  std::size_t links = 1;  // entries grafted, the first included
};

// `library.entries[entry]` with its continuations grafted, at most
// `max_nodes` nodes (a continuation that would pass it is left out). An
// error names a continuation whose leaf is not a leaf of its parent's tree.
plr::Expected<Chain> chain(const Library& library, std::size_t entry, std::size_t max_nodes = 8000);

}  // namespace plr::sim
