// What every participant of a PLR DDS domain agrees on: topic names, the
// patterns of what crosses, kernel ids, and the Cyclone configuration a
// `remote.dds` section becomes.
#include "dds_domain.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdlib>
#include <filesystem>

namespace plr::kernel {
namespace {

DdsConfig loopback() {
  DdsConfig c;
  c.enabled = true;
  return c;
}

bool has(const std::string& xml, const std::string& part) {
  return xml.find(part) != std::string::npos;
}

TEST(DdsDomain, BusTopicsGetDdsTopicNames) {
  EXPECT_EQ(dds_topic_name("robot/joint_state"), "plr/topic/robot/joint_state");
  EXPECT_EQ(dds_topic_name("a b.c"), "plr/topic/a_b_c");
}

TEST(DdsDomain, PatternsMatchWholeNamesWithStars) {
  const std::vector<std::string> patterns = {"telemetry/*", "cmd/swap"};
  EXPECT_TRUE(matches_any(patterns, "telemetry/rates"));
  EXPECT_TRUE(matches_any(patterns, "cmd/swap"));
  EXPECT_FALSE(matches_any(patterns, "cmd/swapped"));
  EXPECT_FALSE(matches_any(patterns, "sim/telemetry/x"));
  EXPECT_TRUE(matches_any({"*"}, "anything/at/all"));
  EXPECT_FALSE(matches_any({}, "x"));
}

TEST(DdsDomain, AKernelIdNamesPipelineHostAndProcess) {
  EXPECT_EQ(make_kernel_id("demo"), "demo@" + hostname() + ":" + std::to_string(::getpid()));
}

TEST(DdsDomain, LoopbackMeansNoMulticastAndOnePeer) {
  ::unsetenv("PLR_DDS_PEERS");
  const auto xml = cyclone_config_xml(loopback());
  ASSERT_TRUE(xml) << xml.error().message;
  EXPECT_TRUE(has(*xml, R"(<NetworkInterface name="lo" multicast="false"/>)")) << *xml;
  EXPECT_TRUE(has(*xml, "<AllowMulticast>false</AllowMulticast>"));
  EXPECT_TRUE(has(*xml, R"(<Peer Address="127.0.0.1"/>)"));
  EXPECT_TRUE(has(*xml, "<MaxMessageSize>65500B</MaxMessageSize>"));
  EXPECT_FALSE(has(*xml, "<Security>"));
}

TEST(DdsDomain, OtherInterfacesAndPeersAreAddedEscaped) {
  DdsConfig c = loopback();
  c.interfaces = {"eth0", "we<ird"};
  ::setenv("PLR_DDS_PEERS", "10.0.0.2,,10.0.0.3", 1);
  const auto xml = cyclone_config_xml(c);
  ::unsetenv("PLR_DDS_PEERS");
  ASSERT_TRUE(xml);
  EXPECT_TRUE(has(*xml, R"(<NetworkInterface name="eth0" multicast="default"/>)")) << *xml;
  EXPECT_TRUE(has(*xml, R"(<NetworkInterface name="we&lt;ird" multicast="default"/>)"));
  EXPECT_FALSE(has(*xml, "<AllowMulticast>false"));
  EXPECT_FALSE(has(*xml, R"(<Peer Address="127.0.0.1"/>)"));
  EXPECT_TRUE(has(*xml, R"(<Peer Address="10.0.0.2"/><Peer Address="10.0.0.3"/>)"));
}

TEST(DdsDomain, NoInterfaceIsRefusedNotLeftToCyclone) {
  DdsConfig c = loopback();
  c.interfaces.clear();
  const auto xml = cyclone_config_xml(c);
  ASSERT_FALSE(xml);
  EXPECT_EQ(xml.error().message,
            "remote.dds.interfaces: none named (Cyclone would choose one itself)");
}

TEST(DdsDomain, SecurityNeedsEveryFileAndSaysWhichIsMissing) {
  const auto dir = std::filesystem::temp_directory_path() /
                   ("plr_dds_domain_test_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  DdsConfig c = loopback();
  c.security_dir = dir.string();
  const auto xml = cyclone_config_xml(c);
  ASSERT_FALSE(xml);
  EXPECT_EQ(xml.error().message, "remote.dds.security_dir: '" + dir.string() +
                                     "' has no identity_ca.pem (scripts/make-dds-certs.sh makes "
                                     "them)");
  std::filesystem::remove_all(dir);
}

TEST(DdsDomain, AParticipantJoinsTheDomain) {
  DdsConfig c = loopback();
  c.domain = 225 + ::getpid() % 8;  // away from the other DDS tests' domains
  auto p = open_participant(c);
  ASSERT_TRUE(p) << p.error().message;
  EXPECT_GT(*p, 0);
  EXPECT_EQ(dds_delete(*p), DDS_RETCODE_OK);
}

}  // namespace
}  // namespace plr::kernel
