// One unit of offline work: an abstract action simulated on one state of
// the trailer (a particle of the strategy generator), and what came of it;
// as a job of the job engine (plr/jobs/, docs/jobs.md) of kind `sim.action`,
// whose input carries everything a worker on any machine needs: the state,
// the action and the observation parameters (sdk/schemas/generator.fbs:
// SimJob in, SimResult out).
// States are the bytes of a finished TruckState buffer
// (plr/actions/state_bytes.hpp), kept as they are and never rebuilt.
#pragma once

#include <plr/expected.hpp>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "plr/actions/rig.hpp"
#include "plr/jobs/kinds.hpp"
#include "plr/sim/fidelity.hpp"
#include "plr/sim/strategy.hpp"
#include "plr/sim/world.hpp"

namespace plr::actions {

using StateBytes = std::shared_ptr<const std::vector<std::uint8_t>>;

struct SimRequest {
  StateBytes state;
  sim::Action action = sim::Action::PickLowLeft;
};

// The observation of an empty trailer, beside the 18 of the strategies.
inline constexpr int kEmptyObservation = -1;

struct SimOutcome {
  bool applicable = true;
  std::uint32_t boxes = 0;
  double robot_time_s = 0.0;
  int observation = kEmptyObservation;  // 0..17, or the trailer is empty
  std::uint32_t boxes_left = 0;
  double highest_stack_m = 0.0;
  double wall_s = 0.0;
  StateBytes state;  // after the action (also when it was not applicable)
};

inline constexpr char kSimActionKind[] = "sim.action";
inline constexpr std::size_t kMaxObservationJson = 64 * 1024;

struct SimJob {
  SimRequest request;
  std::string observation_json = "{}";  // the fields of sim::ObservationParams
  // The level the worker simulates at: the state restored there runs at it.
  sim::Fidelity fidelity = sim::Fidelity::kFull;
};

// The job's input and output bytes; decoding takes untrusted bytes (verified,
// the states checked to be TruckState buffers, values in range). The error
// is one line, "<origin>: <cause>".
plr::jobs::Bytes encode_sim_job(const SimJob& job);
plr::Expected<SimJob> decode_sim_job(const plr::jobs::Bytes& bytes, const std::string& origin);
plr::jobs::Bytes encode_sim_outcome(const SimOutcome& outcome);
plr::Expected<SimOutcome> decode_sim_outcome(const plr::jobs::Bytes& bytes,
                                             const std::string& origin);

// The rig a job runs on: the shipped robot and lattice, scenes classified
// with the observation parameters `observation_json` holds.
plr::Expected<std::unique_ptr<Rig>> make_rig(const std::string& observation_json);
// Runs the request's action from its state on `rig`.
plr::Expected<SimOutcome> simulate(Rig& rig, const SimRequest& request);
// The starting state of a particle: `truth` (with the particle's masses)
// at rest, the robot at home, nothing learnt; and how it looks.
plr::Expected<SimOutcome> start_state(Rig& rig, const sim::World& truth);

// Registers the sim.action kind: its handler keeps one rig, made again when
// a job names other observation parameters, set to each job's fidelity.
void add_sim_action(plr::jobs::Kinds& kinds);

// Whether `bytes` hold a verifiable TruckState buffer.
bool is_truck_state(const std::uint8_t* data, std::size_t size);

// A 64-bit name of (state, action, fidelity): FNV-1a over the state's bytes,
// mixed with the action and, below full fidelity, the level (a full
// simulation's key is the one it had before fidelity levels). The
// generator's cache and result store are keyed by it.
std::uint64_t state_hash(const std::vector<std::uint8_t>& state);
std::uint64_t work_key(std::uint64_t state_hash, sim::Action action,
                       sim::Fidelity fidelity = sim::Fidelity::kFull);

}  // namespace plr::actions
