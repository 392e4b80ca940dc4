// Everything of a library entry that does not depend on when, where or how
// fast it was made: the tests that compare generations (workers killed,
// resumed, remote) compare these.
#pragma once

#include <fmt/format.h>

#include <filesystem>
#include <string>

#include "plr/sim/library.hpp"

namespace plr::sim::testing {

inline std::string entry_fingerprint(const LibraryEntry& e) {
  std::string s = fmt::format("{}\n{}[{:.17g}, {:.17g}] trials {} nodes {} simulations {}\n",
                              e.name, format_yaml(e.strategy), e.lower, e.upper,
                              e.provenance.trials, e.provenance.nodes, e.provenance.simulations);
  for (const auto& p : e.curve)
    s += fmt::format("{} {:.17g} {:.17g}\n", p.trials, p.lower, p.upper);
  if (e.is_continuation()) {
    s += "parent " + e.parent + " leaf";
    for (const Observation o : e.leaf) s += " " + to_string(o);
    for (const auto& p : e.start)
      s += fmt::format("\nstart {} {:016x} {}", p.particle, p.state_hash, p.boxes_left);
    s += "\n";
  }
  return s;
}

// Every entry's, or the error reading the file.
inline std::string library_fingerprint(const std::filesystem::path& library) {
  const auto lib = load_library(library);
  if (!lib) return "error: " + lib.error().message;
  std::string s;
  for (const auto& e : lib->entries) s += entry_fingerprint(e);
  return s;
}

}  // namespace plr::sim::testing
