#include "dds_tool.hpp"

namespace plr::kernel {

Status DdsTool::open(const DdsToolOptions& o) {
  DdsConfig c;
  c.enabled = true;
  c.domain = o.domain;
  c.interfaces = o.interfaces;
  c.security_dir = o.security_dir;
  auto p = open_participant(c);
  if (!p) return p.error();
  participant_ = *p;
  return {};
}

dds_entity_t DdsTool::reader(const char* topic, std::int32_t depth, bool transient) {
  dds_qos_t* q = control_qos(depth, transient);
  const auto e = reader(topic, q);
  dds_delete_qos(q);
  return e;
}

dds_entity_t DdsTool::reader(const char* topic, const dds_qos_t* qos) {
  const auto t = dds_create_topic(participant_, &plr_dds_Envelope_desc, topic, nullptr, nullptr);
  return t < 0 ? t : dds_create_reader(participant_, t, qos, nullptr);
}

dds_entity_t DdsTool::writer(const char* topic, std::int32_t depth, bool transient) {
  const auto t = dds_create_topic(participant_, &plr_dds_Envelope_desc, topic, nullptr, nullptr);
  if (t < 0) return t;
  dds_qos_t* q = control_qos(depth, transient);
  const auto e = dds_create_writer(participant_, t, q, nullptr);
  dds_delete_qos(q);
  return e;
}

bool names_kernel(const std::string& id, const std::string& wanted) {
  if (id == wanted) return true;
  const auto colon = id.rfind(':');
  const auto at = id.find('@');
  return (colon != std::string::npos && id.substr(0, colon) == wanted) ||
         (at != std::string::npos && id.substr(0, at) == wanted);
}

}  // namespace plr::kernel
