// The strategy library L: strategies generated offline (the strategy
// generator plug-in), each with the world it was generated on (what the
// chooser computes its features from) and how it was made.
//
// A world written and read back is the same bit for bit (each box's rotation
// matrix is stored beside its quaternion), and a library read and written
// again gives the same bytes.
//
// File (extension .plrl): a 4-byte little-endian size N, N bytes of
// plr.msg.StrategyLibrary (sdk/schemas/library.fbs, identifier "PLRL"), a
// 4-byte CRC-32 of those N bytes. Written atomically; a file that is cut
// short, altered or malformed is refused with one line naming the file and
// where ("lib.plrl: truncated: 812 of 4104 bytes", "lib.plrl: bytes
// 4..4100: checksum mismatch (corrupt)", "lib.plrl: entries[1] 'A1-2':
// strategy: ...").
#pragma once

#include <plr/expected.hpp>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "plr/sim/strategy.hpp"
#include "plr/sim/world.hpp"

namespace plr::sim {

inline constexpr std::uint32_t kLibraryVersion = 1;
// Bounds on what a library file may hold.
inline constexpr std::size_t kMaxLibraryBytes = std::size_t{1} << 30;
inline constexpr std::size_t kMaxLibraryEntries = 100000;
// made_by and action_model are cut to this many bytes when read.
inline constexpr std::size_t kMaxMadeBy = 64 * 1024;

struct BoundPoint {
  double wall_s = 0.0;
  double lower = 0.0, upper = 0.0;
  std::uint64_t trials = 0;
};

struct Provenance {
  std::uint64_t seed = 0;
  std::uint32_t particles = 0;
  std::uint32_t horizon = 0;
  std::uint64_t trial_budget = 0;
  std::uint64_t trials = 0;
  std::uint64_t simulations = 0;
  std::uint64_t nodes = 0;
  double wall_s = 0.0;
  std::uint32_t workers = 0;
  double epsilon1 = 0.0, epsilon2 = 0.0;
  double seconds_per_box = 0.0;
  std::string created;
};

// A particle of the belief a continuation starts from: the generator's mass
// particle it is (sim::particle_seed(provenance.seed, particle)) and the
// hash of its state there (actions::state_hash of the TruckState bytes).
struct StartParticle {
  std::uint32_t particle = 0;
  std::uint64_t state_hash = 0;
  std::uint32_t boxes_left = 0;
  bool operator==(const StartParticle&) const = default;
};

// A strategy made below full fidelity, re-evaluated at full fidelity: the
// mean value of its tree (negated robot seconds, the terminal estimate at
// the horizon, as the search counts them) and the boxes it unloads, over
// the generator's particles at the level it was made at, and at full
// fidelity over `full_particles` fresh particles: the generator's mass
// particles numbered first_particle, first_particle + 1, ...
// (sim::particle_seed(provenance.seed, n)), never used by the search.
struct FidelityCheck {
  double value = 0.0;
  double boxes = 0.0;
  double full_value = 0.0;
  double full_boxes = 0.0;
  std::uint32_t full_particles = 0;
  std::uint32_t first_particle = 0;
  bool operator==(const FidelityCheck&) const = default;
};

// The names of the fidelity levels (plr/sim/fidelity.hpp, which this layer
// does not see).
inline constexpr const char* kFullFidelity = "full";

struct LibraryEntry {
  std::string name;
  std::string family;
  std::uint64_t world_seed = 0;
  World world;  // W at the strategy's start, without masses
  std::string observation_json;
  Strategy strategy;
  double lower = 0.0, upper = 0.0;  // the root's value bounds: negated robot seconds
  Provenance provenance;
  std::vector<BoundPoint> curve;
  // A continuation: it starts where `parent`'s tree ends after the
  // observations `leaf` (from the parent's root), on the belief `start`.
  // Empty for a strategy made for a fresh trailer.
  std::string parent;
  std::vector<Observation> leaf;
  std::vector<StartParticle> start;
  // The fidelity the strategy was made at ("full", "adaptive", "fast"); below
  // full, its values at that level and at full fidelity.
  std::string fidelity = kFullFidelity;
  std::optional<FidelityCheck> check;

  bool is_continuation() const { return !parent.empty(); }
};

struct Library {
  std::vector<LibraryEntry> entries;
  std::string made_by;       // the command and settings that made it
  std::string action_model;  // the action model's fingerprint when it was made
};

// The continuations of `library.entries[entry]` (indices, in file order).
std::vector<std::size_t> continuations(const Library& library, std::size_t entry);

std::vector<std::uint8_t> serialize(const Library& library);
plr::Expected<Library> deserialize_library(const std::uint8_t* data, std::size_t size,
                                           const std::string& origin);

plr::Status save_library(const Library& library, const std::filesystem::path& file);
plr::Expected<Library> load_library(const std::filesystem::path& file);

}  // namespace plr::sim
