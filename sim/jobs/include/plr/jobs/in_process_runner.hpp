// Runs jobs one after the other in the calling thread: for tests, and for
// jobs too small for a process of their own.
#pragma once

#include "plr/jobs/kinds.hpp"
#include "plr/jobs/runner.hpp"

namespace plr::jobs {

class InProcessRunner final : public Runner {
 public:
  explicit InProcessRunner(const Kinds& kinds) : kinds_(kinds) {}
  void run(const std::vector<Job>& jobs, const std::vector<std::size_t>& todo, const Done& done,
           const std::function<bool()>& stop) override;

 private:
  const Kinds& kinds_;
};

}  // namespace plr::jobs
