#include "plr/sim/fidelity.hpp"

namespace plr::sim {

plr::Expected<Fidelity> parse_fidelity(std::string_view name) {
  if (name == "full") return Fidelity::kFull;
  if (name == "adaptive") return Fidelity::kAdaptive;
  if (name == "fast") return Fidelity::kFast;
  return plr::make_error(
      PLR_ERR_INVALID, "fidelity: '" + std::string(name) + "' is not one of full, adaptive, fast");
}

std::string to_string(Fidelity fidelity) {
  switch (fidelity) {
    case Fidelity::kAdaptive:
      return "adaptive";
    case Fidelity::kFast:
      return "fast";
    case Fidelity::kFull:
      break;
  }
  return "full";
}

}  // namespace plr::sim
