// plr-library (`plr library ...`): lists and shows the entries of a strategy
// library file, writes an entry's strategy as a strategy file for the
// executor, and draws its pictures.
//
//   plr library list FILE
//   plr library show FILE ENTRY            (ENTRY: a name or an index)
//   plr library export FILE ENTRY OUT      (OUT: .plrs or .yaml)
//   plr library svg FILE DIR               (DIR/<name>.svg, <name>-anytime.svg)
#include <plr/atomic_file.hpp>

#include <fmt/format.h>

#include <cstdio>
#include <filesystem>
#include <string>

#include "plr/sim/library.hpp"
#include "truck/svg.hpp"

namespace {

using plr::sim::LibraryEntry;

int usage() {
  std::fprintf(stderr,
               "usage: plr library list FILE\n"
               "       plr library show FILE ENTRY\n"
               "       plr library export FILE ENTRY OUT.plrs|OUT.yaml\n"
               "       plr library svg FILE DIR\n");
  return 2;
}

const LibraryEntry* find(const plr::sim::Library& lib, const std::string& key) {
  for (const LibraryEntry& e : lib.entries) {
    if (e.name == key) return &e;
  }
  char* end = nullptr;
  const unsigned long i = std::strtoul(key.c_str(), &end, 10);
  if (!key.empty() && *end == '\0' && i < lib.entries.size()) return &lib.entries[i];
  return nullptr;
}

void list(const plr::sim::Library& lib) {
  std::printf("%-3s %-12s %-6s %5s %5s %5s %6s %-22s %7s %6s %8s %s\n", "#", "name", "family",
              "seed", "boxes", "nodes", "depth", "root bounds [s]", "trials", "sims", "wall",
              "made");
  for (std::size_t i = 0; i < lib.entries.size(); ++i) {
    const LibraryEntry& e = lib.entries[i];
    std::printf("%-3zu %-12s %-6s %5llu %5zu %5zu %6zu %-22s %7llu %6llu %7.0fs %s\n", i,
                e.name.c_str(), e.family.c_str(), static_cast<unsigned long long>(e.world_seed),
                e.world.boxes.size(), e.strategy.nodes.size(), e.strategy.depth(),
                fmt::format("[{:.1f}, {:.1f}]", e.lower, e.upper).c_str(),
                static_cast<unsigned long long>(e.provenance.trials),
                static_cast<unsigned long long>(e.provenance.simulations), e.provenance.wall_s,
                e.provenance.created.c_str());
  }
}

void show(const LibraryEntry& e) {
  const plr::sim::Provenance& p = e.provenance;
  std::printf("name: %s\nfamily: %s\nworld_seed: %llu\n", e.name.c_str(), e.family.c_str(),
              static_cast<unsigned long long>(e.world_seed));
  std::printf("world: %zu boxes in a %.2f x %.2f x %.2f m trailer\n", e.world.boxes.size(),
              e.world.trailer.width, e.world.trailer.height, e.world.trailer.depth);
  std::printf("observation: %s\n", e.observation_json.c_str());
  std::printf("root_bounds: [%.3f, %.3f]  # value = -(robot s + terminal estimate)\n", e.lower,
              e.upper);
  std::printf(
      "provenance: {seed: %llu, particles: %u, horizon: %u, trial_budget: %llu, trials: %llu, "
      "simulations: %llu, nodes: %llu, wall_s: %.1f, workers: %u, epsilon1: %g, epsilon2: %g, "
      "seconds_per_box: %g, created: %s}\n",
      static_cast<unsigned long long>(p.seed), p.particles, p.horizon,
      static_cast<unsigned long long>(p.trial_budget), static_cast<unsigned long long>(p.trials),
      static_cast<unsigned long long>(p.simulations), static_cast<unsigned long long>(p.nodes),
      p.wall_s, p.workers, p.epsilon1, p.epsilon2, p.seconds_per_box, p.created.c_str());
  std::printf("curve_points: %zu\nstrategy:\n", e.curve.size());
  std::fputs(plr::sim::format_yaml(e.strategy).c_str(), stdout);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) return usage();
  const std::string cmd = argv[1];
  auto lib = plr::sim::load_library(argv[2]);
  if (!lib) {
    std::fprintf(stderr, "plr library: %s\n", lib.error().message.c_str());
    return 1;
  }
  if (cmd == "list" && argc == 3) {
    list(*lib);
    return 0;
  }
  if (cmd == "svg" && argc == 4) {
    for (const LibraryEntry& e : lib->entries) {
      const std::filesystem::path dir(argv[3]);
      for (const auto& [file, text] :
           {std::pair{dir / (e.name + ".svg"), plr::generator::strategy_svg(e.strategy)},
            {dir / (e.name + "-anytime.svg"), plr::generator::anytime_svg(e)}}) {
        if (auto s = plr::write_file_atomically(file.string(), text); !s) {
          std::fprintf(stderr, "plr library: %s\n", s.error().message.c_str());
          return 1;
        }
      }
    }
    return 0;
  }
  if ((cmd == "show" && argc == 4) || (cmd == "export" && argc == 5)) {
    const LibraryEntry* e = find(*lib, argv[3]);
    if (!e) {
      std::fprintf(stderr, "plr library: %s: no entry '%s' (%zu entries)\n", argv[2], argv[3],
                   lib->entries.size());
      return 1;
    }
    if (cmd == "show") {
      show(*e);
      return 0;
    }
    if (auto s = plr::sim::save_strategy(e->strategy, argv[4]); !s) {
      std::fprintf(stderr, "plr library: %s\n", s.error().message.c_str());
      return 1;
    }
    return 0;
  }
  return usage();
}
