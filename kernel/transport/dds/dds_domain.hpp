// What every PLR participant on a DDS domain agrees on — the kernels' DDS
// bridges and the remote tools (`plr monitor`, `plr swap --remote`): how
// Cyclone is configured, the topics and envelope kinds, the limits on what an
// envelope may carry, and how kernels are named.
#pragma once

#include "pipeline_config.hpp"

#include <plr/expected.hpp>

#include <dds/dds.h>

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace plr::kernel {

enum class EnvelopeKind : std::uint8_t {
  kTopic = 0,
  kRequest = 1,
  kReply = 2,
  kError = 3,
  kAnnounce = 4,
  kTelemetry = 5,
  kCommand = 6,
  kResult = 7,
};

inline constexpr const char* kDdsAnnounceTopic = "plr/announce";
inline constexpr const char* kDdsTelemetryTopic = "plr/telemetry";
// Commands only operators may write (DDS Security permissions); kernels answer
// on the result topic, so a kernel identity needs no write access to commands.
inline constexpr const char* kDdsControlTopic = "plr/control";
inline constexpr const char* kDdsResultTopic = "plr/result";
inline constexpr const char* kDdsRequestTopic = "plr/request";
inline constexpr const char* kDdsReplyTopic = "plr/reply";
inline constexpr std::chrono::milliseconds kPeerTimeout{1500};
// Cyclone's participant lease: a silent peer's endpoints go soon after.
inline constexpr std::chrono::milliseconds kDdsLease{2000};
// Sizes an envelope may carry; larger ones are dropped and counted.
inline constexpr std::size_t kMaxNameSize = 256;
inline constexpr std::size_t kMaxJsonPayload = 4 << 20;

// DDS topic carrying bus topic `topic` ("plr/topic/<name>", characters DDS
// does not allow replaced by '_').
std::string dds_topic_name(const std::string& topic);
// Cyclone configuration for `dds`: its interfaces (multicast off and peer
// 127.0.0.1 when only loopback), extra unicast peers from PLR_DDS_PEERS
// (comma-separated), and DDS Security when `security_dir` is set.
Expected<std::string> cyclone_config_xml(const DdsConfig& dds);
// Creates the domain from that XML (once per process) and a participant on it.
Expected<dds_entity_t> open_participant(const DdsConfig& dds);
// QoS of PLR's own DDS topics (announce, telemetry, control, result,
// request, reply): reliable, keeping the last `depth` samples (0: all),
// transient-local for late joiners when `transient`; a participant never
// reads its own samples. dds_delete_qos() it after use.
dds_qos_t* control_qos(std::int32_t depth, bool transient);
// This machine's host name.
std::string hostname();
// "<pipeline>@<hostname>:<pid>"
std::string make_kernel_id(const std::string& pipeline);
bool matches_any(const std::vector<std::string>& patterns, const std::string& name);

}  // namespace plr::kernel
