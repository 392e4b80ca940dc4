// Fuzz target: the job engine's messages (sim/jobs/messages.cpp), which
// arrive from job processes and result store files, each in a frame
// (plr/frame.hpp). The input is a whole frame; a message that decodes is
// encoded again from what was read and must decode again to the same.
#include <plr/frame.hpp>
#include <plr/jobs/messages.hpp>

#include <cstddef>
#include <cstdint>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  auto payload = plr::unframe(data, size, plr::jobs::kMaxBytes, "fuzz");
  if (!payload) return 0;
  auto m = plr::jobs::decode_message(payload->data, payload->size, "fuzz");
  if (!m) return 0;
  const bool request = m->type == plr::jobs::Message::Type::kRequest;
  const auto again = request ? plr::jobs::encode_request(m->id, m->job)
                             : plr::jobs::encode_reply(m->id, m->result);
  auto back = plr::jobs::decode_message(again.data(), again.size(), "again");
  if (!back || back->id != m->id) __builtin_trap();
  if (request && (back->job.key != m->job.key || back->job.input != m->job.input)) __builtin_trap();
  if (!request && (back->result.ok != m->result.ok || back->result.output != m->result.output))
    __builtin_trap();
  return 0;
}
