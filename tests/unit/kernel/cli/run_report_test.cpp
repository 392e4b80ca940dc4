// report.json as the run's report writes it (kernel/cli/run_report.cpp):
// the nodes' latest figures merged, the kernel's `run` once it ended, the
// file rewritten at every change.
#include "run_report.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

namespace plr::kernel {
namespace {

namespace fs = std::filesystem;

class RunReportTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) /
           ("run_report_" +
            std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()));
    fs::remove_all(dir_);
  }
  nlohmann::json on_disk() const {
    std::ifstream in(dir_ / "report.json");
    return in ? nlohmann::json::parse(in, nullptr, false) : nlohmann::json();
  }
  fs::path dir_;
};

TEST_F(RunReportTest, EachNodesLatestFiguresAreWrittenAtOnce) {
  RunReport report(dir_, "p", "r1");
  EXPECT_FALSE(fs::exists(report.file()));
  ASSERT_TRUE(report.add_figures("executor", R"({"boxes_unloaded": 1, "curve": [[1.5, 1]]})"));
  EXPECT_EQ(on_disk(), nlohmann::json::parse(R"({"boxes_unloaded": 1, "curve": [[1.5, 1]]})"));
  ASSERT_TRUE(report.add_figures("counter", R"({"counted": 7})"));
  ASSERT_TRUE(report.add_figures("executor", R"({"boxes_unloaded": 2})"));
  EXPECT_EQ(on_disk(), nlohmann::json::parse(R"({"boxes_unloaded": 2, "counted": 7})"));
  EXPECT_EQ(report.json(), on_disk());
}

TEST_F(RunReportTest, TheEndAddsRunAndANodeCannotWriteIt) {
  RunReport report(dir_, "pipe", "r2");
  ASSERT_TRUE(report.add_figures("n", R"({"run": "mine", "x": 1})"));
  EXPECT_FALSE(on_disk().contains("run")) << "the run has not ended";
  report.end({Ending::Stopped, "stop requested", 5}, 1.5, 2, {{.name = "t", .messages = 4}});
  const auto j = on_disk();
  EXPECT_EQ(j["x"], 1);
  EXPECT_EQ(j["run"]["pipeline"], "pipe");
  EXPECT_EQ(j["run"]["run_id"], "r2");
  EXPECT_EQ(j["run"]["ended"], "stopped");
  EXPECT_EQ(j["run"]["reason"], "stop requested");
  EXPECT_EQ(j["run"]["exit_code"], 5);
  EXPECT_EQ(j["run"]["wall_s"], 1.5);
  EXPECT_EQ(j["run"]["host_restarts"], 2);
  EXPECT_EQ(j["run"]["topic_messages"]["t"], 4);
}

TEST_F(RunReportTest, FiguresThatAreNotAJsonObjectAreRefused) {
  RunReport report(dir_, "p", "r3");
  ASSERT_TRUE(report.add_figures("n", R"({"x": 1})"));
  for (const char* bad : {"[1, 2]", "{\"x\": ", "", "3"}) {
    const auto added = report.add_figures("n", bad);
    ASSERT_FALSE(added) << bad;
    EXPECT_NE(added.error().message.find("node 'n'"), std::string::npos);
  }
  EXPECT_EQ(on_disk(), nlohmann::json::parse(R"({"x": 1})"));
}

TEST_F(RunReportTest, AnEarlierRunsReportIsReplacedNotMerged) {
  fs::create_directories(dir_);
  std::ofstream(dir_ / "report.json") << R"({"boxes_unloaded": 99, "run": {"ended": "finished"}})";
  RunReport report(dir_, "p", "r4");
  report.end({Ending::NotStarted, "no", 2}, 0, 0);
  const auto j = on_disk();
  EXPECT_FALSE(j.contains("boxes_unloaded")) << j.dump();
  EXPECT_EQ(j["run"]["ended"], "not_started");
}

}  // namespace
}  // namespace plr::kernel
