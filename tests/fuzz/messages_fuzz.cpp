// Fuzz target: every FlatBuffers message type of sdk/schemas as untrusted
// bytes from another process or machine: the verifier the bus and the
// plug-ins run first, then the decoders that read what it passed.
#include <plr/actions/motion_messages.hpp>
#include <plr/message.hpp>
#include <plr/messages.hpp>
#include <plr/planning/plan_messages.hpp>
#include <plr/sim/observation.hpp>
#include <plr/sim/strategy.hpp>

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <vector>

namespace {

using namespace plr::msg;

template <class... T>
void verify_all(const std::uint8_t* data, std::size_t size) {
  (void)(plr::verify<T>(data, size) + ...);
}

template <class T, class F>
void decode(const std::uint8_t* data, std::size_t size, F f) {
  if (plr::verify<T>(data, size)) f(*flatbuffers::GetRoot<T>(data));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // Structs of doubles are read in place: the transports hand out 8-aligned buffers.
  std::vector<std::uint64_t> aligned((size + 7) / 8);
  if (size > 0) std::memcpy(aligned.data(), data, size);
  const auto* bytes = reinterpret_cast<const std::uint8_t*>(aligned.data());
  verify_all<JointState, Clock, PipelineDone, Count, DoubleRequest, DoubleReply, PlanRequest,
             PlanStats, PlanResponse, ResetRequest, ExecuteRequest, ExecuteOutcome, ObserveRequest,
             SnapshotRequest, SnapshotReply, Progress, StrategyEdge, StrategyNode, Strategy,
             NextStrategyRequest, NextStrategyReply, TopicStats, NodeStatus, KernelTelemetry, Stat,
             Statistics, TrajectoryPoint, Trajectory, WorldState>(bytes, size);
  decode<PipelineDone>(bytes, size, [](const PipelineDone& d) {
    if (d.reason() != nullptr) (void)d.reason()->str();
  });
  decode<PlanRequest>(bytes, size,
                      [](const PlanRequest& r) { (void)plr::planning::decode_plan_request(r); });
  decode<PlanResponse>(bytes, size,
                       [](const PlanResponse& r) { (void)plr::planning::decode_plan_response(r); });
  decode<ExecuteRequest>(
      bytes, size, [](const ExecuteRequest& r) { (void)plr::actions::decode_execute_request(r); });
  decode<ExecuteOutcome>(
      bytes, size, [](const ExecuteOutcome& o) { (void)plr::actions::decode_execute_outcome(o); });
  decode<Strategy>(bytes, size,
                   [](const Strategy& s) { (void)plr::sim::from_message(s, "fuzz message"); });
  decode<WorldState>(bytes, size,
                     [](const WorldState& w) { (void)plr::sim::world_from_message(w); });
  return 0;
}
