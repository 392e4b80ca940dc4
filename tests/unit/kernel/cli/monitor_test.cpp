// `plr monitor`, run as an operator would, against a kernel on a DDS domain:
// it finds the kernel from its announcements and shows its telemetry, as a
// table or as JSON; on an empty domain it says so and still exits 0.
#include "bare_kernel.hpp"
#include "kernel_fixture.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

namespace plr::kernel {
namespace {

const std::string kPlr = PLR_BINARY;

// Domains of this process's own, away from the other DDS tests' (100..199,
// and 225..232 for dds_domain_test).
int domain() {
  return 200 + ::getpid() % 15;
}

TEST(Monitor, FindsAKernelAndShowsItsTelemetry) {
  remote_test::BareKernel kernel(domain(), "monitored", true, "echo");
  const Status joined = kernel.open();
  ASSERT_TRUE(joined) << joined.error().message;
  const std::string id = kernel.bridge_stats()["kernel"];
  std::string out;
  ASSERT_EQ(testing::run_command(kPlr + " monitor --once --json --wait 10 --domain " +
                                     std::to_string(domain()) + " 2>/dev/null",
                                 &out),
            0)
      << out;
  const auto doc = nlohmann::json::parse(out, nullptr, false);
  ASSERT_TRUE(doc.is_object()) << out;
  EXPECT_EQ(doc["domain"], domain());
  EXPECT_EQ(doc["invalid"], 0);
  ASSERT_EQ(doc["kernels"].size(), 1u) << out;
  const auto& k = doc["kernels"][0];
  EXPECT_EQ(k["kernel"], id);
  EXPECT_EQ(k["pid"], ::getpid());
  EXPECT_EQ(k["hostname"], hostname());

  out.clear();
  ASSERT_EQ(testing::run_command(kPlr + " monitor --once --wait 10 --domain " +
                                     std::to_string(domain()) + " 2>/dev/null",
                                 &out),
            0);
  EXPECT_NE(out.find("1 kernel(s)"), std::string::npos) << out;
  EXPECT_NE(out.find(id), std::string::npos) << out;
}

TEST(Monitor, AnEmptyDomainIsSaidSo) {
  const int empty = 215 + ::getpid() % 8;
  std::string out;
  ASSERT_EQ(testing::run_command(
                kPlr + " monitor --once --json --wait 2 --domain " + std::to_string(empty), &out),
            0);
  EXPECT_NE(out.find("plr: no kernel found on domain " + std::to_string(empty)), std::string::npos)
      << out;
}

}  // namespace
}  // namespace plr::kernel
