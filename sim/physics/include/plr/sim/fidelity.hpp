// How accurately a run simulates the boxes, chosen per run (a setting, not
// part of the simulated state: a snapshot restored into a simulation runs at
// that simulation's fidelity).
//
//   full      every box the contacts wake is integrated until it has been
//             slow for sleep_time (or balanced for a fifth of it): today's
//             simulation, bit for bit.
//   adaptive  as full, but boxes with no contact path to the action (the
//             robot, the held boxes, a box moving at wake_speed or more) are
//             frozen as soon as they have been slow for a fifth of
//             sleep_time, balanced or not; a frozen box wakes when a box on
//             such a path comes within the wake margin while closing on it
//             at sleep_speed or more (see docs/fidelity.md).
//   fast      the robot and what it holds move kinematically while no box
//             moves: no fixed steps are integrated. A box is handed to the
//             physics (woken) only when a robot shape or a held box presses
//             into it (wake_depth), or when a box it rests on leaves and its
//             centre of mass is no longer over what remains below it (the
//             support rule); a released box over a running belt leaves on
//             it. The woken boxes run as at adaptive fidelity (see
//             docs/fidelity.md).
#pragma once

#include <plr/expected.hpp>

#include <string>
#include <string_view>

namespace plr::sim {

enum class Fidelity { kFull, kAdaptive, kFast };

// "full", "adaptive" or "fast"; anything else is an error naming the value.
plr::Expected<Fidelity> parse_fidelity(std::string_view name);
std::string to_string(Fidelity fidelity);

}  // namespace plr::sim
