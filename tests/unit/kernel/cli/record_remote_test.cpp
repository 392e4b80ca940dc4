// `plr record --remote`, run as an operator would beside a running kernel:
// it finds the topics the kernel exports on DDS, and the file holds every
// message of the chosen ones published while it recorded, in order, with
// their schemas; topics not asked for stay out.
#include "bare_kernel.hpp"
#include "kernel_fixture.hpp"
#include "mcap_reader.hpp"
#include "test_util.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <csignal>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <thread>

namespace plr::kernel {
namespace {

const std::string kPlr = PLR_BINARY;

// Apart from the other DDS tests' domains (monitor_test uses 200..214).
int domain() {
  return 180 + ::getpid() % 10;
}

TEST(RecordRemote, HoldsEveryMessageOfTheChosenTopicsAKernelExportsWhileItRecords) {
  remote_test::BareKernel kernel(domain(), "recorded", true, "*");
  for (const char* name : {"count", "other"}) {
    TopicSettings t;
    t.name = name;
    t.policy = TopicPolicy::Reliable;
    t.depth = 1024;
    kernel.set_topic(t);
  }
  const Status joined = kernel.open();
  ASSERT_TRUE(joined) << joined.error().message;
  auto& node = kernel.add_node("counter");
  const auto count =
      kernel.bus().advertise(&node, "count", MessageTraits<msg::Count>::type_id(), 1);
  const auto other =
      kernel.bus().advertise(&node, "other", MessageTraits<msg::Count>::type_id(), 1);
  ASSERT_TRUE(count && other);

  const auto path = std::filesystem::temp_directory_path() /
                    ("record_remote_" + std::to_string(::getpid()) + ".mcap");
  const std::string log = path.string() + ".log";
  // Until Ctrl-C, as an operator records; what came before it is kept.
  const pid_t pid = shm::test::spawn({kPlr, "record", "--remote", "recorded", path.string(),
                                      "--topics", "count", "--domain", std::to_string(domain())},
                                     log);
  constexpr int kMessages = 600;
  for (int i = 0; i < kMessages; ++i) {
    for (const auto publisher : {*count, *other}) {
      flatbuffers::FlatBufferBuilder fbb;
      fbb.Finish(msg::CreateCount(fbb, i));
      ASSERT_TRUE(kernel.bus().publish(publisher, testing::make_msg<msg::Count>(fbb)));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  ::kill(pid, SIGINT);
  EXPECT_EQ(shm::test::wait_child(pid), 130);
  std::stringstream out;
  out << std::ifstream(log).rdbuf();
  EXPECT_NE(out.str().find("on 1 topics to " + path.string()), std::string::npos) << out.str();

  auto bytes = mcap::load(path.string());
  ASSERT_TRUE(bytes) << bytes.error().message;
  mcap::Contents contents;
  std::vector<std::int64_t> values;
  ASSERT_TRUE(mcap::read(
      *bytes, path.string(),
      [&](const mcap::MessageRecord& m) {
        EXPECT_EQ(m.channel->topic, "count");
        ASSERT_TRUE(verify<msg::Count>(reinterpret_cast<const std::uint8_t*>(m.data.data()),
                                       m.data.size()));
        // A record's bytes lie anywhere in the file: read from a copy.
        const std::string body(m.data);
        values.push_back(flatbuffers::GetRoot<msg::Count>(body.data())->value());
      },
      contents));
  ASSERT_EQ(contents.schemas.size(), 1u);
  EXPECT_EQ(contents.schemas.begin()->second.name, "plr.msg.Count");
  // It joined while the kernel published (discovery takes a moment) and
  // missed nothing after: consecutive values up to the last one published.
  ASSERT_GE(values.size(), 200u) << out.str();
  for (std::size_t k = 1; k < values.size(); ++k) ASSERT_EQ(values[k], values[k - 1] + 1) << k;
  EXPECT_EQ(values.back(), kMessages - 1);
  std::filesystem::remove(path);
  std::filesystem::remove(log);
}

TEST(RecordRemote, WithoutAFileOrWithTwoItSaysWhatItNeeds) {
  std::string out;
  EXPECT_EQ(testing::run_command(kPlr + " record --remote x a.mcap b.mcap 2>&1", &out), 2);
  EXPECT_NE(out.find("record --remote: give only the file to write"), std::string::npos) << out;
  out.clear();
  EXPECT_EQ(testing::run_command(kPlr + " record only.mcap 2>&1", &out), 2);
  EXPECT_NE(out.find("give the pipeline config and the file to write"), std::string::npos) << out;
}

}  // namespace
}  // namespace plr::kernel
