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

// `plr run CONFIG` in a mount namespace of its own whose /dev/shm holds
// `size` (tmpfs -o size=); its exit code, and what it printed into `text`.
int run_with_dev_shm(const std::string& name, const std::string& size, const std::string& yaml,
                     std::string* text) {
  const std::string config = ::testing::TempDir() + name + ".yaml";
  std::ofstream(config) << yaml;
  const std::string log = ::testing::TempDir() + name + ".log";
  const pid_t pid = test::spawn(
      {"/usr/bin/unshare", "-m", "sh", "-c",
       "mount -t tmpfs -o size=" + size + " tmpfs /dev/shm && exec " + kPlr + " run " + config +
           " --duration 5 --report " + ::testing::TempDir() + name + "_report"},
      log);
  const int code = test::wait_child(pid);
  std::ifstream in(log);
  text->assign(std::istreambuf_iterator<char>(in), {});
  return code;
}

// Docker's default /dev/shm is 64 MB; the run's segments took 1.2 GiB. The
// host died of SIGBUS and `plr run` said only that it did not start its
// nodes. Now the run counts its need first and no host starts.
TEST(RunCleanup, ARunIsRefusedBeforeAnyHostStartsWhenDevShmHasLessRoomThanItNeeds) {
  if (geteuid() != 0) GTEST_SKIP() << "needs root for a private /dev/shm";
  std::string text;
  const int code =
      run_with_dev_shm("short_shm", "4m",
                       "hosts:\n  b: {restart: never}\n"
                       "nodes:\n"
                       "  counter: {plugin: demo_counter, params: {period_ms: 2}}\n"
                       "  doubler: {plugin: demo_doubler, host: b, params: {factor: 2}}\n",
                       &text);
  EXPECT_EQ(code, 4) << text;
  // "plr: <file>: the run needs 8.33 MiB (8732672 B) of /dev/shm and 4.00 MiB (4194304 B) is
  // free: give /dev/shm more room ..."
  EXPECT_NE(text.find("short_shm.yaml: the run needs "), std::string::npos) << text;
  EXPECT_NE(text.find(" B) of /dev/shm and 4.00 MiB (4194304 B) is free"), std::string::npos)
      << text;
  EXPECT_EQ(text.find("host 'b' started"), std::string::npos) << "no host starts\n" << text;
  EXPECT_EQ(text.find("cannot serve"), std::string::npos) << text;
}

// What the need does not count (a plug-in that declares nothing, here the
// test probe with a 64 MiB topic) still fails at its segment, by name.
TEST(RunCleanup, ASegmentWithoutRoomIsStillAClearErrorOfItsHost) {
  if (geteuid() != 0) GTEST_SKIP() << "needs root for a private /dev/shm";
  std::string text;
  const int code = run_with_dev_shm("small_shm", "16m",
                                    "plugin_paths: [" PLR_TEST_PLUGIN_DIR ", " PLR_DEMO_PLUGIN_DIR
                                    "]\n"
                                    "hosts:\n  b: {restart: never}\n"
                                    "nodes:\n"
                                    "  counter: {plugin: demo_counter, params: {period_ms: 2}}\n"
                                    "  probe: {plugin: test_probe, host: b}\n"
                                    "topics:\n  lifecycle: {slot_size: 1048576}\n",
                                    &text);
  EXPECT_EQ(code, 4) << text;
  EXPECT_NE(text.find("shm: cannot export topic 'lifecycle': no room in /dev/shm"),
            std::string::npos)
      << text;
}

}  // namespace
}  // namespace plr::shm
