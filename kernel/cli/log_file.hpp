// `plr run --log FILE`: what the run writes to stdout and stderr, its hosts'
// processes' too (they inherit both), goes through a pipe to FILE, which is
// rotated so the log of a run of any length stays bounded: when FILE would
// pass `max_bytes` it becomes FILE.1 (FILE.1 becomes FILE.2, ...; the
// oldest beyond FILE.<keep> is removed), at a line's end where a line fits.
// At most (keep + 1) * max_bytes on disk. A FILE left by an earlier run is
// rotated away first. A write the disk refuses is counted and dropped: the
// run never waits for its log.
#pragma once

#include <plr/expected.hpp>

#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <thread>

namespace plr::kernel {

struct LogFileOptions {
  std::string path;
  std::uint64_t max_bytes = std::uint64_t{16} << 20;
  int keep = 3;
};

inline constexpr std::uint64_t kMinLogBytes = 4096;

class LogFile {
 public:
  // Checks the options, opens FILE and points stdout and stderr at the pipe.
  static Expected<std::unique_ptr<LogFile>> open(LogFileOptions options);
  // Points stdout and stderr back, writes what is left in the pipe.
  ~LogFile();
  LogFile(const LogFile&) = delete;
  LogFile& operator=(const LogFile&) = delete;

  std::uint64_t dropped_bytes() const { return dropped_; }

 private:
  explicit LogFile(LogFileOptions options);
  void loop();
  void write(std::string_view data);
  void rotate();
  void open_file();

  LogFileOptions options_;
  int fd_ = -1;
  std::uint64_t size_ = 0;
  int read_fd_ = -1;
  int saved_stdout_ = -1, saved_stderr_ = -1;
  std::atomic<bool> stop_{false};
  std::atomic<std::uint64_t> dropped_{0};
  std::thread thread_;
};

}  // namespace plr::kernel
