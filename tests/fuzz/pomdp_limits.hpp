// The POMDP readers' fuzz targets read under these bounds: small enough that
// an input cannot make a target spend its time on one legal, huge model.
#pragma once

#include "plr/pomdp/read_limits.hpp"

inline plr::pomdp::ReadLimits fuzz_limits() {
  plr::pomdp::ReadLimits limits;
  limits.max_states = 2000;
  limits.max_actions = 64;
  limits.max_observations = 64;
  limits.max_state_actions = 20000;
  limits.max_entries = 200000;
  return limits;
}
