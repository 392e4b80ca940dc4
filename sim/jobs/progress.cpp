#include "plr/jobs/progress.hpp"

#include <unistd.h>

#include <fmt/format.h>

#include <algorithm>
#include <cstdio>
#include <optional>

#include "plr/jobs/signals.hpp"

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

plr::Expected<Outcome> run_with_progress(const std::string& name, const std::vector<Job>& jobs,
                                         Runner& runner, const Store& store,
                                         const std::function<void()>& prepare) {
  std::optional<ProgressBar> bar;
  const StopOnSignals stop;
  auto outcome = run(jobs, runner, &store,
                     {[&](std::size_t stored, std::size_t to_run) {
                        if (stored > 0)
                          std::fprintf(stderr, "%s: %zu of %zu runs already in %s\n", name.c_str(),
                                       stored, jobs.size(), store.dir().c_str());
                        if (to_run > 0 && prepare) prepare();
                        bar.emplace(name, to_run);
                      },
                      [&] { return stop(); }, [&](const Result& r) { bar->step(r.key); }});
  if (bar) bar->finish();
  if (outcome) {
    // A stored failure is not run again; say so, or a run whose workers
    // could not start looks finished the next time.
    std::size_t failed = 0;
    const Result* first = nullptr;
    for (const Result& r : outcome->results)
      if (r.stored && !r.ok && failed++ == 0) first = &r;
    if (first != nullptr)
      std::fprintf(stderr,
                   "%s: %zu of the runs already in %s had failed and were not run again "
                   "(delete their result files to retry them), e.g. %s: %s\n",
                   name.c_str(), failed, store.dir().c_str(), first->key.c_str(),
                   first->error.c_str());
  }
  return outcome;
}

}  // namespace plr::jobs
