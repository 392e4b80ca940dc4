// Seeded environment families (the paper's A1, A2: stacked walls; B1, B2:
// unstructured piles; C: mixed scenes; D1-D3: ceiling-high carton walls). Every call seeds its own
// std::mt19937_64; the same (family, seed) always gives the same world on one machine.
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
//
// D: walls of one size of cartons stacked to just under the ceiling
// (make_carton_wall below): D1 light 0.5 m cartons, 2.65 m high in a 2.7 m
// trailer; D2 the same cartons heavy; D3 light, its two top layers set down
// loosely. The top boxes are as high as a trailer allows.
enum class EnvFamily { kA1, kA2, kB1, kB2, kC, kD1, kD2, kD3 };

std::string_view to_string(EnvFamily family);
// Every family, in order.
std::vector<EnvFamily> all_env_families();
// "A1, A2, B1, B2, C, D1, D2 or D3", for messages.
std::string env_family_names();
// "A1", "a1", ... ; nullopt for anything else.
std::optional<EnvFamily> parse_env_family(std::string_view name);

// Throws std::invalid_argument for a trailer smaller than 1 x 1 x 4 m, or one
// a D family's wall does not fit in.
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

// A wall of equal cartons from the front wall backwards, its columns as
// high as the trailer allows: layers = floor((height - headroom) / carton)
// of cartons carton x carton wide and (height - headroom) / layers high, so
// every column's top is `headroom` under the ceiling. Columns spread evenly
// across the width; a jitter of a few mm keeps the wall from being a grid.
// Loose layers (the top ones) are not in columns: each carton is shifted
// (up to a fifth of its size) and turned (up to 0.25 rad) off its place,
// and left out where it would overlap one already set down or tip over.
struct CartonWall {
  double carton = 0.5;                  // m, edge of the square footprint
  double headroom = 0.05;               // m, from the top of the wall to the ceiling
  int slabs = 3;                        // rows of columns, from the front wall backwards
  int columns = 0;                      // across the width, centred; 0: as many as fit
  int loose_layers = 0;                 // top layers set down loosely
  MassPrior mass{3.0, 0.35, 1.0, 6.0};  // light cartons
};

// The wall of a D family.
CartonWall carton_wall(EnvFamily family);

// Whether the wall fits the trailer (in its front half) and its values make
// sense; the error names the field.
plr::Status check(const CartonWall& wall, const Trailer& trailer);

// The wall (seeded as generate_world), or check's error.
plr::Expected<World> make_carton_wall(const CartonWall& wall, std::uint64_t seed,
                                      const Trailer& trailer = {});

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
