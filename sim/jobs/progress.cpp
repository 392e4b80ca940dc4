#include "plr/jobs/progress.hpp"

#include <unistd.h>

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>

namespace plr::jobs {

ProgressBar::ProgressBar(std::string name, std::size_t total)
    : name_(std::move(name)),
      total_(total),
      tty_(isatty(STDERR_FILENO) == 1),
      t0_(std::chrono::steady_clock::now()) {}

void ProgressBar::step(const std::string& what) {
  ++done_;
  const std::size_t total = std::max(total_, done_);
  const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0_).count();
  const double eta = s / static_cast<double>(done_) * static_cast<double>(total - done_);
  const int width = 30;
  const int filled = static_cast<int>(width * done_ / total);
  const std::string line =
      fmt::format("{}: [{}{}] {}/{}  {:.0f} min left  {} done", name_, std::string(filled, '#'),
                  std::string(width - filled, '.'), done_, total, eta / 60, what);
  if (tty_)
    std::fprintf(stderr, "\r%-110.110s", line.c_str());
  else if (done_ * 10 / total != (done_ - 1) * 10 / total || done_ == total)
    std::fprintf(stderr, "%s\n", line.c_str());
  std::fflush(stderr);
}

void ProgressBar::finish() {
  if (tty_ && done_ > 0) std::fprintf(stderr, "\n");
}

}  // namespace plr::jobs
