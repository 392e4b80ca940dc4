// What the DDS bridge accepts from another kernel, before it acts on it:
// every field of an envelope arrives from the network, so sizes and kinds
// are checked here, and the JSON payloads (announces, commands) are parsed
// here with their bounds. Pure functions, so that a fuzz target reaches
// them without a DDS domain (tests/fuzz/dds_envelope_fuzz.cpp).
#pragma once

#include "dds_domain.hpp"
#include "envelope.h"

#include <plr/expected.hpp>

#include <nlohmann/json.hpp>

#include <cstddef>
#include <cstdint>
#include <set>
#include <string>

namespace plr::kernel {

inline constexpr std::size_t kMaxKernelId = 128;

// Length of `s` up to `max` + 1 (max + 1: longer, or missing).
std::size_t bounded_len(const char* s, std::size_t max);

// Why an envelope is refused (field sizes, kind, payload), or nullptr.
const char* envelope_problem(const plr_dds_Envelope& e);

// The services a kernel's announce lists; names longer than kMaxNameSize
// are left out.
plr::Expected<std::set<std::string>> announce_services(const std::uint8_t* payload,
                                                       std::size_t size);

// A remote command: a JSON object with a string "cmd".
plr::Expected<nlohmann::json> remote_command(const std::uint8_t* payload, std::size_t size);

}  // namespace plr::kernel
