// Fuzz target: what the DDS bridge reads from another kernel's envelope
// (kernel/transport/dds/envelope_check.cpp). Cyclone hands the bridge
// NUL-terminated strings and a sized payload; the input supplies them: a
// kind byte, three strings of up to 255 bytes (each after its length byte),
// and the rest as the payload.
#include "envelope_check.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::size_t at = 0;
  const auto take_string = [&] {
    if (at >= size) return std::string();
    const std::size_t n = std::min<std::size_t>(data[at], size - at - 1);
    std::string s(reinterpret_cast<const char*>(data + at + 1), n);
    at += n + 1;
    return s;
  };
  if (size == 0) return 0;
  const std::uint8_t kind = data[at++];
  std::string kernel = take_string(), target = take_string(), name = take_string();
  plr_dds_Envelope e{};
  e.kernel = kernel.data();
  e.target = target.data();
  e.name = name.data();
  e.kind = kind;
  e.payload._buffer = const_cast<std::uint8_t*>(data + at);
  e.payload._length = static_cast<std::uint32_t>(size - at);
  if (plr::kernel::envelope_problem(e) != nullptr) return 0;
  if (e.kind == static_cast<std::uint8_t>(plr::kernel::EnvelopeKind::kAnnounce))
    (void)plr::kernel::announce_services(e.payload._buffer, e.payload._length);
  if (e.kind == static_cast<std::uint8_t>(plr::kernel::EnvelopeKind::kCommand))
    (void)plr::kernel::remote_command(e.payload._buffer, e.payload._length);
  return 0;
}
