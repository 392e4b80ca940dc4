// What the benchmarks share: a progress bar on stderr and medians.
#pragma once

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace plr::bench {

inline double median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// A bar redrawn in place on a terminal; a line per tenth of the work when
// stderr is a file (a CI log).
class Progress {
 public:
  Progress(std::string name, std::size_t total)
      : name_(std::move(name)), total_(total), tty_(isatty(STDERR_FILENO) == 1) {}
  void step(const std::string& what) {
    ++done_;
    const int width = 30;
    const int filled = static_cast<int>(width * done_ / std::max<std::size_t>(total_, 1));
    if (tty_) {
      std::fprintf(stderr, "\r[%s%s] %zu/%zu %-40.40s", std::string(filled, '#').c_str(),
                   std::string(width - filled, '.').c_str(), done_, total_, what.c_str());
    } else if (done_ * 10 / total_ != (done_ - 1) * 10 / total_ || done_ == total_) {
      std::fprintf(stderr, "%s: %zu/%zu %s\n", name_.c_str(), done_, total_, what.c_str());
    }
    std::fflush(stderr);
  }
  void finish() {
    if (tty_) std::fprintf(stderr, "\n");
  }
  void add(std::size_t more) { total_ += more; }

 private:
  std::string name_;
  std::size_t total_, done_ = 0;
  bool tty_;
};

}  // namespace plr::bench
