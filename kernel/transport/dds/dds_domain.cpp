#include "dds_domain.hpp"

#include <fmt/format.h>
#include <plr/xml_escape.hpp>

#include <unistd.h>
#include <cctype>
#include <cstdlib>
#include <filesystem>

namespace plr::kernel {

namespace {

bool glob_match(const char* p, const char* s) {
  if (*p == '\0') return *s == '\0';
  if (*p == '*') return glob_match(p + 1, s) || (*s != '\0' && glob_match(p, s + 1));
  return *p == *s && glob_match(p + 1, s + 1);
}

}  // namespace

dds_qos_t* control_qos(std::int32_t depth, bool transient) {
  dds_qos_t* q = dds_create_qos();
  dds_qset_reliability(q, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  if (depth > 0)
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, depth);
  else
    dds_qset_history(q, DDS_HISTORY_KEEP_ALL, 0);
  dds_qset_durability(q, transient ? DDS_DURABILITY_TRANSIENT_LOCAL : DDS_DURABILITY_VOLATILE);
  dds_qset_ignorelocal(q, DDS_IGNORELOCAL_PARTICIPANT);
  return q;
}

std::string hostname() {
  char buf[256] = {};
  ::gethostname(buf, sizeof buf - 1);
  return buf;
}

std::string dds_topic_name(const std::string& topic) {
  std::string out = "plr/topic/";
  for (char c : topic)
    out += (std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '/') ? c : '_';
  return out;
}

bool matches_any(const std::vector<std::string>& patterns, const std::string& name) {
  for (const auto& p : patterns)
    if (glob_match(p.c_str(), name.c_str())) return true;
  return false;
}

std::string make_kernel_id(const std::string& pipeline) {
  return fmt::format("{}@{}:{}", pipeline, hostname(), ::getpid());
}

Expected<std::string> cyclone_config_xml(const DdsConfig& dds) {
  if (dds.interfaces.empty())
    return make_error(PLR_ERR_INVALID,
                      "remote.dds.interfaces: none named (Cyclone would choose one itself)");
  bool loopback_only = true;
  for (const auto& i : dds.interfaces) loopback_only = loopback_only && i == "lo";
  std::string xml =
      R"(<CycloneDDS xmlns="https://cdds.io/config"><Domain Id="any"><General><Interfaces>)";
  for (const auto& i : dds.interfaces)
    xml += fmt::format(R"(<NetworkInterface name="{}" multicast="{}"/>)", xml_escape(i),
                       i == "lo" ? "false" : "default");
  xml += "</Interfaces>";
  if (loopback_only) xml += "<AllowMulticast>false</AllowMulticast>";
  // Cyclone's default MaxMessageSize (14720 B) sends a 64 KiB sample as five
  // datagrams; in one datagram its round trip takes half as long.
  xml += "<MaxMessageSize>65500B</MaxMessageSize></General>";
  // A frozen kernel stays matched until its DDS lease ends, and reliable
  // writers keep its unacknowledged samples: by Cyclone's default of 10 s the
  // request and reply histories fill and every call on the domain stalls.
  // The lease ends shortly after the heartbeat has declared the kernel gone.
  xml += fmt::format(
      "<Discovery><ParticipantIndex>auto</ParticipantIndex>"
      "<MaxAutoParticipantIndex>60</MaxAutoParticipantIndex>"
      "<LeaseDuration>{} ms</LeaseDuration><SPDPInterval>{} ms</SPDPInterval><Peers>",
      kDdsLease.count(), kDdsLease.count() / 4);
  if (loopback_only) xml += R"(<Peer Address="127.0.0.1"/>)";
  if (const char* extra = std::getenv("PLR_DDS_PEERS")) {
    std::string list = extra;
    for (std::size_t start = 0; start <= list.size();) {
      auto end = list.find(',', start);
      if (end == std::string::npos) end = list.size();
      if (end > start)
        xml += fmt::format(R"(<Peer Address="{}"/>)", xml_escape(list.substr(start, end - start)));
      start = end + 1;
    }
  }
  xml += "</Peers></Discovery>";
  // The request and reply writers keep all samples until acknowledged, and a
  // writer blocks while more than WhcHigh of them is unacknowledged (30 kB at
  // first by default: each large call waited for the peer's ACK). A writer
  // asks for ACKs once half of WhcHigh is outstanding, by default at most
  // every 5 ms: back-to-back 64 KiB calls reached a 500 kB limit every 8th
  // call and waited 60 us for the ACK. Asking every 100 us at most, with 1 MB
  // between the first request and the limit, keeps the ACKs ahead.
  xml +=
      "<Internal><HeartbeatInterval min=\"100 us\">100 ms</HeartbeatInterval><Watermarks>"
      "<WhcHigh>2 MB</WhcHigh><WhcHighInit>2 MB</WhcHighInit></Watermarks></Internal>";
  if (!dds.security_dir.empty()) {
    namespace fs = std::filesystem;
    for (const char* f : {"identity_ca.pem", "identity.pem", "identity_key.pem",
                          "permissions_ca.pem", "governance.p7s", "permissions.p7s"})
      if (!fs::exists(fs::path(dds.security_dir) / f))
        return make_error(PLR_ERR_INVALID, fmt::format("remote.dds.security_dir: '{}' has no {} "
                                                       "(scripts/make-dds-certs.sh makes them)",
                                                       dds.security_dir, f));
    const std::string lib = PLR_DDS_SECURITY_LIBDIR;
    const auto file = [&](const char* f) {
      return xml_escape("file:" + (fs::path(dds.security_dir) / f).string());
    };
    xml += fmt::format(
        "<Security><Authentication>"
        R"(<Library path="{0}/libdds_security_auth.so" initFunction="init_authentication" finalizeFunction="finalize_authentication"/>)"
        "<IdentityCA>{1}</IdentityCA><IdentityCertificate>{2}</IdentityCertificate>"
        "<PrivateKey>{3}</PrivateKey></Authentication><AccessControl>"
        R"(<Library path="{0}/libdds_security_ac.so" initFunction="init_access_control" finalizeFunction="finalize_access_control"/>)"
        "<PermissionsCA>{4}</PermissionsCA><Governance>{5}</Governance>"
        "<Permissions>{6}</Permissions></AccessControl><Cryptographic>"
        R"(<Library path="{0}/libdds_security_crypto.so" initFunction="init_crypto" finalizeFunction="finalize_crypto"/>)"
        "</Cryptographic></Security>",
        lib, file("identity_ca.pem"), file("identity.pem"), file("identity_key.pem"),
        file("permissions_ca.pem"), file("governance.p7s"), file("permissions.p7s"));
  }
  // Cyclone's own trace, for debugging discovery or security: PLR_DDS_TRACE=security,discovery
  if (const char* trace = std::getenv("PLR_DDS_TRACE"))
    xml += fmt::format("<Tracing><Category>{}</Category><OutputFile>stderr</OutputFile></Tracing>",
                       xml_escape(trace));
  xml += "</Domain></CycloneDDS>";
  return xml;
}

Expected<dds_entity_t> open_participant(const DdsConfig& dds) {
  auto xml = cyclone_config_xml(dds);
  if (!xml) return xml.error();
  const auto domain = static_cast<dds_domainid_t>(dds.domain);
  // A second participant in this process (tests, tools) shares the domain.
  const dds_entity_t d = dds_create_domain(domain, xml->c_str());
  if (d < 0 && d != DDS_RETCODE_PRECONDITION_NOT_MET)
    return make_error(PLR_ERR_INVALID, fmt::format("dds: cannot create domain {}: {}", dds.domain,
                                                   dds_strretcode(d)));
  const dds_entity_t p = dds_create_participant(domain, nullptr, nullptr);
  if (p < 0)
    return make_error(
        PLR_ERR_UNAVAILABLE,
        fmt::format("dds: cannot join domain {}: {}{}", dds.domain, dds_strretcode(p),
                    dds.security_dir.empty() ? "" : " (check the DDS Security files)"));
  return p;
}

}  // namespace plr::kernel
