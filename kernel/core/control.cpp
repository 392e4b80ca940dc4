#include "control.hpp"

#include "pipeline_config.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <fcntl.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>

namespace plr::kernel {

namespace {

Error sys_error(const std::string& what) {
  return make_error(PLR_ERR_INTERNAL, fmt::format("{}: {}", what, std::strerror(errno)));
}

bool fill_address(const std::string& path, sockaddr_un* addr) {
  std::memset(addr, 0, sizeof *addr);
  addr->sun_family = AF_UNIX;
  if (path.size() >= sizeof addr->sun_path) return false;
  std::memcpy(addr->sun_path, path.c_str(), path.size());
  return true;
}

bool read_line(int fd, std::string* out, int timeout_ms) {
  char buf[4096];
  for (;;) {
    pollfd p{fd, POLLIN, 0};
    if (poll(&p, 1, timeout_ms) <= 0) return false;
    const auto n = ::read(fd, buf, sizeof buf);
    if (n <= 0) return !out->empty();
    out->append(buf, static_cast<std::size_t>(n));
    if (out->find('\n') != std::string::npos) return true;
    if (out->size() > (1u << 20)) return false;
  }
}

bool write_all(int fd, const std::string& s) {
  std::size_t done = 0;
  while (done < s.size()) {
    const auto n = ::send(fd, s.data() + done, s.size() - done, MSG_NOSIGNAL);
    if (n <= 0) return false;
    done += static_cast<std::size_t>(n);
  }
  return true;
}

}  // namespace

namespace {

// `dir` (and its missing parents) created private; an existing one must be
// a real folder of ours that only we can use, else a socket in it could be
// replaced by someone else's.
Expected<std::string> private_dir(const std::string& dir) {
  std::error_code ec;
  std::filesystem::create_directories(std::filesystem::path(dir).parent_path(), ec);
  if (::mkdir(dir.c_str(), 0700) != 0 && errno != EEXIST) return sys_error("mkdir " + dir);
  struct stat st {};
  if (::lstat(dir.c_str(), &st) != 0) return sys_error("stat " + dir);
  if (!S_ISDIR(st.st_mode) || st.st_uid != ::geteuid() || (st.st_mode & 0077) != 0)
    return make_error(
        PLR_ERR_INVALID,
        fmt::format("{}: refused as control folder: it must be a folder of ours (uid {}) with "
                    "mode 0700, it is {} of uid {} with mode {:04o}",
                    dir, ::geteuid(), S_ISDIR(st.st_mode) ? "a folder" : "not a folder", st.st_uid,
                    st.st_mode & 07777));
  return dir;
}

}  // namespace

Expected<std::string> control_dir() {
  const char* runtime = std::getenv("XDG_RUNTIME_DIR");
  if (runtime != nullptr && *runtime == '/') return private_dir(std::string(runtime) + "/plr");
  // Not a fixed name in a shared folder such as /tmp: another user could
  // create it first and stop every run.
  const char* home = std::getenv("HOME");
  if (home != nullptr && *home == '/') return private_dir(std::string(home) + "/.local/state/plr");
  return make_error(PLR_ERR_UNAVAILABLE,
                    "no private folder for the control socket: set XDG_RUNTIME_DIR or HOME");
}

Expected<std::string> control_socket_path(const std::string& pipeline) {
  if (auto ok = check_name(pipeline, "pipeline"); !ok) return ok.error();
  auto dir = control_dir();
  if (!dir) return dir.error();
  return *dir + "/" + pipeline + ".sock";
}

ControlServer::ControlServer(std::string path, Handler handler)
    : path_(std::move(path)), handler_(std::move(handler)) {}

ControlServer::~ControlServer() {
  if (thread_.joinable()) {
    const char x = 1;
    (void)!::write(wake_[1], &x, 1);
    thread_.join();
  }
  if (fd_ >= 0) {
    ::close(fd_);
    ::unlink(path_.c_str());
  }
  for (int fd : wake_)
    if (fd >= 0) ::close(fd);
}

Status ControlServer::start() {
  sockaddr_un addr{};
  if (!fill_address(path_, &addr))
    return make_error(PLR_ERR_INVALID, fmt::format("{}: socket path too long", path_));
  // A socket left by a run that no longer answers is stale; a live one means
  // the same pipeline is already running.
  struct stat st {};
  if (::lstat(path_.c_str(), &st) == 0) {
    if (!S_ISSOCK(st.st_mode))
      return make_error(PLR_ERR_INVALID, fmt::format("{}: exists and is not a socket", path_));
    if (control_request(path_, {{"cmd", "ping"}}, 500))
      return make_error(PLR_ERR_STATE,
                        fmt::format("{}: a pipeline with this name is already running", path_));
    ::unlink(path_.c_str());
  }
  fd_ = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd_ < 0) return sys_error("socket");
  const mode_t old = ::umask(0177);
  const int rc = ::bind(fd_, reinterpret_cast<sockaddr*>(&addr), sizeof addr);
  ::umask(old);
  if (rc != 0) return sys_error("bind " + path_);
  if (::listen(fd_, 8) != 0) return sys_error("listen " + path_);
  if (::pipe2(wake_, O_CLOEXEC) != 0) return sys_error("pipe");
  thread_ = std::thread([this] { loop(); });
  return {};
}

void ControlServer::loop() {
  for (;;) {
    pollfd p[2] = {{fd_, POLLIN, 0}, {wake_[0], POLLIN, 0}};
    if (::poll(p, 2, -1) < 0) {
      if (errno == EINTR) continue;
      return;
    }
    if (p[1].revents) return;
    const int c = ::accept4(fd_, nullptr, nullptr, SOCK_CLOEXEC);
    if (c < 0) continue;
    std::string line;
    nlohmann::json reply;
    if (!read_line(c, &line, 2000)) {
      reply = {{"ok", false}, {"error", "no request"}};
    } else {
      try {
        reply = handler_(nlohmann::json::parse(line.substr(0, line.find('\n'))));
      } catch (const std::exception& e) {
        reply = {{"ok", false}, {"error", std::string("bad request: ") + e.what()}};
      }
    }
    (void)write_all(c, reply.dump() + "\n");
    ::close(c);
  }
}

Expected<nlohmann::json> control_request(const std::string& path, const nlohmann::json& request,
                                         int timeout_ms) {
  sockaddr_un addr{};
  if (!fill_address(path, &addr))
    return make_error(PLR_ERR_INVALID, fmt::format("{}: socket path too long", path));
  const int fd = ::socket(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return sys_error("socket");
  if (::connect(fd, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
    auto e =
        make_error(PLR_ERR_UNAVAILABLE, fmt::format("connect {}: {}", path, std::strerror(errno)));
    ::close(fd);
    return e;
  }
  std::string line;
  const bool ok = write_all(fd, request.dump() + "\n") && read_line(fd, &line, timeout_ms);
  ::close(fd);
  if (!ok) return make_error(PLR_ERR_TIMEOUT, fmt::format("{}: no answer", path));
  try {
    return nlohmann::json::parse(line.substr(0, line.find('\n')));
  } catch (const std::exception& e) {
    return make_error(PLR_ERR_INVALID, fmt::format("{}: bad answer: {}", path, e.what()));
  }
}

}  // namespace plr::kernel
