// `plr run --log FILE`: the run's output, its child processes' too, in FILE
// and its rotated predecessors, never more than (keep + 1) files of at most
// max_bytes, lines whole.
#include "log_file.hpp"

#include <gtest/gtest.h>

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace plr::kernel {
namespace {

namespace fs = std::filesystem;

struct TempDir {
  fs::path path;
  TempDir() {
    std::string t = (fs::temp_directory_path() / "plr_log_file_XXXXXX").string();
    path = ::mkdtemp(t.data());
  }
  ~TempDir() { fs::remove_all(path); }
};

std::string read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// A child process writing `lines` lines to the stderr it inherited, as a host does.
void child_writes(int lines) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    const std::string script = "i=0; while [ $i -lt " + std::to_string(lines) +
                               " ]; do echo \"host line $i\"; i=$((i+1)); done >&2";
    ::execl("/bin/sh", "sh", "-c", script.c_str(), nullptr);
    ::_exit(127);
  }
  int status = 0;
  ::waitpid(pid, &status, 0);
}

TEST(LogFile, OutputPastTheBoundIsRotatedAndTheFilesStayWithinIt) {
  TempDir dir;
  const fs::path file = dir.path / "run.log";
  constexpr std::uint64_t kMax = 8192;
  constexpr int kKeep = 2;
  std::uint64_t dropped = 0;
  {
    auto log = LogFile::open({file.string(), kMax, kKeep});
    ASSERT_TRUE(log) << log.error().message;
    // About 150 KiB: stderr and stdout of this process and of a child's.
    for (int i = 0; i < 2000; ++i) std::fprintf(stderr, "main line %d on stderr\n", i);
    for (int i = 0; i < 1000; ++i) std::printf("main line %d on stdout\n", i);
    std::fflush(stdout);
    child_writes(2000);
    std::fprintf(stderr, "the last line\n");
    dropped = (*log)->dropped_bytes();
  }
  EXPECT_EQ(dropped, 0u);
  std::vector<fs::path> files;
  for (const auto& e : fs::directory_iterator(dir.path)) files.push_back(e.path());
  EXPECT_EQ(files.size(), static_cast<std::size_t>(kKeep + 1));
  for (const auto& name : {"run.log", "run.log.1", "run.log.2"}) {
    const fs::path p = dir.path / name;
    ASSERT_TRUE(fs::exists(p)) << name;
    EXPECT_LE(fs::file_size(p), kMax) << name;
    // Whole lines: each file starts a line and ends one.
    const std::string text = read_file(p);
    ASSERT_FALSE(text.empty()) << name;
    EXPECT_EQ(text.back(), '\n') << name;
    EXPECT_TRUE(text.starts_with("main line") || text.starts_with("host line") ||
                text.starts_with("the last line"))
        << name << " starts with: " << text.substr(0, 40);
  }
  EXPECT_FALSE(fs::exists(dir.path / "run.log.3"));
  const std::string newest = read_file(file);
  EXPECT_NE(newest.find("host line 1999\nthe last line\n"), std::string::npos) << newest;
}

TEST(LogFile, AnEarlierRunsLogBecomesFileDotOne) {
  TempDir dir;
  const fs::path file = dir.path / "run.log";
  std::ofstream(file) << "the earlier run\n";
  {
    auto log = LogFile::open({file.string(), 4096, 1});
    ASSERT_TRUE(log) << log.error().message;
    std::fprintf(stderr, "this run\n");
  }
  EXPECT_EQ(read_file(dir.path / "run.log.1"), "the earlier run\n");
  EXPECT_EQ(read_file(file), "this run\n");
}

TEST(LogFile, ABoundTooSmallIsRefused) {
  TempDir dir;
  auto log = LogFile::open({(dir.path / "run.log").string(), 100, 3});
  ASSERT_FALSE(log);
  EXPECT_NE(log.error().message.find("--log-max"), std::string::npos) << log.error().message;
  EXPECT_FALSE(fs::exists(dir.path / "run.log"));
}

}  // namespace
}  // namespace plr::kernel
