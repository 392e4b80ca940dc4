// DDS Security (Cyclone's built-in plug-ins, material from
// scripts/make-dds-certs.sh): with remote control on, the operator identity
// pauses, resumes and swaps a node; a tool without credentials does not even
// find the kernel; the read-only monitor identity and a kernel identity (a
// stolen kernel key) may not publish commands. Locally, pause and resume go
// through the control socket.
#include "remote_fixture.hpp"

#include <gtest/gtest.h>

#include <string>

namespace {

using namespace plr::remote_test;

TEST(RemoteSecurity, CommandsAcceptedWithPermissionRefusedWithout) {
  const auto dir = ::testing::TempDir() + "plr_dds_security/";
  std::string out;
  ASSERT_EQ(sh("rm -rf " + dir + " && " + std::string(PLR_SOURCE_DIR) +
                   "/scripts/make-dds-certs.sh " + dir + "certs kernel",
               &out),
            0)
      << out;
  const int domain = 100 + (::getpid() + 25) % 100;
  const auto config = write_file(dir + "secure.yaml",
                                 "pipeline: secure\nnodes:\n  doubler: {plugin: demo_doubler}\n"
                                 "remote:\n  dds: {domain: " +
                                     std::to_string(domain) + ", allow_remote_control: true, " +
                                     "security_dir: " + dir + "certs/kernel}\n");
  Proc kernel("", {kPlr, "run", config, "--report", dir + "report"}, dir + "kernel.log");
  const auto remote = [&](const std::string& command, const std::string& identity,
                          std::string* text) {
    text->clear();
    return sh(kPlr + " " + command + " --remote secure --domain " + std::to_string(domain) +
                  (identity.empty() ? "" : " --security " + dir + "certs/" + identity),
              text);
  };

  // The first command waits for secure discovery; retried until the kernel is up.
  std::string paused;
  int rc = 1;
  for (int i = 0; i < 5 && rc != 0; ++i) rc = remote("pause doubler", "operator", &paused);
  EXPECT_EQ(rc, 0) << paused << slurp(kernel.log);
  EXPECT_NE(paused.find("node 'doubler' of kernel 'secure@"), std::string::npos) << paused;
  std::string again;
  EXPECT_EQ(remote("pause doubler", "operator", &again), 1);
  EXPECT_NE(again.find("pause: node 'doubler' is not running"), std::string::npos) << again;
  std::string resumed;
  EXPECT_EQ(remote("resume doubler", "operator", &resumed), 0) << resumed;
  EXPECT_NE(resumed.find("resumed"), std::string::npos) << resumed;

  // The same through the local control socket.
  std::string local;
  EXPECT_EQ(sh(kPlr + " pause doubler --pipeline secure", &local), 0) << local;
  EXPECT_EQ(sh(kPlr + " resume doubler --pipeline secure", &local), 0) << local;
  EXPECT_NE(local.find("node 'doubler' resumed"), std::string::npos) << local;

  std::string swapped;
  EXPECT_EQ(remote("swap doubler demo_doubler", "operator", &swapped), 0) << swapped;
  EXPECT_NE(swapped.find("now runs 'demo_doubler'"), std::string::npos) << swapped;

  std::string anonymous, monitor, stolen;
  EXPECT_EQ(remote("swap doubler demo_doubler", "", &anonymous), 1);
  EXPECT_NE(anonymous.find("no kernel 'secure'"), std::string::npos) << anonymous;
  EXPECT_EQ(remote("pause doubler", "monitor", &monitor), 1);
  EXPECT_NE(monitor.find("cannot create the control endpoints"), std::string::npos) << monitor;
  EXPECT_EQ(remote("pause doubler", "kernel", &stolen), 1);
  EXPECT_NE(stolen.find("cannot create the control endpoints"), std::string::npos) << stolen;

  const auto log = slurp(kernel.log);
  EXPECT_NE(log.find(R"(dds: remote command {"cmd":"pause")"), std::string::npos) << log;
  // Paused once remotely, once locally (the second remote pause was refused).
  std::size_t pauses = 0;
  for (auto at = log.find("node 'doubler' paused"); at != std::string::npos;
       at = log.find("node 'doubler' paused", at + 1))
    ++pauses;
  EXPECT_EQ(pauses, 2u) << log;
  EXPECT_NE(log.find("node 'doubler' resumed"), std::string::npos) << log;
  EXPECT_NE(log.find("node 'doubler' swapped to demo_doubler"), std::string::npos) << log;
}

}  // namespace
