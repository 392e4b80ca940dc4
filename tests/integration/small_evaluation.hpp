// A tiny evaluation for the tests that run plr evaluate end to end: two
// environments of the small world (one a training world of a one-strategy
// library made here, one held out), `methods`, 2 seeds, a 60 s horizon.
#pragma once

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "plr/chooser/features.hpp"
#include "plr/chooser/model.hpp"
#include "plr/chooser/nearest.hpp"
#include "plr/sim/generators.hpp"
#include "plr/sim/hardcoded_strategy.hpp"
#include "plr/sim/library.hpp"
#include "plr/sim/world_io.hpp"

namespace plr::evaluation_test {

// Writes dir/library.plrl, dir/model.plrm and dir/evaluate.yaml; empty on
// success, else what failed.
inline std::string write_small_evaluation(const std::filesystem::path& dir,
                                          const std::string& methods) {
  // A library of one strategy for the small world: H's first action, then
  // a low sweep whatever is seen (a leaf per observation).
  auto world = plr::sim::load_world(SMALL_WORLD);
  if (!world) return world.error().message;
  plr::sim::LibraryEntry e;
  e.name = "S-1";
  e.family = "A1";
  e.world_seed = 1;
  e.world = plr::sim::without_masses(*world);
  e.observation_json = "{}";
  e.strategy.name = "S-1";
  const auto first = plr::sim::hardcoded_action(plr::sim::analyse(e.world), {});
  e.strategy.nodes.push_back({first, {}});
  for (std::uint32_t o = 0; o < plr::sim::kNumObservations; ++o) {
    e.strategy.nodes[0].children.push_back({static_cast<plr::sim::Observation>(o), o + 1});
    e.strategy.nodes.push_back({plr::sim::make_sweep(plr::sim::Height::kLow), {}});
  }
  e.provenance.seed = 1;
  e.provenance.particles = 2;
  e.provenance.horizon = 2;
  plr::sim::Library library;
  library.entries.push_back(e);
  if (!plr::sim::save_library(library, dir / "library.plrl")) return "cannot save the library";
  // M: trained on the full world (NN's) and on it without its top layer (H's).
  plr::sim::World lower = e.world;
  std::erase_if(lower.boxes, [](const plr::sim::Box& b) { return b.pose.translation().z() > 0.8; });
  plr::sim::World front = e.world;
  front.boxes.resize(front.boxes.size() / 2);
  const std::vector<plr::chooser::Features> samples = {
      plr::chooser::features(e.world), plr::chooser::features(lower), plr::chooser::features(front),
      plr::chooser::features(e.world)};
  auto model =
      plr::chooser::Model::train(samples, {1, -1, -1, 1}, plr::chooser::Scaling::fit(samples),
                                 plr::chooser::fingerprint(library), {2, {1}, {-3}});
  if (!model) return model.error().message;
  if (!model->save(dir / "model.plrm")) return "cannot save the model";
  std::ofstream(dir / "evaluate.yaml")
      << "format: plr-evaluation\n"
      << "library: " << (dir / "library.plrl").string() << "\n"
      << "model: " << (dir / "model.plrm").string() << "\n"
      << "environments:\n"
      << "  - {name: S, family: A1, training: true}\n"
      << "  - {name: T, family: A1, world: " << SMALL_WORLD << "}\n"
      << "methods: " << methods << "\n"
      << "seeds: 2\n"
      << "max_robot_time_s: 60\n"
      << "workers: 2\n";
  return {};
}

}  // namespace plr::evaluation_test
