// The control socket of a running pipeline: its private folder, one JSON
// request and reply per connection, a stale socket replaced, a live one kept.
#include "control.hpp"

#include <gtest/gtest.h>

#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>

namespace plr::kernel {
namespace {

namespace fs = std::filesystem;

class ControlTest : public ::testing::Test {
 protected:
  void SetUp() override {
    runtime_ = fs::temp_directory_path() / ("plr_control_test_" + std::to_string(::getpid()));
    fs::remove_all(runtime_);
    fs::create_directories(runtime_);
    old_ = std::getenv("XDG_RUNTIME_DIR") ? std::getenv("XDG_RUNTIME_DIR") : "";
    ::setenv("XDG_RUNTIME_DIR", runtime_.c_str(), 1);
  }
  void TearDown() override {
    if (old_.empty())
      ::unsetenv("XDG_RUNTIME_DIR");
    else
      ::setenv("XDG_RUNTIME_DIR", old_.c_str(), 1);
    fs::remove_all(runtime_);
  }
  static mode_t mode_of(const fs::path& p) {
    struct stat st {};
    return ::lstat(p.c_str(), &st) == 0 ? st.st_mode & 0777 : 0;
  }
  static ControlServer::Handler echo() {
    return [](const nlohmann::json& request) {
      return nlohmann::json{{"ok", true}, {"echo", request}};
    };
  }

  fs::path runtime_;
  std::string old_;
};

TEST_F(ControlTest, TheFolderIsPrivateAndTheSocketNamedAfterThePipeline) {
  auto dir = control_dir();
  ASSERT_TRUE(dir) << dir.error().message;
  EXPECT_EQ(*dir, (runtime_ / "plr").string());
  EXPECT_EQ(mode_of(*dir), 0700u);
  EXPECT_EQ(control_socket_path("demo").value(), (runtime_ / "plr" / "demo.sock").string());
}

TEST_F(ControlTest, AFolderOthersCanWriteIsRefused) {
  fs::create_directories(runtime_ / "plr");
  fs::permissions(runtime_ / "plr", fs::perms::owner_all | fs::perms::group_write);
  auto dir = control_dir();
  ASSERT_FALSE(dir);
  EXPECT_EQ(dir.error().message,
            (runtime_ / "plr").string() +
                ": refused as control folder: it must be a folder of ours (uid " +
                std::to_string(::geteuid()) + ") with mode 0700, it is a folder of uid " +
                std::to_string(::geteuid()) + " with mode 0720");
}

TEST_F(ControlTest, ARequestGetsItsReplyOverAPrivateSocket) {
  const std::string path = control_socket_path("demo").value();
  ControlServer server(path, echo());
  ASSERT_TRUE(server.start());
  EXPECT_EQ(mode_of(path) & 0077, 0u) << "only the user may connect";
  auto reply = control_request(path, {{"cmd", "status"}}, 5000);
  ASSERT_TRUE(reply) << reply.error().message;
  EXPECT_EQ((*reply)["echo"]["cmd"], "status");
  // One connection per request: a second one is served the same way.
  EXPECT_TRUE(control_request(path, {{"cmd", "swap"}}, 5000));
}

TEST_F(ControlTest, ARequestThatIsNotJsonIsAnsweredWithTheReason) {
  const std::string path = control_socket_path("demo").value();
  ControlServer server(path, echo());
  ASSERT_TRUE(server.start());
  const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::strncpy(addr.sun_path, path.c_str(), sizeof addr.sun_path - 1);
  ASSERT_EQ(::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
  const std::string junk = "{not json\n";
  ASSERT_EQ(::write(fd, junk.data(), junk.size()), static_cast<ssize_t>(junk.size()));
  char buf[512] = {};
  const auto n = ::read(fd, buf, sizeof buf - 1);
  ::close(fd);
  ASSERT_GT(n, 0);
  const auto reply = nlohmann::json::parse(std::string(buf, static_cast<std::size_t>(n)));
  EXPECT_EQ(reply["ok"], false);
  EXPECT_EQ(reply["error"].get<std::string>().rfind("bad request: ", 0), 0u) << reply.dump();
}

TEST_F(ControlTest, ALiveSocketIsKeptAStaleOneReplaced) {
  const std::string path = control_socket_path("demo").value();
  {
    ControlServer first(path, echo());
    ASSERT_TRUE(first.start());
    ControlServer second(path, echo());
    const Status s = second.start();
    ASSERT_FALSE(s);
    EXPECT_EQ(s.error().code, PLR_ERR_STATE);
    EXPECT_EQ(s.error().message, path + ": a pipeline with this name is already running");
  }
  // A socket left behind by a run that no longer answers.
  const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  std::strncpy(addr.sun_path, path.c_str(), sizeof addr.sun_path - 1);
  ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr), 0);
  ::close(fd);
  ASSERT_TRUE(fs::exists(path));
  ControlServer next(path, echo());
  ASSERT_TRUE(next.start());
  EXPECT_TRUE(control_request(path, {{"cmd", "ping"}}, 5000));
}

TEST_F(ControlTest, ServerGoneOrPathTooLongAreErrors) {
  const std::string path = control_socket_path("nobody").value();
  auto none = control_request(path, {{"cmd", "status"}}, 1000);
  ASSERT_FALSE(none);
  EXPECT_EQ(none.error().message, "connect " + path + ": No such file or directory");
  const std::string long_path = "/tmp/" + std::string(200, 'x') + ".sock";
  EXPECT_EQ(control_request(long_path, {}, 1000).error().message,
            long_path + ": socket path too long");
  ControlServer server(long_path, echo());
  EXPECT_EQ(server.start().error().code, PLR_ERR_INVALID);
}

}  // namespace
}  // namespace plr::kernel
