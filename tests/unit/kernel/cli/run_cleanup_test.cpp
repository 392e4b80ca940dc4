// Whatever ends a multi-host run — Ctrl-C of `plr run`, or kill -9 of the
// supervisor itself — no process and no shared-memory segment of the run is
// left afterwards (clean ends and kill -9 of a host: kernel_hosts_test).
#include "test_util.hpp"

#include <gtest/gtest.h>

#include <dirent.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdlib>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

namespace plr::shm {
namespace {

using namespace std::chrono_literals;

const std::string kPlr = PLR_BINARY;

// Processes whose command line names this run id (and `host`, if given).
std::vector<pid_t> pids_of(const std::string& run_id, const std::string& host = "") {
  std::vector<pid_t> out;
  if (DIR* d = opendir("/proc")) {
    while (auto* e = readdir(d)) {
      if (e->d_name[0] < '0' || e->d_name[0] > '9') continue;
      std::ifstream f(std::string("/proc/") + e->d_name + "/cmdline");
      const std::string cmd((std::istreambuf_iterator<char>(f)), {});
      if (cmd.find(std::string("--run-id") + '\0' + run_id + '\0') != std::string::npos &&
          (host.empty() ||
           cmd.find(std::string("--host") + '\0' + host + '\0') != std::string::npos))
        out.push_back(std::atoi(e->d_name));
    }
    closedir(d);
  }
  return out;
}

int processes_of(const std::string& run_id) {
  return static_cast<int>(pids_of(run_id).size());
}

template <class F>
bool eventually(F done, std::chrono::milliseconds limit) {
  const auto end = std::chrono::steady_clock::now() + limit;
  while (!done()) {
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::sleep_for(10ms);
  }
  return true;
}

// Starts `plr run` (counter on main, doubler on host b) and waits until both
// hosts exchange messages over shared memory.
pid_t start_run(const std::string& run_id) {
  const std::string config = ::testing::TempDir() + run_id + ".yaml";
  std::ofstream(config) << "hosts:\n  b: {restart: never}\n"
                           "nodes:\n"
                           "  counter: {plugin: demo_counter, params: {period_ms: 2}}\n"
                           "  doubler: {plugin: demo_doubler, host: b, params: {factor: 2}}\n";
  const std::string log = ::testing::TempDir() + run_id + ".log";
  const pid_t pid = test::spawn({kPlr, "run", config, "--run-id", run_id}, log);
  // One segment per exported topic on each side: main/count and b/doubled.
  EXPECT_TRUE(eventually([&] { return test::run_segments(run_id).size() >= 2; }, 10s))
      << "the run never set up its segments";
  EXPECT_EQ(processes_of(run_id), 3) << "supervisor, its watchdog and host b";
  return pid;
}

TEST(RunCleanup, CtrlCOfAMultiHostRunLeavesNoProcessAndNoSegment) {
  const std::string run = test::unique_run_id();
  const pid_t pid = start_run(run);
  ASSERT_GT(pid, 0);
  std::this_thread::sleep_for(100ms);
  kill(pid, SIGINT);
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 130) << status;
  EXPECT_TRUE(eventually([&] { return processes_of(run) == 0; }, 5s));
  EXPECT_TRUE(test::run_segments(run).empty());
}

TEST(RunCleanup, KillDashNineOfTheSupervisorLeavesNoProcessAndNoSegment) {
  const std::string run = test::unique_run_id();
  const pid_t pid = start_run(run);
  ASSERT_GT(pid, 0);
  std::this_thread::sleep_for(100ms);
  kill(pid, SIGKILL);
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  // Host b learns of its parent's death, stops, and removes the whole run.
  EXPECT_TRUE(eventually([&] { return processes_of(run) == 0; }, 5s));
  EXPECT_TRUE(eventually([&] { return test::run_segments(run).empty(); }, 2s))
      << test::run_segments(run).size() << " segments left";
}

// Both killed at once: no process of the run is left to clean up but the
// supervisor's watchdog (12 segments, 1.19 GiB stayed in /dev/shm).
TEST(RunCleanup, KillDashNineOfTheSupervisorAndAHostTogetherLeavesNoSegment) {
  const std::string run = test::unique_run_id();
  const pid_t pid = start_run(run);
  ASSERT_GT(pid, 0);
  const auto host = pids_of(run, "b");
  ASSERT_EQ(host.size(), 1u);
  kill(host[0], SIGKILL);
  kill(pid, SIGKILL);
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  EXPECT_TRUE(eventually([&] { return test::run_segments(run).empty(); }, 5s))
      << test::run_segments(run).size() << " segments left";
  EXPECT_TRUE(eventually([&] { return processes_of(run) == 0; }, 5s));
}

// Docker's default /dev/shm is 64 MB; a run's segments need more. The host
// died of SIGBUS and `plr run` said only that it did not start its nodes.
TEST(RunCleanup, ATooSmallDevShmIsAClearErrorBeforeTheRun) {
  if (geteuid() != 0) GTEST_SKIP() << "needs root for a private /dev/shm";
  const std::string config = ::testing::TempDir() + "small_shm.yaml";
  std::ofstream(config) << "hosts:\n  b: {restart: never}\n"
                           "nodes:\n"
                           "  counter: {plugin: demo_counter, params: {period_ms: 2}}\n"
                           "  doubler: {plugin: demo_doubler, host: b, params: {factor: 2}}\n";
  // A mount namespace of its own, with a 4 MiB /dev/shm.
  const std::string log = ::testing::TempDir() + "small_shm.log";
  const pid_t pid =
      test::spawn({"/usr/bin/unshare", "-m", "sh", "-c",
                   "mount -t tmpfs -o size=4m tmpfs /dev/shm && exec " + kPlr + " run " + config +
                       " --duration 5 --report " + ::testing::TempDir() + "small_shm_report"},
                  log);
  const int code = test::wait_child(pid);
  std::ifstream in(log);
  const std::string text((std::istreambuf_iterator<char>(in)), {});
  EXPECT_EQ(code, 4) << text;
  EXPECT_NE(text.find("shm: cannot serve 'double': no room in /dev/shm"), std::string::npos)
      << text;
}

}  // namespace
}  // namespace plr::shm
