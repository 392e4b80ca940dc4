#include "truck/simulator.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <filesystem>

#include "plr/jobs/engine.hpp"

namespace plr::generator {

std::string Simulator::key(const SimRequest& request, sim::Fidelity fidelity) {
  return fmt::format(
      "{:016x}", actions::work_key(actions::state_hash(*request.state), request.action, fidelity));
}

int Simulator::busy() const {
  return std::min(running_.load(std::memory_order_relaxed), workers_);
}

std::vector<Simulated> Simulator::run(const std::vector<SimRequest>& batch,
                                      const plr::jobs::Store* store) {
  std::vector<plr::jobs::Job> jobs;
  jobs.reserve(batch.size());
  for (const SimRequest& r : batch)
    jobs.push_back({actions::kSimActionKind, key(r, fidelity_),
                    actions::encode_sim_job({r, observation_json_, fidelity_})});
  plr::jobs::RunOptions options;
  options.on_start = [&](std::size_t, std::size_t to_run) {
    running_.store(static_cast<int>(to_run), std::memory_order_relaxed);
  };
  options.on_done = [&](const plr::jobs::Result&) {
    running_.fetch_sub(1, std::memory_order_relaxed);
  };
  auto outcome = plr::jobs::run(jobs, runner_, store, options);
  running_.store(0, std::memory_order_relaxed);
  std::vector<Simulated> out(batch.size());
  for (std::size_t i = 0; i < batch.size(); ++i) {
    if (!outcome) {
      out[i].outcome = outcome.error();
      continue;
    }
    const plr::jobs::Result& r = outcome->results[i];
    out[i].stored = r.stored;
    if (!r.ok) {
      out[i].outcome = plr::make_error(PLR_ERR_INTERNAL, r.error);
      // Not kept: the generation stops on it, and a run started again tries it anew.
      std::error_code ec;
      if (store) std::filesystem::remove(store->result_file(r.key), ec);
    } else {
      out[i].outcome = actions::decode_sim_outcome(r.output, "result " + r.key);
    }
  }
  return out;
}

}  // namespace plr::generator
