// Size limits for model files: a file that asks for more is refused with a
// located error instead of exhausting memory. Fuzzers use small limits.
#pragma once

#include <cstddef>

namespace plr::pomdp {

struct ReadLimits {
  std::size_t max_file_bytes = std::size_t{256} << 20;
  int max_states = 1 << 20;
  int max_actions = 1 << 12;
  int max_observations = 1 << 16;
  // States times actions: the number of table rows.
  std::size_t max_state_actions = std::size_t{1} << 23;
  // Non-zero transition and observation entries, and reward rules.
  std::size_t max_entries = 50'000'000;
};

}  // namespace plr::pomdp
