// Fuzz target: the simulation worker's frames (sim/actions/simulation_job.cpp),
// which arrive from worker processes and, as the sim/simulate service, from
// other machines. A frame that decodes is built again from what was read
// and must decode again.
#include <plr/actions/simulation_job.hpp>

#include <cstddef>
#include <cstdint>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto frame = plr::actions::decode_frame(data, size, "fuzz");
  if (!frame) return 0;
  flatbuffers::FlatBufferBuilder fbb;
  switch (frame->kind) {
    case plr::actions::Frame::Kind::kJob:
      plr::actions::build_job(fbb, frame->id, frame->request, frame->observation_json);
      break;
    case plr::actions::Frame::Kind::kResult:
      plr::actions::build_result(fbb, frame->id, frame->result);
      break;
    case plr::actions::Frame::Kind::kSetup:
      return 0;
  }
  if (!plr::actions::decode_frame(fbb.GetBufferPointer(), fbb.GetSize(), "again")) __builtin_trap();
  return 0;
}
