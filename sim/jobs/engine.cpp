#include "plr/jobs/engine.hpp"

#include <fmt/format.h>

#include <set>

#include "pause_for_tests.hpp"

namespace plr::jobs {

plr::Expected<Outcome> run(const std::vector<Job>& jobs, Runner& runner, const Store* store,
                           const RunOptions& options) {
  std::set<std::string> keys;
  for (const Job& job : jobs) {
    if (!valid_key(job.key))
      return plr::make_error(PLR_ERR_INVALID, fmt::format("job key '{}' is no file name", job.key));
    if (!keys.insert(job.key).second)
      return plr::make_error(PLR_ERR_INVALID, fmt::format("job key '{}' twice", job.key));
  }
  Outcome out;
  out.results.resize(jobs.size());
  std::vector<bool> reported(jobs.size(), false);
  std::vector<std::size_t> todo;
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    if (auto stored = store ? store->load(jobs[i].key) : std::nullopt) {
      out.results[i] = std::move(*stored);
      reported[i] = true;
      ++out.stored;
    } else {
      todo.push_back(i);
    }
  }
  if (options.on_start) options.on_start(out.stored, todo.size());
  std::optional<plr::Error> failure;
  runner.run(
      jobs, todo,
      [&](std::size_t i, Result result) {
        if (failure) return;
        if (store)
          if (auto saved = store->save(result); !saved) {
            failure = saved.error();
            return;
          }
        if (options.on_done) options.on_done(result);
        out.results[i] = std::move(result);
        reported[i] = true;
        ++out.ran;
        if (store) pause_for_tests();
      },
      [&] { return failure.has_value() || (options.stop && options.stop()); });
  if (failure) return *failure;
  for (std::size_t i = 0; i < jobs.size(); ++i)
    if (!reported[i]) {
      out.stopped = true;
      out.results[i].key = jobs[i].key;
      out.results[i].error = "not run: the run was stopped";
    }
  return out;
}

}  // namespace plr::jobs
