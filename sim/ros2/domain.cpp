#include "plr/ros2/domain.hpp"

#include <fmt/format.h>

namespace plr::ros2 {

plr::Expected<dds_entity_t> open_participant(std::uint32_t domain_id, bool loopback_only) {
  if (domain_id > 232)
    return plr::make_error(PLR_ERR_INVALID,
                           fmt::format("ROS 2 domain id {}: must be 0 to 232", domain_id));
  if (loopback_only) {
    const std::string xml =
        R"(<CycloneDDS xmlns="https://cdds.io/config"><Domain Id="any"><General><Interfaces>)"
        R"(<NetworkInterface name="lo" multicast="false"/></Interfaces>)"
        "<AllowMulticast>false</AllowMulticast></General><Discovery>"
        "<ParticipantIndex>auto</ParticipantIndex><MaxAutoParticipantIndex>60"
        R"(</MaxAutoParticipantIndex><Peers><Peer Address="127.0.0.1"/></Peers></Discovery>)"
        "</Domain></CycloneDDS>";
    // Another participant of this process may have created the domain already.
    const dds_entity_t d = dds_create_domain(domain_id, xml.c_str());
    if (d < 0 && d != DDS_RETCODE_PRECONDITION_NOT_MET)
      return plr::make_error(PLR_ERR_INVALID, fmt::format("ROS 2 domain {}: cannot create it: {}",
                                                          domain_id, dds_strretcode(d)));
  }
  const dds_entity_t p = dds_create_participant(domain_id, nullptr, nullptr);
  if (p < 0)
    return plr::make_error(PLR_ERR_UNAVAILABLE, fmt::format("ROS 2 domain {}: cannot join it: {}",
                                                            domain_id, dds_strretcode(p)));
  return p;
}

dds_qos_t* default_qos(std::int32_t depth) {
  dds_qos_t* q = dds_create_qos();
  dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_history(q, DDS_HISTORY_KEEP_LAST, depth);
  dds_qset_durability(q, DDS_DURABILITY_VOLATILE);
  return q;
}

dds_qos_t* status_qos() {
  dds_qos_t* q = dds_create_qos();
  dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_history(q, DDS_HISTORY_KEEP_LAST, 1);
  dds_qset_durability(q, DDS_DURABILITY_TRANSIENT_LOCAL);
  return q;
}

}  // namespace plr::ros2
