// The `plr` command line, run as a user would.
#include "kernel_fixture.hpp"
#include "test_util.hpp"

#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <thread>

namespace plr::kernel {
namespace {

using testing::run_command;
namespace fs = std::filesystem;

const std::string kPlr = PLR_BINARY;

// Until `plr status` of a pipeline started in the background answers (5 s
// at most); `out` is its last answer.
bool wait_until_running(const std::string& pipeline, std::string* out) {
  for (int i = 0; i < 100; ++i) {
    out->clear();
    if (run_command(kPlr + " status --pipeline " + pipeline, out) == 0) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return false;
}

const std::string kDemo = std::string(PLR_SOURCE_DIR) + "/configs/demo.yaml";

std::string temp_config(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path) << text;
  return path;
}

TEST(Cli, VersionNamesTheAbi) {
  std::string out;
  ASSERT_EQ(run_command(kPlr + " version", &out), 0);
  EXPECT_NE(out.find("plug-in ABI 1."), std::string::npos) << out;
}

TEST(Cli, ValidateAcceptsTheDemo) {
  std::string out;
  ASSERT_EQ(run_command(kPlr + " validate " + kDemo, &out), 0) << out;
  EXPECT_NE(out.find("ok (2 nodes"), std::string::npos) << out;
}

// The /dev/shm a run of the unloading pipeline takes, counted from what its
// plug-ins declare. Its 15 segments took 1.38 GiB with 1 MiB slots for
// everything and 16 client channels per service (1.19 GiB seen in a run);
// 16 since the executor reports its figures on pipeline/report.
TEST(Cli, ValidatePrintsTheRunsDevShmNeed) {
  const std::string config = std::string(PLR_SOURCE_DIR) + "/configs/unload_sim.yaml";
  std::string out;
  ASSERT_EQ(run_command(kPlr + " validate " + config, &out), 0) << out;
  const auto at = out.find("/dev/shm: ");
  ASSERT_NE(at, std::string::npos) << out;
  const auto open = out.find('(', at);
  ASSERT_NE(open, std::string::npos) << out;
  const auto bytes = std::stoull(out.substr(open + 1));
  EXPECT_GT(bytes, 0u) << out;
  EXPECT_LT(bytes, std::uint64_t{192} << 20) << out;
  EXPECT_NE(out.find("B) in 16 segments"), std::string::npos) << out;
  EXPECT_EQ(out.find("  sim "), std::string::npos) << "segments only with --verbose\n" << out;

  ASSERT_EQ(run_command(kPlr + " validate -v " + config, &out), 0) << out;
  for (const auto* line : {"sim      topic   world                       64 x    524288 B",
                           "sim      service sim/execute                 16 x   1048576 B",
                           "main     topic   executor/state              64 x    524288 B",
                           "main     topic   pipeline/report             64 x    524288 B"})
    EXPECT_NE(out.find(line), std::string::npos) << line << "\n" << out;

  ASSERT_EQ(run_command(kPlr + " validate " + kDemo, &out), 0) << out;
  EXPECT_NE(out.find("/dev/shm: none (one host"), std::string::npos) << out;
}

TEST(Cli, ValidateNamesTheUnknownPlugin) {
  const auto path = temp_config("bad_plugin.yaml", "nodes:\n  x:\n    plugin: nope\n");
  std::string out;
  EXPECT_EQ(run_command(kPlr + " validate " + path, &out), 2);
  EXPECT_NE(out.find(path + ":2:3: nodes.x.plugin:"), std::string::npos) << out;
  EXPECT_NE(out.find("nope.so"), std::string::npos) << out;
}

// Tests run in parallel and a pipeline name is one control socket: each run
// here gets its own name.
TEST(Cli, RunFinishesTheDemoAndExitsZero) {
  std::string out;
  ASSERT_EQ(run_command(kPlr + " run " + kDemo +
                            " --set pipeline=cli_run_demo --set nodes.counter.params.period_ms=1"
                            " --set nodes.counter.params.limit=5",
                        &out),
            0)
      << out;
  EXPECT_NE(out.find("4 doubled is 8"), std::string::npos) << out;
  EXPECT_NE(out.find("pipeline done: counted to 5"), std::string::npos) << out;
}

// A list option takes one value per use: the config after it is the config.
TEST(Cli, ASetBeforeTheConfigLeavesItToItsArgument) {
  std::string out;
  EXPECT_EQ(
      run_command(kPlr +
                      " run --set pipeline=cli_set_first --set nodes.counter.params.period_ms=1"
                      " --set nodes.counter.params.limit=2 " +
                      kDemo + " --report " + ::testing::TempDir() + "cli_set_first",
                  &out),
      0)
      << out;
  EXPECT_NE(out.find("pipeline done: counted to 2"), std::string::npos) << out;
}

TEST(Cli, RunRefusesABadOverride) {
  std::string out;
  EXPECT_EQ(
      run_command(kPlr + " run " + kDemo +
                      " --set pipeline=cli_bad_override --set nodes.counter.params.period_ms=fast",
                  &out),
      2);
  EXPECT_NE(out.find("param 'period_ms': expected a number"), std::string::npos) << out;
}

TEST(Cli, CtrlCStopsCleanlyAndSwapWorksOnTheRunningPipeline) {
  const auto path = temp_config("cli_swap.yaml",
                                "pipeline: cli_swap_test\n"
                                "nodes:\n"
                                "  counter: {plugin: demo_counter, params: {period_ms: 5}}\n"
                                "  doubler: {plugin: demo_doubler, params: {factor: 2}}\n");
  const std::string log = ::testing::TempDir() + "plr_test_cli_swap.log";
  std::remove(log.c_str());  // never read a previous run's log
  const pid_t pid = shm::test::spawn({kPlr, "run", path}, log);
  ASSERT_GE(pid, 0);
  std::string out;
  ASSERT_TRUE(wait_until_running("cli_swap_test", &out)) << out;
  EXPECT_NE(out.find("\"doubler\""), std::string::npos) << out;
  out.clear();
  EXPECT_EQ(run_command(kPlr + " swap doubler demo_doubler --pipeline cli_swap_test", &out), 0)
      << out;
  out.clear();
  EXPECT_EQ(run_command(kPlr + " swap doubler nope --pipeline cli_swap_test", &out), 2) << out;
  EXPECT_NE(out.find("swap of 'doubler' to 'nope' failed, 'demo_doubler' keeps running"),
            std::string::npos)
      << out;
  kill(pid, SIGINT);
  int status = 0;
  waitpid(pid, &status, 0);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 130) << "128 + SIGINT, as a shell reports it";
  std::ifstream in(log);
  const std::string text((std::istreambuf_iterator<char>(in)), {});
  EXPECT_NE(text.find("saw "), std::string::npos) << "doubler deactivated cleanly:\n" << text;
}

TEST(Cli, SighupReloadsTheConfigAndSwapsChangedPlugins) {
  const std::string head =
      "pipeline: cli_reload_test\nplugin_paths: [" PLR_TEST_PLUGIN_DIR "]\nnodes:\n";
  const std::string counter = "  counter: {plugin: demo_counter, params: {period_ms: 5}}\n";
  const auto path =
      temp_config("cli_reload.yaml",
                  head + "  doubler: {plugin: demo_doubler, params: {factor: 2}}\n" + counter);
  const pid_t pid = shm::test::spawn({kPlr, "run", path}, "");
  ASSERT_GE(pid, 0);
  std::string out;
  ASSERT_TRUE(wait_until_running("cli_reload_test", &out)) << out;
  temp_config("cli_reload.yaml",
              head + "  doubler: {plugin: test_probe, params: {factor: 2}}\n" + counter);
  kill(pid, SIGHUP);
  bool swapped = false;
  for (int i = 0; i < 100 && !swapped; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    out.clear();
    run_command(kPlr + " status --pipeline cli_reload_test", &out);
    swapped = out.find("\"plugin\": \"test_probe\"") != std::string::npos;
  }
  EXPECT_TRUE(swapped) << out;
  kill(pid, SIGINT);
  int status = 0;
  waitpid(pid, &status, 0);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 130);
}

// `validate` said 2 and `run` 1 for the same missing plug-in.
TEST(Cli, AMissingPluginHasTheSameExitCodeInEveryCommand) {
  const auto path = temp_config("cli_missing.yaml", "nodes:\n  x: {plugin: nope}\n");
  std::string out;
  EXPECT_EQ(run_command(kPlr + " validate " + path, &out), 2) << out;
  EXPECT_EQ(
      run_command(
          kPlr + " run " + path + " --report " + ::testing::TempDir() + "cli_missing_report", &out),
      2)
      << out;
}

// Errors quoted terminal escapes from names in requests as raw bytes.
TEST(Cli, ErrorsShowControlBytesEscaped) {
  std::string out;
  EXPECT_EQ(run_command(kPlr + " status --pipeline $(printf 'a\\033[2Jb')", &out), 2) << out;
  EXPECT_EQ(out.find('\033'), std::string::npos) << out;
  EXPECT_NE(out.find("'a\\x1b[2Jb' is not a name"), std::string::npos) << out;
}

// `pipeline: ../victims/victim` made `plr run` delete victims/victim.sock and
// bind its control socket in its place.
TEST(Cli, APipelineNameCannotReachOutOfTheControlFolder) {
  const fs::path xdg = fs::path(::testing::TempDir()) / "cli_traversal_xdg";
  fs::remove_all(xdg);
  fs::create_directories(xdg / "victims");
  fs::permissions(xdg, fs::perms::owner_all);
  std::ofstream(xdg / "victims" / "victim.sock") << "precious";
  const auto path =
      temp_config("cli_traversal.yaml",
                  "pipeline: ../victims/victim\nnodes:\n  counter: {plugin: demo_counter}\n");
  const std::string env = "XDG_RUNTIME_DIR=" + xdg.string() + " ";
  std::string out;
  EXPECT_EQ(run_command(env + kPlr + " validate " + path, &out), 2) << out;
  EXPECT_NE(out.find(path + ":1:11: pipeline: '../victims/victim' is not a name"),
            std::string::npos)
      << out;
  out.clear();
  EXPECT_EQ(run_command(env + kPlr + " run " + path + " --duration 0.2 --report " +
                            (xdg / "report").string(),
                        &out),
            2)
      << out;
  std::ifstream victim(xdg / "victims" / "victim.sock");
  const std::string text((std::istreambuf_iterator<char>(victim)), {});
  EXPECT_EQ(text, "precious");
  out.clear();
  EXPECT_EQ(run_command(env + kPlr + " status --pipeline ../victims/victim", &out), 2) << out;
}

// Without XDG_RUNTIME_DIR the control folder was /tmp/plr-<uid>: another
// user who made it first stopped every run of that user. Run as `nobody`
// with /tmp/plr-65534 taken by root.
TEST(Cli, AControlFolderTakenByAnotherUserDoesNotStopARun) {
  if (geteuid() != 0) GTEST_SKIP() << "needs root to run as another user";
  // A tree cloned into root's own home (0700) is out of nobody's reach.
  const pid_t probe = ::fork();
  if (probe == 0) {
    const bool reach = ::setgid(65534) == 0 && ::setuid(65534) == 0 &&
                       ::access(kPlr.c_str(), X_OK) == 0 && ::access(kDemo.c_str(), R_OK) == 0;
    ::_exit(reach ? 0 : 1);
  }
  if (shm::test::wait_child(probe) != 0)
    GTEST_SKIP() << "user nobody cannot reach " << kPlr
                 << " (a folder above it is closed to others)";
  const std::string taken = "/tmp/plr-65534";
  const bool made = ::mkdir(taken.c_str(), 0777) == 0;
  struct stat st {};
  ASSERT_EQ(::lstat(taken.c_str(), &st), 0);
  ASSERT_NE(st.st_uid, 65534u) << taken << " is nobody's own: cannot show the attack";
  const fs::path home = fs::path(::testing::TempDir()) / "cli_nobody_home";
  fs::remove_all(home);
  fs::create_directories(home);
  ASSERT_EQ(::chown(home.c_str(), 65534, 65534), 0);
  const std::string log = (home / "log").string();
  const pid_t pid = ::fork();
  if (pid == 0) {
    if (::setgid(65534) != 0 || ::setuid(65534) != 0) ::_exit(126);
    ::unsetenv("XDG_RUNTIME_DIR");
    ::setenv("HOME", home.c_str(), 1);
    std::freopen(log.c_str(), "w", stdout);
    std::freopen(log.c_str(), "a", stderr);
    ::execl(kPlr.c_str(), kPlr.c_str(), "run", kDemo.c_str(), "--set", "pipeline=cli_nobody",
            "--duration", "0.3", "--report", (home / "report").c_str(), nullptr);
    ::_exit(127);
  }
  const int code = shm::test::wait_child(pid);
  if (made) ::rmdir(taken.c_str());
  std::ifstream in(log);
  const std::string text((std::istreambuf_iterator<char>(in)), {});
  EXPECT_EQ(code, 3) << text;
  EXPECT_TRUE(fs::exists(home / "report" / "report.json")) << text;
  fs::remove_all(home);
}

TEST(Cli, PluginsListsTheDemoPluginsAsJson) {
  std::string out;
  ASSERT_EQ(run_command(kPlr + " plugins --json", &out), 0) << out;
  EXPECT_NE(out.find("\"name\": \"demo_counter\""), std::string::npos) << out;
  EXPECT_NE(out.find("\"kind\": \"other\""), std::string::npos) << out;
}

}  // namespace
}  // namespace plr::kernel
