#include "envelope_check.hpp"

#include <cstring>

namespace plr::kernel {

std::size_t bounded_len(const char* s, std::size_t max) {
  return s == nullptr ? max + 1 : ::strnlen(s, max + 1);
}

const char* envelope_problem(const plr_dds_Envelope& e) {
  const auto kernel = bounded_len(e.kernel, kMaxKernelId);
  if (kernel == 0 || kernel > kMaxKernelId) return "bad sender id";
  if (bounded_len(e.target, kMaxKernelId) > kMaxKernelId) return "bad target id";
  if (bounded_len(e.name, kMaxNameSize) > kMaxNameSize) return "name too long";
  if (e.kind > static_cast<std::uint8_t>(EnvelopeKind::kResult)) return "unknown kind";
  if (e.payload._length > 0 && e.payload._buffer == nullptr) return "missing payload";
  return nullptr;
}

plr::Expected<std::set<std::string>> announce_services(const std::uint8_t* payload,
                                                       std::size_t size) {
  if (size > kMaxJsonPayload) return plr::make_error(PLR_ERR_INVALID, "announce too large");
  const auto j = nlohmann::json::parse(payload, payload + size, nullptr, false);
  if (j.is_discarded() || !j.is_object() || !j.contains("services") || !j["services"].is_array())
    return plr::make_error(PLR_ERR_INVALID, "malformed announce");
  std::set<std::string> services;
  for (const auto& s : j["services"])
    if (s.is_string() && s.get_ref<const std::string&>().size() <= kMaxNameSize)
      services.insert(s.get<std::string>());
  return services;
}

plr::Expected<nlohmann::json> remote_command(const std::uint8_t* payload, std::size_t size) {
  if (size > kMaxJsonPayload) return plr::make_error(PLR_ERR_INVALID, "command too large");
  auto cmd = nlohmann::json::parse(payload, payload + size, nullptr, false);
  if (cmd.is_discarded() || !cmd.is_object() || !cmd.contains("cmd") || !cmd["cmd"].is_string())
    return plr::make_error(PLR_ERR_INVALID, "malformed command");
  return cmd;
}

}  // namespace plr::kernel
