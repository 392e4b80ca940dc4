#include "plr/jobs/in_process_runner.hpp"

namespace plr::jobs {

void InProcessRunner::run(const std::vector<Job>& jobs, const std::vector<std::size_t>& todo,
                          const Done& done, const std::function<bool()>& stop) {
  for (const std::size_t i : todo) {
    if (stop && stop()) return;
    done(i, kinds_.run(jobs[i]));
  }
}

}  // namespace plr::jobs
