// One unit of offline work: an abstract action simulated on one state of
// the trailer (a particle of the strategy generator), and what came of it;
// and the frames that carry both to a worker and back
// (sdk/schemas/generator.fbs) — over a pipe to a process on this machine, or
// as the `sim/simulate` service of a kernel on another.
// States are the bytes of a finished TruckState buffer
// (plr/actions/state_bytes.hpp), kept as they are and never rebuilt.
#pragma once

#include <plr/expected.hpp>

#include <flatbuffers/flatbuffers.h>

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "plr/sim/strategy.hpp"

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

// A stream of frames: a 4-byte little-endian size, then that many bytes of
// a WorkerFrame. Larger frames are refused.
inline constexpr std::size_t kMaxFrameBytes = std::size_t{1} << 28;
inline constexpr std::size_t kMaxObservationJson = 64 * 1024;

std::vector<std::uint8_t> frame_setup(const std::string& observation_json);
std::vector<std::uint8_t> frame_job(std::uint64_t id, const SimRequest& request);
std::vector<std::uint8_t> frame_result(std::uint64_t id, const plr::Expected<SimOutcome>& result);
// The same frames finished in `fbb`, without the size: the message of a
// service call. A job for a service carries its observation parameters
// (a service keeps no setup between calls).
void build_job(flatbuffers::FlatBufferBuilder& fbb, std::uint64_t id, const SimRequest& request,
               const std::string& observation_json = {});
void build_result(flatbuffers::FlatBufferBuilder& fbb, std::uint64_t id,
                  const plr::Expected<SimOutcome>& result);

struct Frame {
  enum class Kind { kSetup, kJob, kResult } kind = Kind::kSetup;
  std::uint64_t id = 0;
  // kSetup; kJob: empty unless the job names its own (a service's jobs do)
  std::string observation_json;
  SimRequest request;                               // kJob
  plr::Expected<SimOutcome> result = SimOutcome{};  // kResult
};

// The bytes of one frame without its size prefix; untrusted: verified, and
// the embedded states checked to be TruckState buffers. The error is one
// line, "<origin>: <cause>".
plr::Expected<Frame> decode_frame(const std::uint8_t* data, std::size_t size,
                                  const std::string& origin);

// Whether `bytes` hold a verifiable TruckState buffer.
bool is_truck_state(const std::uint8_t* data, std::size_t size);

// A 64-bit name of (state, action): FNV-1a over the state's bytes, mixed
// with the action. The generator's cache and journal are keyed by it.
std::uint64_t state_hash(const std::vector<std::uint8_t>& state);
std::uint64_t work_key(std::uint64_t state_hash, sim::Action action);

}  // namespace plr::actions
