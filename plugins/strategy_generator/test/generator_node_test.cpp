// `plr run` of a generation, killed with SIGKILL mid-run and run again:
// the library it ends with is the one an undisturbed run writes.
#include <gtest/gtest.h>

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "plr/sim/library.hpp"
#include "plr/sim/testing/library_fingerprint.hpp"

extern char** environ;

namespace {

namespace fs = std::filesystem;

class TempDir {
 public:
  TempDir() {
    std::string pattern = (fs::temp_directory_path() / "plr_generate_XXXXXX").string();
    path_ = mkdtemp(pattern.data());
  }
  ~TempDir() { fs::remove_all(path_); }
  fs::path operator/(const std::string& name) const { return path_ / name; }

 private:
  fs::path path_;
};

// `plr run` of `config` with `env` added to the environment, its output in
// `log` when one is given.
pid_t start(const fs::path& config, const fs::path& report,
            const std::vector<std::string>& env = {}, const fs::path& log = {}) {
  const std::string cfg = config.string(), rep = report.string(), out = log.string();
  char* argv[] = {const_cast<char*>(PLR_BIN),     const_cast<char*>("run"),
                  const_cast<char*>(cfg.c_str()), const_cast<char*>("--report"),
                  const_cast<char*>(rep.c_str()), nullptr};
  std::vector<char*> envp;
  for (char** e = environ; *e != nullptr; ++e) envp.push_back(*e);
  for (const std::string& e : env) envp.push_back(const_cast<char*>(e.c_str()));
  envp.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (!out.empty()) {
    posix_spawn_file_actions_addopen(&actions, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
  }
  pid_t pid = -1;
  EXPECT_EQ(::posix_spawn(&pid, PLR_BIN, &actions, nullptr, argv, envp.data()), 0);
  posix_spawn_file_actions_destroy(&actions);
  return pid;
}

int wait_exit(pid_t pid) {
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
}

std::string output(const std::string& command) {
  std::string out;
  if (std::FILE* p = ::popen(command.c_str(), "r")) {
    char buf[4096];
    while (const std::size_t n = std::fread(buf, 1, sizeof buf, p)) out.append(buf, n);
    ::pclose(p);
  }
  return out;
}

// A generator config for the block world, `extra` added to its params.
struct Sizes {
  int particles, horizon, trials, workers;
};
void write_config(const fs::path& file, Sizes n, const std::string& extra = "") {
  std::ofstream cfg(file);
  // Named after this process: a pipeline's name is its control socket's, and
  // tests run in parallel.
  cfg << "pipeline: generate_test_" << ::getpid()
      << "\n"
         "nodes:\n"
         "  generator:\n"
         "    plugin: strategy_generator\n"
         "    params:\n"
         "      library: ${report_dir}/library.plrl\n"
         "      checkpoint_dir: ${report_dir}/checkpoint\n"
         "      worlds: [{family: A1, world_file: " BLOCK_WORLD "}]\n"
      << "      particles: " << n.particles << "\n      horizon: " << n.horizon
      << "\n      trials: " << n.trials << "\n      workers: " << n.workers
      << "\n"
         "      progress: false\n"
         "      observation: {h_pile: 0.55, pile_mid: 0.25, pile_high: 0.4, wall_mid: 1.2, "
         "wall_high: 1.9}\n"
      << extra;
}

TEST(GeneratorNode, KilledWithSigkillAndRunAgainGivesTheSameLibrary) {
  TempDir dir;
  write_config(dir / "generate.yaml", {3, 3, 6, 2});
  ASSERT_EQ(wait_exit(start(dir / "generate.yaml", dir / "whole")), 0);
  const std::string whole = plr::sim::testing::library_fingerprint(dir / "whole/library.plrl");
  ASSERT_EQ(whole.rfind("block\n", 0), 0u) << whole;
  const auto made = plr::sim::load_library(dir / "whole/library.plrl");
  ASSERT_TRUE(made) << made.error().message;
  const std::size_t simulations = made->entries.front().provenance.simulations;

  // Killed with 10 results stored, mid-strategy: the job engine stops there
  // and says so on a pipe (PLR_JOBS_TEST_PAUSE) until the kill.
  constexpr std::size_t kStoredAtKill = 10;
  ASSERT_GT(simulations, kStoredAtKill);
  int paused[2];
  ASSERT_EQ(::pipe(paused), 0);
  ::fcntl(paused[0], F_SETFD, FD_CLOEXEC);
  const pid_t pid = start(dir / "generate.yaml", dir / "killed",
                          {fmt::format("PLR_JOBS_TEST_PAUSE={}:{}", kStoredAtKill, paused[1])});
  ::close(paused[1]);
  std::string said;
  char buf[64];
  for (ssize_t n;
       said.find('\n') == std::string::npos && (n = ::read(paused[0], buf, sizeof buf)) > 0;)
    said.append(buf, static_cast<std::size_t>(n));
  ::close(paused[0]);
  ASSERT_EQ(::kill(pid, SIGKILL), 0);
  EXPECT_EQ(wait_exit(pid), -SIGKILL);
  ASSERT_EQ(said, "paused\n");
  std::size_t stored = 0;
  for (const auto& f : fs::directory_iterator(dir / "killed/checkpoint/block/results")) {
    EXPECT_EQ(f.path().extension(), ".result") << f.path();
    ++stored;
  }
  EXPECT_EQ(stored, kStoredAtKill);
  EXPECT_FALSE(fs::exists(dir / "killed/library.plrl"));
  ASSERT_EQ(wait_exit(start(dir / "generate.yaml", dir / "killed", {}, dir / "resumed.log")), 0);
  EXPECT_EQ(plr::sim::testing::library_fingerprint(dir / "killed/library.plrl"), whole);
  // The stored results were read, not simulated again.
  std::ifstream log(dir / "resumed.log");
  const std::string resumed((std::istreambuf_iterator<char>(log)), {});
  EXPECT_NE(resumed.find(fmt::format("{} simulations ({} run now)", simulations,
                                     simulations - kStoredAtKill)),
            std::string::npos)
      << resumed;
  EXPECT_TRUE(fs::exists(dir / "killed/block.svg"));
  EXPECT_TRUE(fs::exists(dir / "killed/block-anytime.svg"));

  // `plr library` (the kernel runs plr-library) lists and shows the entry,
  // and refuses a truncated file with its located error.
  const std::string lib = (dir / "whole/library.plrl").string();
  const std::string list = output(std::string(PLR_BIN) + " library list " + lib);
  EXPECT_NE(list.find("block"), std::string::npos) << list;
  EXPECT_NE(list.find("root bounds"), std::string::npos) << list;
  const std::string show = output(std::string(PLR_BIN) + " library show " + lib + " block");
  EXPECT_NE(show.find("particles: 3, horizon: 3"), std::string::npos) << show;
  EXPECT_NE(show.find("nodes:"), std::string::npos) << show;
  fs::resize_file(lib, fs::file_size(lib) - 10);
  const std::string refused = output(std::string(PLR_BIN) + " library list " + lib + " 2>&1");
  EXPECT_EQ(refused, fmt::format("plr library: {}: truncated: {} of {} bytes\n", lib,
                                 fs::file_size(lib), fs::file_size(lib) + 10));
}

TEST(GeneratorNode, ContinuationsMakeAChainThatResumesFromALibraryWithoutThem) {
  TempDir dir;
  write_config(dir / "none.yaml", {2, 1, 2, 1});
  write_config(dir / "zero.yaml", {2, 1, 2, 1}, "      continuations: 0\n");
  write_config(dir / "chain.yaml", {2, 1, 2, 1}, "      continuations: 2\n");
  // continuations: 0 is the default, and makes the strategy alone.
  ASSERT_EQ(wait_exit(start(dir / "none.yaml", dir / "none")), 0);
  ASSERT_EQ(wait_exit(start(dir / "zero.yaml", dir / "resumed")), 0);
  const std::string alone = plr::sim::testing::library_fingerprint(dir / "none/library.plrl");
  EXPECT_EQ(plr::sim::testing::library_fingerprint(dir / "resumed/library.plrl"), alone);

  // The chain in one go, and after the strategy alone (its leaves replayed
  // from its result store): the same library, the first entry unchanged.
  ASSERT_EQ(wait_exit(start(dir / "chain.yaml", dir / "chain")), 0);
  ASSERT_EQ(wait_exit(start(dir / "chain.yaml", dir / "resumed")), 0);
  const std::string chain = plr::sim::testing::library_fingerprint(dir / "chain/library.plrl");
  EXPECT_EQ(plr::sim::testing::library_fingerprint(dir / "resumed/library.plrl"), chain);
  EXPECT_EQ(chain.rfind(alone, 0), 0u) << chain;
  const auto lib = plr::sim::load_library(dir / "chain/library.plrl");
  ASSERT_TRUE(lib) << lib.error().message;
  ASSERT_GE(lib->entries.size(), 2u) << chain;
  ASSERT_LE(lib->entries.size(), 3u) << chain;
  for (std::size_t i = 1; i < lib->entries.size(); ++i) {
    const plr::sim::LibraryEntry& e = lib->entries[i];
    EXPECT_EQ(e.parent, lib->entries[i - 1].name);
    EXPECT_EQ(e.leaf.size(), 1u);  // horizon 1: one observation from the parent's root
    EXPECT_FALSE(e.start.empty());
    EXPECT_TRUE(fs::exists(dir / "chain" / (e.name + ".svg")));
  }

  const std::string file = (dir / "chain/library.plrl").string();
  const std::string list = output(std::string(PLR_BIN) + " library list " + file);
  EXPECT_NE(list.find("chains (parent -> continuation"), std::string::npos) << list;
  EXPECT_NE(list.find("-> " + lib->entries[1].name + " at ["), std::string::npos) << list;
  const std::string show =
      output(std::string(PLR_BIN) + " library show " + file + " " + lib->entries[1].name);
  EXPECT_NE(show.find("parent: block\nleaf: ["), std::string::npos) << show;
  EXPECT_NE(show.find("state_hash: "), std::string::npos) << show;
}

}  // namespace
