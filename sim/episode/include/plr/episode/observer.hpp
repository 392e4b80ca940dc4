// What watches an episode as it goes: the executor's progress line, state
// topic, log and report; a test's trace. Each hook is told in the order the
// observers were given to the engine; the figures it is given are the
// engine's so far.
#pragma once

#include <plr/expected.hpp>

#include <cstdint>
#include <string>

#include "plr/episode/episode.hpp"
#include "plr/sim/strategy.hpp"

namespace plr::episode {

struct ActionStart {
  std::uint64_t number = 0;  // 1 for the run's first action (a repeated one keeps its number)
  sim::Action action{};
  const sim::Strategy& strategy;  // the tree being walked
  std::uint32_t node = 0;
};

class Observer {
 public:
  virtual ~Observer() = default;
  // An action about to run; again after a recovery that repeats it.
  virtual void starting(const ActionStart&, const Episode&) {}
  // The running action's progress and log lines (actions::Reporter).
  virtual void progress(const std::string&) {}
  virtual void note(const std::string&) {}
  // An action done, and recorded in the episode.
  virtual void recorded(const EpisodeStep&, const Episode&) {}
  // The world was lost (Recovery::lost); restored() follows once it is back
  // and the episode is again as at its last checkpoint.
  virtual void lost(const plr::Error&) {}
  virtual void restored(const Episode&) {}
  // The run ended by its rules (Episode::stop_reason).
  virtual void stopped(const Episode&) {}
};

}  // namespace plr::episode
