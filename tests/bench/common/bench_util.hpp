// What the benchmarks share: a progress bar on stderr and medians.
#pragma once

#include <algorithm>
#include <cmath>
#include <vector>

#include "plr/jobs/progress.hpp"

namespace plr::bench {

inline double median(std::vector<double> v) {
  if (v.empty()) return std::nan("");
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// The job engine's progress bar: redrawn in place on a terminal, a line
// per tenth of the work when stderr is a file (a CI log).
using Progress = plr::jobs::ProgressBar;

}  // namespace plr::bench
