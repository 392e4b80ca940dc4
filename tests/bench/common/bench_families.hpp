// --families A1,B1 for the benchmarks that run environment families.
#pragma once

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

#include "plr/sim/generators.hpp"

namespace plr::bench {

// Replaces `families` with the listed ones; an unknown name is a usage error.
inline CLI::Option* add_families_option(CLI::App& app, std::vector<sim::EnvFamily>& families,
                                        const std::string& what) {
  return app
      .add_option_function<std::vector<std::string>>(
          "--families",
          [&families](const std::vector<std::string>& names) {
            families.clear();
            for (const std::string& name : names) {
              const auto f = sim::parse_env_family(name);
              if (!f) throw CLI::ValidationError("--families", "unknown family '" + name + "'");
              families.push_back(*f);
            }
          },
          what)
      ->delimiter(',')
      ->type_name("LIST");
}

}  // namespace plr::bench
