#include "log_file.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <fcntl.h>
#include <poll.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>

namespace plr::kernel {

namespace fs = std::filesystem;

Expected<std::unique_ptr<LogFile>> LogFile::open(LogFileOptions options) {
  if (options.path.empty()) return make_error(PLR_ERR_INVALID, "--log: empty file name");
  if (options.max_bytes < kMinLogBytes)
    return make_error(PLR_ERR_INVALID, fmt::format("--log-max: {} B is below the least, {} B",
                                                   options.max_bytes, kMinLogBytes));
  if (options.keep < 0 || options.keep > 1000)
    return make_error(PLR_ERR_INVALID,
                      fmt::format("--log-keep: {} is not 0 to 1000", options.keep));
  std::unique_ptr<LogFile> log(new LogFile(std::move(options)));
  std::error_code ec;
  if (fs::exists(log->options_.path, ec) && fs::file_size(log->options_.path, ec) > 0)
    log->rotate();  // an earlier run's log becomes FILE.1
  else
    log->open_file();
  if (log->fd_ < 0)
    return make_error(PLR_ERR_INVALID,
                      fmt::format("--log: {}: {}", log->options_.path, std::strerror(errno)));
  int pipe_fds[2];
  if (::pipe2(pipe_fds, O_CLOEXEC) != 0)
    return make_error(PLR_ERR_INTERNAL, fmt::format("--log: pipe: {}", std::strerror(errno)));
  std::fflush(stdout);
  std::fflush(stderr);
  log->saved_stdout_ = ::fcntl(STDOUT_FILENO, F_DUPFD_CLOEXEC, 0);
  log->saved_stderr_ = ::fcntl(STDERR_FILENO, F_DUPFD_CLOEXEC, 0);
  // dup2 clears close-on-exec: the hosts inherit the pipe as their stdout and stderr.
  ::dup2(pipe_fds[1], STDOUT_FILENO);
  ::dup2(pipe_fds[1], STDERR_FILENO);
  ::close(pipe_fds[1]);
  log->read_fd_ = pipe_fds[0];
  log->thread_ = std::thread([l = log.get()] { l->loop(); });
  return log;
}

LogFile::LogFile(LogFileOptions options) : options_(std::move(options)) {}

LogFile::~LogFile() {
  spdlog::default_logger()->flush();
  std::fflush(stdout);
  std::fflush(stderr);
  if (saved_stdout_ >= 0) ::dup2(saved_stdout_, STDOUT_FILENO);
  if (saved_stderr_ >= 0) ::dup2(saved_stderr_, STDERR_FILENO);
  stop_ = true;
  if (thread_.joinable()) thread_.join();
  for (int fd : {saved_stdout_, saved_stderr_, read_fd_, fd_})
    if (fd >= 0) ::close(fd);
}

void LogFile::loop() {
  // Until every writer closed the pipe; once stopped, until it is quiet for
  // a while (a process that still holds it, a host being stopped, may say
  // more; then it is gone too).
  char buf[1 << 16];
  for (;;) {
    pollfd p{read_fd_, POLLIN, 0};
    const int r = ::poll(&p, 1, 100);
    if (r < 0 && errno == EINTR) continue;
    if (r <= 0) {
      if (stop_ || r < 0) return;
      continue;
    }
    const ssize_t n = ::read(read_fd_, buf, sizeof buf);
    if (n > 0) write({buf, static_cast<std::size_t>(n)});
    if (n == 0 || (n < 0 && errno != EINTR)) return;
  }
}

void LogFile::open_file() {
  fd_ = ::open(options_.path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  size_ = 0;
}

void LogFile::rotate() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  const auto& p = options_.path;
  if (options_.keep == 0) {
    ::unlink(p.c_str());
  } else {
    for (int k = options_.keep - 1; k >= 1; --k)
      ::rename(fmt::format("{}.{}", p, k).c_str(), fmt::format("{}.{}", p, k + 1).c_str());
    ::rename(p.c_str(), (p + ".1").c_str());
  }
  open_file();
}

void LogFile::write(std::string_view data) {
  const std::uint64_t max = options_.max_bytes;
  while (!data.empty()) {
    if (fd_ < 0 || size_ >= max) rotate();
    if (fd_ < 0) {  // cannot open it now: dropped, tried again with the next write
      dropped_ += data.size();
      return;
    }
    std::size_t n = static_cast<std::size_t>(std::min<std::uint64_t>(max - size_, data.size()));
    if (n < data.size()) {
      // A line that does not fit starts the next file, unless it fills one alone.
      const auto end = data.substr(0, n).rfind('\n');
      if (end != std::string_view::npos) {
        n = end + 1;
      } else if (size_ > 0) {
        size_ = max;
        continue;
      }
    }
    const ssize_t w = ::write(fd_, data.data(), n);
    if (w < 0 && errno == EINTR) continue;
    if (w <= 0) {
      dropped_ += n;  // refused (disk full, read-only): dropped, the run goes on
    } else {
      n = static_cast<std::size_t>(w);
      size_ += n;
    }
    data.remove_prefix(n);
  }
}

}  // namespace plr::kernel
