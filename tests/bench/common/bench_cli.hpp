// The command line every benchmark shares (CLI11): --json and --quick with
// the same words in every --help, and parsing that exits on a bad option.
#pragma once

#include <CLI/CLI.hpp>

#include <cstdlib>
#include <string>

namespace plr::bench {

inline void add_json_flag(CLI::App& app, bool& json) {
  app.add_flag("--json", json, "Print one JSON object instead of tables");
}

// `cuts`: what the quick run leaves out, e.g. "seeds 1-5".
inline void add_quick_flag(CLI::App& app, bool& quick, const std::string& cuts) {
  app.add_flag("--quick", quick, "A shorter run: " + cuts);
}

// Parses argv; on --help prints it and exits 0, on a bad option prints one
// line and exits non-zero.
inline void parse_or_exit(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    std::exit(app.exit(e));
  }
}

}  // namespace plr::bench
