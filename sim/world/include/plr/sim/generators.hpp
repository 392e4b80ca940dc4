// Seeded environment families (the paper's A1, A2: stacked walls; B1, B2:
// unstructured piles). Every call seeds its own std::mt19937_64; the same
// (family, seed) always gives the same world on one machine.
//
// Boxes fill the trailer from the front wall (x = depth) towards the rear;
// the rear part stays free for the robot. Walls come out resting (boxes touch
// without interpenetration). Piles come out as a drop configuration: boxes
// hover a few millimetres apart and still have to fall and settle — use
// plr::sim::make_environment (physics.hpp) for a settled pile.
#pragma once

#include <cstdint>
#include <optional>
#include <string_view>
#include <utility>
#include <vector>

#include "plr/expected.hpp"
#include "plr/sim/world.hpp"

namespace plr::sim {

// C: mixed scenes between the paper's families, as a robot meets them: a
// wall (A1's or A2's boxes) with boxes fallen in front of it, a partly
// unloaded (stair-stepped) front, or a loose layer of flat boxes before it;
// in a trailer or in a 40/45 ft ISO container (2.35 m wide, 2.39 or 2.69 m
// high: C chooses the width and height, the depth is the caller's).
enum class EnvFamily { kA1, kA2, kB1, kB2, kC };

std::string_view to_string(EnvFamily family);
// Every family, in order.
std::vector<EnvFamily> all_env_families();
// "A1, A2, B1, B2 or C", for messages.
std::string env_family_names();
// "A1", "a1", ... ; nullopt for anything else.
std::optional<EnvFamily> parse_env_family(std::string_view name);

World generate_world(EnvFamily family, std::uint64_t seed, const Trailer& trailer = {});

// Pairs of box ids whose volumes overlap by more than `tolerance` (m), and
// boxes that stick out of the trailer's floor, walls or ceiling by more than it
// (reported as pair (id, id)).
std::vector<std::pair<std::uint32_t, std::uint32_t>> find_interpenetrations(const World& world,
                                                                            double tolerance);

// Ids of upright (yaw-only) boxes that tip over: the resultant of a box's
// weight and of what rests on it (shared among several supports by the lever
// rule) falls outside its support, less a margin of 15% of its size. A box
// rests on the floor or on box tops up to 1.5 cm below its bottom face.
std::vector<std::uint32_t> toppling_boxes(const World& world);

// The perceived world W: same boxes without masses.
World without_masses(const World& world);

// The masses a family's generator draws: log(mass) is normal around
// log(median) with standard deviation `spread`, clipped to [min, max]. Walls
// and piles alike draw every box's mass independently of its size.
struct MassPrior {
  double median = 0.0;  // kg
  double spread = 0.0;
  double min = 0.0, max = 0.0;  // kg
};
MassPrior mass_prior(EnvFamily family);

// A particle of the belief over W^t: `visible` with every unknown mass (0)
// drawn from the family's prior; masses already known (> 0, e.g. measured by
// the suction cups) stay. A box's mass depends only on (seed, box id), so the
// same particle keeps its masses as boxes leave the world.
World sample_masses(const World& visible, EnvFamily family, std::uint64_t seed);

// The sample_masses seed of particle `particle` of a generator seeded with
// `seed` (a SplitMix64 step): the strategy generator's particles, and what
// the evaluation replays them from.
std::uint64_t particle_seed(std::uint64_t seed, int particle);

// Sets the masses of the boxes named by id. An unknown id or a mass that is
// not finite and > 0 is refused (naming it) and changes nothing.
plr::Status set_masses(World& world, const std::vector<std::pair<std::uint32_t, double>>& masses);

}  // namespace plr::sim
