// plr-library (`plr library ...`): lists and shows the entries of a strategy
// library file, writes an entry's strategy as a strategy file for the
// executor, and draws its pictures.
//
//   plr library list FILE                  (with the chains: parent -> continuations)
//   plr library show FILE ENTRY            (ENTRY: a name or an index)
//   plr library export FILE ENTRY OUT      (OUT: .plrs or .yaml)
//   plr library svg FILE DIR               (DIR/<name>.svg, <name>-anytime.svg)
#include <plr/atomic_file.hpp>

#include <fmt/format.h>
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string>

#include "plr/sim/library.hpp"
#include "truck/svg.hpp"

namespace {

using plr::sim::LibraryEntry;

// "wall/low/left > pile/mid/center": a leaf's observations from its parent's root.
std::string path(const LibraryEntry& e) {
  std::string out;
  for (const plr::sim::Observation o : e.leaf)
    out += (out.empty() ? "" : " > ") + plr::sim::to_string(o);
  return out;
}

std::uint32_t boxes_left(const LibraryEntry& e) {
  std::uint32_t n = 0;
  for (const auto& p : e.start) n += p.boxes_left;
  return e.start.empty() ? 0 : n / static_cast<std::uint32_t>(e.start.size());
}

// Each continuation under its parent, with the leaf it starts at.
void print_chain(const plr::sim::Library& lib, std::size_t entry, int depth) {
  for (const std::size_t c : plr::sim::continuations(lib, entry)) {
    const LibraryEntry& e = lib.entries[c];
    std::printf("%*s-> %s at [%s]: %zu particle%s, %u boxes left, %zu nodes\n", 2 + 4 * depth, "",
                e.name.c_str(), path(e).c_str(), e.start.size(), e.start.size() == 1 ? "" : "s",
                boxes_left(e), e.strategy.nodes.size());
    if (depth < 1000) print_chain(lib, c, depth + 1);
  }
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
  // Continuations' names grow with the chain ("B1-1.1.1.2").
  int width = 12;
  for (const LibraryEntry& e : lib.entries)
    width = std::max(width, static_cast<int>(e.name.size()));
  std::printf("%-3s %-*s %-6s %5s %5s %5s %6s %-22s %7s %6s %8s %s\n", "#", width, "name", "family",
              "seed", "boxes", "nodes", "depth", "root bounds [s]", "trials", "sims", "wall",
              "made");
  for (std::size_t i = 0; i < lib.entries.size(); ++i) {
    const LibraryEntry& e = lib.entries[i];
    std::printf("%-3zu %-*s %-6s %5llu %5zu %5zu %6zu %-22s %7llu %6llu %7.0fs %s\n", i, width,
                e.name.c_str(), e.family.c_str(), static_cast<unsigned long long>(e.world_seed),
                e.world.boxes.size(), e.strategy.nodes.size(), e.strategy.depth(),
                fmt::format("[{:.1f}, {:.1f}]", e.lower, e.upper).c_str(),
                static_cast<unsigned long long>(e.provenance.trials),
                static_cast<unsigned long long>(e.provenance.simulations), e.provenance.wall_s,
                e.provenance.created.c_str());
  }
  bool chains = false;
  for (std::size_t i = 0; i < lib.entries.size(); ++i) {
    if (lib.entries[i].is_continuation() || plr::sim::continuations(lib, i).empty()) continue;
    if (!chains) std::printf("chains (parent -> continuation at the leaf [observations]):\n");
    chains = true;
    std::printf("  %s\n", lib.entries[i].name.c_str());
    print_chain(lib, i, 0);
  }
  if (!lib.action_model.empty()) std::printf("action model: %s\n", lib.action_model.c_str());
  if (!lib.made_by.empty()) std::printf("made by: %s\n", lib.made_by.c_str());
}

void show(const plr::sim::Library& lib, const LibraryEntry& e) {
  const plr::sim::Provenance& p = e.provenance;
  std::printf("name: %s\nfamily: %s\nworld_seed: %llu\n", e.name.c_str(), e.family.c_str(),
              static_cast<unsigned long long>(e.world_seed));
  if (e.is_continuation()) {
    std::printf("parent: %s\nleaf: [%s]\nstart:\n", e.parent.c_str(), path(e).c_str());
    for (const auto& s : e.start)
      std::printf("  - {particle: %u, state_hash: %016llx, boxes_left: %u}\n", s.particle,
                  static_cast<unsigned long long>(s.state_hash), s.boxes_left);
  }
  const auto index = static_cast<std::size_t>(&e - lib.entries.data());
  const auto next = plr::sim::continuations(lib, index);
  if (!next.empty()) {
    std::printf("continuations:\n");
    for (const std::size_t c : next)
      std::printf("  - {name: %s, leaf: [%s]}\n", lib.entries[c].name.c_str(),
                  path(lib.entries[c]).c_str());
  }
  std::printf("world: %zu boxes in a %.2f x %.2f x %.2f m trailer\n", e.world.boxes.size(),
              e.world.trailer.width, e.world.trailer.height, e.world.trailer.depth);
  std::printf("observation: %s\n", e.observation_json.c_str());
  std::printf("root_bounds: [%.3f, %.3f]  # value = -(robot s + terminal estimate)\n", e.lower,
              e.upper);
  std::printf("fidelity: %s\n", e.fidelity.c_str());
  if (e.check) {
    const plr::sim::FidelityCheck& c = *e.check;
    std::printf(
        "value_at_%s: {value: %.3f, boxes: %.2f, particles: %u}  # the tree on the search's "
        "particles\n",
        e.fidelity.c_str(), c.value, c.boxes, p.particles);
    std::printf(
        "value_at_full: {value: %.3f, boxes: %.2f, particles: %u, first_particle: %u}  # on "
        "fresh particles\n",
        c.full_value, c.full_boxes, c.full_particles, c.first_particle);
  }
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

int fail(const std::string& what) {
  std::fprintf(stderr, "plr library: %s\n", what.c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Lists and shows the entries of a strategy library, exports an entry's strategy "
      "and draws its pictures"};
  app.name("plr library");
  app.require_subcommand(1);
  std::string file, key, out;
  const auto library_file = [&file](CLI::App* cmd) {
    cmd->add_option("file", file, "Strategy library (.plrl)")->required();
  };
  const auto entry = [&key](CLI::App* cmd) {
    cmd->add_option("entry", key, "The entry: its name or its index")->required();
  };
  auto* list_cmd = app.add_subcommand("list", "A line per entry, then the chains of continuations");
  library_file(list_cmd);
  auto* show_cmd = app.add_subcommand(
      "show",
      "An entry's world, its parent and leaf (a continuation), its continuations, bounds, "
      "provenance and strategy");
  library_file(show_cmd);
  entry(show_cmd);
  auto* export_cmd = app.add_subcommand(
      "export", "Writes an entry's strategy as a strategy file for the executor");
  library_file(export_cmd);
  entry(export_cmd);
  export_cmd->add_option("out", out, "Strategy file: OUT.plrs or OUT.yaml")->required();
  auto* svg_cmd = app.add_subcommand("svg",
                                     "Draws every entry: DIR/<name>.svg (its strategy tree) and "
                                     "DIR/<name>-anytime.svg (its root bounds against time)");
  library_file(svg_cmd);
  svg_cmd->add_option("dir", out, "Folder of the pictures")->required();
  CLI11_PARSE(app, argc, argv);

  auto lib = plr::sim::load_library(file);
  if (!lib) return fail(lib.error().message);
  if (*list_cmd) {
    list(*lib);
    return 0;
  }
  if (*svg_cmd) {
    const std::filesystem::path dir(out);
    for (const LibraryEntry& e : lib->entries) {
      for (const auto& [path, text] :
           {std::pair{dir / (e.name + ".svg"), plr::generator::strategy_svg(e.strategy)},
            {dir / (e.name + "-anytime.svg"), plr::generator::anytime_svg(e)}}) {
        if (auto s = plr::write_file_atomically(path.string(), text); !s)
          return fail(s.error().message);
      }
    }
    return 0;
  }
  const LibraryEntry* e = find(*lib, key);
  if (!e) {
    return fail(fmt::format("{}: no entry '{}' ({} entries)", file, key, lib->entries.size()));
  }
  if (*show_cmd) {
    show(*lib, *e);
    return 0;
  }
  if (auto s = plr::sim::save_strategy(e->strategy, out); !s) return fail(s.error().message);
  return 0;
}
