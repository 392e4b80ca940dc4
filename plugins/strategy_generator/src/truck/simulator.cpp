#include "truck/simulator.hpp"

namespace plr::generator {

std::vector<plr::Expected<SimOutcome>> LocalSimulator::run(const std::vector<SimRequest>& batch) {
  std::vector<plr::Expected<SimOutcome>> out;
  out.reserve(batch.size());
  busy_ = 1;
  for (const SimRequest& r : batch) out.push_back(runner_.run(r));
  busy_ = 0;
  return out;
}

}  // namespace plr::generator
