// Whatever ends a multi-host run — Ctrl-C of `plr run`, or kill -9 of the
// supervisor itself — no process and no shared-memory segment of the run is
// left afterwards (clean ends and kill -9 of a host: kernel_hosts_test).
#include "test_util.hpp"

#include <gtest/gtest.h>

#include <dirent.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <fstream>
#include <string>
#include <thread>

namespace plr::shm {
namespace {

using namespace std::chrono_literals;

const std::string kPlr = PLR_BINARY;

// Processes whose command line names this run id.
int processes_of(const std::string& run_id) {
  int n = 0;
  if (DIR* d = opendir("/proc")) {
    while (auto* e = readdir(d)) {
      if (e->d_name[0] < '0' || e->d_name[0] > '9') continue;
      std::ifstream f(std::string("/proc/") + e->d_name + "/cmdline");
      const std::string cmd((std::istreambuf_iterator<char>(f)), {});
      if (cmd.find(std::string("--run-id") + '\0' + run_id + '\0') != std::string::npos) ++n;
    }
    closedir(d);
  }
  return n;
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
  EXPECT_EQ(processes_of(run_id), 2) << "supervisor and host b";
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
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << status;
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

}  // namespace
}  // namespace plr::shm
