// write_file_atomically: the whole new content or the old one, never a part,
// no temporary file left behind, and errors that name the path and the cause.
#include <plr/atomic_file.hpp>

#include <gtest/gtest.h>

#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>

namespace plr {
namespace {

namespace fs = std::filesystem;

class AtomicFile : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("plr_atomic_file_test_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    fs::permissions(dir_, fs::perms::owner_all);
    fs::remove_all(dir_);
  }
  static std::string read(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    std::ostringstream text;
    text << in.rdbuf();
    return text.str();
  }
  std::size_t files() const {
    return static_cast<std::size_t>(std::distance(fs::directory_iterator(dir_), {}));
  }
  fs::path dir_;
};

TEST_F(AtomicFile, WritesAndReplacesWholeFiles) {
  const auto file = (dir_ / "report.json").string();
  ASSERT_TRUE(write_file_atomically(file, "first"));
  EXPECT_EQ(read(file), "first");
  const std::string big(1 << 20, 'x');
  ASSERT_TRUE(write_file_atomically(file, big));
  EXPECT_EQ(read(file), big);
  ASSERT_TRUE(write_file_atomically(file, ""));
  EXPECT_EQ(read(file), "");
  EXPECT_EQ(files(), 1u) << "no temporary file is left behind";
}

TEST_F(AtomicFile, MakesAnOrdinaryDocument) {
  const auto file = dir_ / "world.yaml";
  ASSERT_TRUE(write_file_atomically(file.string(), "a: 1\n"));
  struct stat st {};
  ASSERT_EQ(::stat(file.c_str(), &st), 0);
  EXPECT_EQ(st.st_mode & 0777, 0644u);
}

TEST_F(AtomicFile, ARelativePathLandsInTheWorkingFolder) {
  const auto old = fs::current_path();
  fs::current_path(dir_);
  const Status s = write_file_atomically("plain.txt", "here");
  fs::current_path(old);
  ASSERT_TRUE(s) << s.error().message;
  EXPECT_EQ(read(dir_ / "plain.txt"), "here");
}

TEST_F(AtomicFile, AFailureLeavesTheOldFileAndSaysWhy) {
  if (::geteuid() == 0) GTEST_SKIP() << "root writes into read-only folders";
  const auto file = (dir_ / "strategy.yaml").string();
  ASSERT_TRUE(write_file_atomically(file, "old"));
  fs::permissions(dir_, fs::perms::owner_read | fs::perms::owner_exec);
  const Status s = write_file_atomically(file, "new");
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().message, file + ": cannot create a temporary file: Permission denied");
  EXPECT_EQ(read(file), "old");
  EXPECT_EQ(files(), 1u);
}

TEST_F(AtomicFile, AMissingFolderIsNamed) {
  const auto file = (dir_ / "no" / "such.txt").string();
  const Status s = write_file_atomically(file, "x");
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().message,
            file + ": cannot create a temporary file: No such file or directory");
}

TEST_F(AtomicFile, AFolderIsNotReplaced) {
  const auto sub = dir_ / "sub";
  fs::create_directories(sub);
  const Status s = write_file_atomically(sub.string(), "x");
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().message, sub.string() + ": cannot replace: Is a directory");
  EXPECT_TRUE(fs::is_directory(sub));
  EXPECT_EQ(files(), 1u) << "the temporary file is removed";
}

}  // namespace
}  // namespace plr
