// Semantic observation of a world: what structure stands in front of the
// robot (a pile on the floor or a wall of stacked boxes), how high it is, and
// on which side its top box lies — one of the 18 plr::msg::Observation values.
//
// Boxes are split by stack height: a box whose column (the boxes overlapping
// its footprint, itself included) tops out below h_pile belongs to the pile,
// otherwise to a wall. The first wall is the wall boxes whose front face lies
// within wall_depth of the nearest wall face; the pile that counts is the one
// in front of it or level with it (centres before wall face + wall_depth).
// A box no wall box stands in front of, across the trailer, counts too,
// however deep. Sides follow the frame of world.hpp: y > 0 is left.
#pragma once

#include <plr/msg/world_generated.h>
#include <plr/expected.hpp>

#include <nlohmann/json.hpp>

#include <cstdint>
#include <optional>
#include <vector>

#include "plr/sim/strategy.hpp"
#include "plr/sim/world.hpp"

namespace plr::sim {

// The defaults split what strategy H meets on the four families (A1, A2,
// B1, B2; `steps` in an unloading report lists the raw heights): B's piles,
// up to 1.3 m, stay piles; piles then range 0.25-1.35 m and first walls
// 1.4-2.35 m, and each class below occurs on them.
struct ObservationParams {
  double h_pile = 1.35;         // m; columns lower than this are pile
  double wall_depth = 0.7;      // m; depth of the first wall from its nearest face
  double min_pile_depth = 0.3;  // m; a thinner pile in front of a wall is not "the" structure
  double pile_mid = 0.4;        // m; pile top at or above this is mid
  double pile_high = 0.8;       // m; ... high
  double wall_mid = 1.6;        // m; first-wall top at or above this is mid
  double wall_high = 2.2;       // m; ... high
  double side_band = 1.0 / 3;   // centre band as a fraction of the trailer width

  // Whether the values are consistent; the error names the parameter.
  plr::Status check() const;

  // From a node's `observation` param: a map of the fields above (absent
  // ones keep their defaults), checked. Every node that classifies scenes
  // reads it this way, and a pipeline config defines it once (an alias).
  static plr::Expected<ObservationParams> from_json(const nlohmann::json& values);
};

// World-frame axis-aligned bounds of a (possibly rotated) box.
struct Bounds {
  double x0 = 0, x1 = 0, y0 = 0, y1 = 0, z0 = 0, z1 = 0;
};
Bounds bounds(const Box& box);
// Whether two bounds come closer than `gap` on every axis (overlap: gap 0).
bool within(const Bounds& a, const Bounds& b, double gap);

struct SceneAnalysis {
  std::vector<std::uint32_t> pile;        // every pile box
  std::vector<std::uint32_t> wall;        // every wall box
  std::vector<std::uint32_t> front_pile;  // pile boxes in front of / level with the first wall
  std::vector<std::uint32_t> first_wall;  // the wall boxes of the first wall

  double pile_near_x = 0;  // front of the front pile (smallest x)
  double pile_far_x = 0;   // its far end
  double pile_depth = 0;   // d_pile = pile_far_x - pile_near_x (0 without a pile)
  double pile_height = 0;  // top of the front pile
  double wall_near_x = 0;  // front face of the first wall
  double wall_height = 0;  // h_W, top of the first wall (0 without a wall)

  // Height class and top-box side of each structure, whichever is in front
  // (meaningful only when that structure has boxes).
  Height pile_class = Height::kLow, wall_class = Height::kLow;
  Side pile_side = Side::kCenter, wall_side = Side::kCenter;
  std::uint32_t pile_top_box = 0, wall_top_box = 0;

  // The semantic observation; nullopt when the trailer is empty.
  std::optional<Observation> observation;
  std::uint32_t top_box = 0;  // the structure's top box (valid with an observation)
};

SceneAnalysis analyse(const World& world, const ObservationParams& params = {});
std::optional<Observation> classify(const World& world, const ObservationParams& params = {});

// The perceived world in a WorldState message (masses as given, usually 0).
World world_from_message(const plr::msg::WorldState& state);
// The world a strategy/next request carries; a request without one, or with
// bytes that are not a WorldState, is refused naming the service.
plr::Expected<World> world_from_request(const plr::msg::NextStrategyRequest& request);

}  // namespace plr::sim
