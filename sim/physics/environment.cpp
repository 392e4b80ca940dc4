#include "plr/sim/physics.hpp"

namespace plr::sim {

World make_environment(EnvFamily family, std::uint64_t seed, const Trailer& trailer,
                       double max_settle) {
  Simulation sim(generate_world(family, seed, trailer));
  sim.settle(max_settle);
  return sim.world();
}

}  // namespace plr::sim
