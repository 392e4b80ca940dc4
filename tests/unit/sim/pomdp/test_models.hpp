// Hand-made two-state models whose values can be worked out on paper.
#pragma once

#include <string>

#include "plr/pomdp/cassandra_reader.hpp"

namespace plr::pomdp::test {

// The state never changes and nothing is observed: V = max_a b.R_a / (1 - g).
// At the uniform belief with g = 0.5: stay earns 0.5 a step, go 1.0: V* = 2.
inline const char* kBandit = R"(discount: 0.5
values: reward
states: s0 s1
actions: stay go
observations: none
T: * identity
O: * : * : none 1
R: stay : s0 : * : * 1
R: go : s1 : * : * 2
)";

// sense shows the state, a correct pick earns 1 and a wrong one -1, nothing
// moves. g = 0.5: V(known) = 1/(1-g) = 2, V*(uniform) = 0 + g * 2 = 1.
inline const char* kSense = R"(discount: 0.5
values: reward
states: left right
actions: sense pick-left pick-right
observations: see-left see-right
start: uniform
T: * identity
O: sense identity
O: pick-left uniform
O: pick-right uniform
R: pick-left : left : * : * 1
R: pick-left : right : * : * -1
R: pick-right : right : * : * 1
R: pick-right : left : * : * -1
)";

inline TabularModel parse_or_die(const char* text, const char* name) {
  auto m = parse_cassandra(text, name);
  if (!m) throw std::runtime_error(m.error().message);
  return std::move(m).value();
}

}  // namespace plr::pomdp::test
