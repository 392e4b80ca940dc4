// However `plr run` ends — its job done, Ctrl-C, SIGTERM, `--duration`, a
// host lost for good — report.json says how, with an exit code of its own;
// and a host's crashes count only within its restart window.
#include "kernel_fixture.hpp"
#include "test_util.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <sys/wait.h>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <thread>

namespace plr::kernel {
namespace {

using testing::run_command;
namespace fs = std::filesystem;

const std::string kPlr = PLR_BINARY;

struct RunDir {
  fs::path dir;
  std::string config;
};

// A fresh folder with `config_text` as x.yaml; the report goes to dir/report.
RunDir prepare(const std::string& name, const std::string& config_text) {
  RunDir r{fs::path(::testing::TempDir()) / ("run_end_" + name), {}};
  fs::remove_all(r.dir);
  fs::create_directories(r.dir);
  r.config = (r.dir / "x.yaml").string();
  std::ofstream(r.config) << "pipeline: run_end_" << name << "\n" << config_text;
  return r;
}

nlohmann::json report_of(const RunDir& r) {
  std::ifstream in(r.dir / "report" / "report.json");
  if (!in) return {};
  return nlohmann::json::parse(in, nullptr, false);
}

std::string args(const RunDir& r) {
  return " run " + r.config + " --report " + (r.dir / "report").string();
}

const char* kEndless = R"(nodes:
  counter: {plugin: demo_counter, params: {period_ms: 5}}
  doubler: {plugin: demo_doubler, params: {factor: 2}}
)";

// Starts an endless run, waits until it is up, sends `sig`.
int run_and_signal(const RunDir& r, int sig) {
  const pid_t pid = shm::test::spawn(
      {kPlr, "run", r.config, "--report", (r.dir / "report").string()}, (r.dir / "log").string());
  std::string out;
  for (int i = 0; i < 200; ++i) {
    out.clear();
    if (run_command(kPlr + " status --pipeline " + r.dir.filename().string(), &out) == 0) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
  }
  ::kill(pid, sig);
  return shm::test::wait_child(pid);
}

TEST(RunEnd, JobDoneWritesReportAndExitsZero) {
  const RunDir r = prepare("done", R"(nodes:
  counter: {plugin: demo_counter, params: {period_ms: 1, limit: 3}}
  doubler: {plugin: demo_doubler, params: {factor: 2}}
)");
  std::string out;
  ASSERT_EQ(run_command(kPlr + args(r), &out), 0) << out;
  const auto report = report_of(r);
  ASSERT_TRUE(report.is_object()) << out;
  EXPECT_EQ(report["run"]["ended"], "finished");
  EXPECT_EQ(report["run"]["exit_code"], 0);
  EXPECT_EQ(report["run"]["reason"], "counted to 3");
}

TEST(RunEnd, CtrlCWritesReportAndExits130) {
  const RunDir r = prepare("sigint", kEndless);
  EXPECT_EQ(run_and_signal(r, SIGINT), 130);
  const auto report = report_of(r);
  ASSERT_TRUE(report.is_object());
  EXPECT_EQ(report["run"]["ended"], "interrupted");
  EXPECT_EQ(report["run"]["reason"], "signal 2 (INT)");
  EXPECT_EQ(report["run"]["exit_code"], 130);
}

TEST(RunEnd, SigtermWritesReportAndExits143) {
  const RunDir r = prepare("sigterm", kEndless);
  EXPECT_EQ(run_and_signal(r, SIGTERM), 143);
  EXPECT_EQ(report_of(r)["run"]["ended"], "terminated");
}

TEST(RunEnd, DurationWritesReportAndExitsWithTheTimeoutCode) {
  const RunDir r = prepare("duration", kEndless);
  std::string out;
  EXPECT_EQ(run_command(kPlr + args(r) + " --duration 0.3", &out), 3) << out;
  const auto report = report_of(r);
  ASSERT_TRUE(report.is_object()) << out;
  EXPECT_EQ(report["run"]["ended"], "duration");
  EXPECT_GE(report["run"]["wall_s"].get<double>(), 0.3);
}

TEST(RunEnd, AReportOfAnEarlierRunIsReplacedNotMerged) {
  const RunDir r = prepare("stale", kEndless);
  fs::create_directories(r.dir / "report");
  std::ofstream(r.dir / "report" / "report.json") << R"({"boxes_unloaded": 99})";
  fs::last_write_time(r.dir / "report" / "report.json",
                      fs::file_time_type::clock::now() - std::chrono::hours(1));
  std::string out;
  EXPECT_EQ(run_command(kPlr + args(r) + " --duration 0.1", &out), 3) << out;
  const auto report = report_of(r);
  EXPECT_FALSE(report.contains("boxes_unloaded")) << report.dump();
  EXPECT_EQ(report["run"]["ended"], "duration");
}

// The probe on host b kills its own process `crash_after_ms` after it starts.
std::string crashing_host(int crash_after_ms, int max_restarts, double window_s) {
  return "plugin_paths: [" PLR_TEST_PLUGIN_DIR "]\nhosts:\n  b: {max_restarts: " +
         std::to_string(max_restarts) + ", restart_window_s: " + std::to_string(window_s) +
         ", backoff_ms: 0}\n"
         "nodes:\n"
         "  probe: {plugin: test_probe, host: b, params: {crash_after_ms: " +
         std::to_string(crash_after_ms) +
         "}}\n"
         "  counter: {plugin: demo_counter, params: {period_ms: 5}}\n";
}

// Each crash comes at least 1 s after the previous one: never 3 within
// 1.5 s, so the host is restarted every time, however long the run.
TEST(RunEnd, CrashesSpreadOverARunAreEachRestarted) {
  const RunDir r = prepare("spread", crashing_host(1000, 2, 1.5));
  std::string out;
  EXPECT_EQ(run_command(kPlr + args(r) + " --duration 6", &out), 3) << out;
  const auto report = report_of(r);
  ASSERT_TRUE(report.is_object()) << out;
  EXPECT_EQ(report["run"]["ended"], "duration") << out;
  EXPECT_GE(report["run"]["host_restarts"].get<int>(), 3) << out;
}

TEST(RunEnd, TooManyCrashesWithinTheWindowEndTheRunWithAReport) {
  const RunDir r = prepare("lost", crashing_host(1000, 2, 60));
  std::string out;
  EXPECT_EQ(run_command(kPlr + args(r) + " --duration 60", &out), 4) << out;
  EXPECT_NE(out.find("host 'b' killed by signal 9 and is not restarted: 3 crashes within 60 s"),
            std::string::npos)
      << out;
  const auto report = report_of(r);
  ASSERT_TRUE(report.is_object()) << out;
  EXPECT_EQ(report["run"]["ended"], "host_lost");
  EXPECT_EQ(report["run"]["host_restarts"], 2);
  EXPECT_EQ(report["run"]["exit_code"], 4);
}

}  // namespace
}  // namespace plr::kernel
