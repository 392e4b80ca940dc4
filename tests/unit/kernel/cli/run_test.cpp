// A run driven in process, step by step (kernel/cli/run.cpp): how it ends
// and what its report.json then says, with the test plug-ins as its nodes.
#include "run.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <thread>

namespace plr::kernel {
namespace {

namespace fs = std::filesystem;

// A fresh folder holding `nodes` as the config of pipeline `name`; the
// report goes to its report/ folder.
RunOptions options_for(const std::string& name, const std::string& nodes) {
  const fs::path dir = fs::path(::testing::TempDir()) / ("run_" + name);
  fs::remove_all(dir);
  fs::create_directories(dir);
  RunOptions o;
  o.config = (dir / "run.yaml").string();
  o.report_dir = (dir / "report").string();
  std::ofstream(o.config) << "pipeline: run_test_" << name
                          << "\nplugin_paths: [" PLR_TEST_PLUGIN_DIR "]\nnodes:\n"
                          << nodes;
  return o;
}

// Polls as `plr run` does, until something ends the run (10 s at most).
std::optional<RunEnd> wait_for_end(Run& run) {
  for (int i = 0; i < 2000; ++i) {
    if (auto end = run.poll()) return end;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return std::nullopt;
}

nlohmann::json read_report(const Run& run) {
  std::ifstream in(run.report_file());
  return in ? nlohmann::json::parse(in, nullptr, false) : nlohmann::json();
}

TEST(Run, AJobThatFinishesEndsTheRunWithItsFiguresInTheReport) {
  kernel::Run run(options_for("finishes", R"(  job:
    plugin: test_reporter
    params: {figures: {boxes_unloaded: 3, stop_reason: "trailer empty"}, done: ok}
)"));
  ASSERT_TRUE(run.prepare());
  ASSERT_TRUE(run.start());
  const auto end = wait_for_end(run);
  ASSERT_TRUE(end);
  EXPECT_EQ(end->ending, Ending::Finished);
  EXPECT_EQ(end->reason, "job ok");
  EXPECT_EQ(run.finish(*end), 0);

  const auto report = read_report(run);
  EXPECT_EQ(report["boxes_unloaded"], 3);
  EXPECT_EQ(report["stop_reason"], "trailer empty");
  EXPECT_EQ(report["run"]["ended"], "finished");
  EXPECT_EQ(report["run"]["reason"], "job ok");
  EXPECT_EQ(report["run"]["exit_code"], 0);
  EXPECT_EQ(report["run"]["pipeline"], "run_test_finishes");
  EXPECT_EQ(report["run"]["run_id"], run.run_id());
  EXPECT_EQ(report["run"]["topic_messages"]["pipeline/report"], 1);
  EXPECT_EQ(report["run"]["topic_messages"]["pipeline/done"], 1);
}

// The figures a node reports are in report.json while the run goes on, and
// those it reports while it stops replace them.
TEST(Run, AStopRequestInterruptsItAndTheReportSaysSo) {
  kernel::Run run(options_for("stopped", R"(  job:
    plugin: test_reporter
    params: {figures: {boxes_unloaded: 1, stop_reason: running},
             stopped_figures: {boxes_unloaded: 2, stop_reason: stopped}}
)"));
  ASSERT_TRUE(run.prepare());
  ASSERT_TRUE(run.start());
  EXPECT_FALSE(run.poll()) << "nothing ended it yet";
  nlohmann::json during;
  for (int i = 0; i < 2000 && !during.is_object(); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
    during = read_report(run);
  }
  EXPECT_EQ(during["boxes_unloaded"], 1) << during.dump();
  EXPECT_FALSE(during.contains("run")) << "the run has not ended";

  run.request_stop();
  const auto end = run.poll();
  ASSERT_TRUE(end);
  EXPECT_EQ(end->ending, Ending::Stopped);
  EXPECT_EQ(run.finish(*end), exit_code(PLR_ERR_CANCELLED));

  const auto report = read_report(run);
  EXPECT_EQ(report["boxes_unloaded"], 2);
  EXPECT_EQ(report["stop_reason"], "stopped");
  EXPECT_EQ(report["run"]["ended"], "stopped");
  EXPECT_EQ(report["run"]["reason"], "stop requested on the control socket");
  EXPECT_EQ(report["run"]["exit_code"], 5);
}

TEST(Run, AFailedJobFailsTheRun) {
  kernel::Run run(options_for("fails", R"(  job:
    plugin: test_reporter
    params: {figures: {boxes_unloaded: 0}, done: failed}
)"));
  ASSERT_TRUE(run.prepare());
  ASSERT_TRUE(run.start());
  const auto end = wait_for_end(run);
  ASSERT_TRUE(end);
  EXPECT_EQ(end->ending, Ending::Failed);
  EXPECT_EQ(run.finish(*end), 1);
  const auto report = read_report(run);
  EXPECT_EQ(report["boxes_unloaded"], 0);
  EXPECT_EQ(report["run"]["ended"], "failed");
  EXPECT_EQ(report["run"]["reason"], "job failed");
  EXPECT_EQ(report["run"]["exit_code"], 1);
}

TEST(Run, ANodeThatCannotStartLeavesANotStartedReport) {
  kernel::Run run(options_for("not_started", R"(  job:
    plugin: test_reporter
    params: {figures: {boxes_unloaded: 0}}
  probe:
    plugin: test_probe
    params: {fail_activate: true}
)"));
  ASSERT_TRUE(run.prepare());
  const auto started = run.start();
  ASSERT_FALSE(started);
  EXPECT_EQ(run.not_started(started.error()), exit_code(started.error().code));
  const auto report = read_report(run);
  EXPECT_EQ(report["run"]["ended"], "not_started");
  EXPECT_NE(report["run"]["reason"].get<std::string>().find("activation refused by test"),
            std::string::npos)
      << report.dump();
}

TEST(Run, ABadConfigIsRefusedWithoutAReport) {
  auto options = options_for("bad_config", "  job: {plugin: test_reporter}\n");
  options.overrides = {"no_value"};
  kernel::Run run(options);
  const auto prepared = run.prepare();
  ASSERT_FALSE(prepared);
  EXPECT_EQ(run.not_started(prepared.error()), 2);
  EXPECT_TRUE(run.report_file().empty());
  EXPECT_FALSE(fs::exists(fs::path(options.report_dir) / "report.json"));
}

TEST(Run, DurationEndsTheRun) {
  auto options = options_for("duration", "  job: {plugin: test_reporter}\n");
  options.duration_s = 0.01;
  kernel::Run run(options);
  ASSERT_TRUE(run.prepare());
  ASSERT_TRUE(run.start());
  const auto end = wait_for_end(run);
  ASSERT_TRUE(end);
  EXPECT_EQ(end->ending, Ending::Duration);
  EXPECT_EQ(run.finish(*end), exit_code(PLR_ERR_TIMEOUT));
  EXPECT_EQ(read_report(run)["run"]["ended"], "duration");
}

TEST(Run, ASignalEndsItAsAShellWouldSay) {
  const auto interrupted = ended_by_signal(SIGINT);
  EXPECT_EQ(interrupted.ending, Ending::Interrupted);
  EXPECT_EQ(interrupted.reason, "signal 2 (INT)");
  EXPECT_EQ(interrupted.exit_code, 130);
  const auto terminated = ended_by_signal(SIGTERM);
  EXPECT_EQ(terminated.ending, Ending::Terminated);
  EXPECT_EQ(terminated.exit_code, 143);
}

}  // namespace
}  // namespace plr::kernel
