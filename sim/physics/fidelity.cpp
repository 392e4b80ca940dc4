#include "plr/sim/fidelity.hpp"

namespace plr::sim {

plr::Expected<Fidelity> parse_fidelity(std::string_view name) {
  if (name == "full") return Fidelity::kFull;
  if (name == "adaptive") return Fidelity::kAdaptive;
  if (name == "fast")
    return plr::make_error(PLR_ERR_INVALID, "fidelity: 'fast' is not built (full or adaptive)");
  return plr::make_error(PLR_ERR_INVALID,
                         "fidelity: '" + std::string(name) + "' is not one of full, adaptive");
}

std::string to_string(Fidelity fidelity) {
  return fidelity == Fidelity::kAdaptive ? "adaptive" : "full";
}

}  // namespace plr::sim
