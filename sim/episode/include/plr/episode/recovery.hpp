// A world the engine may lose in the middle of a run and get back: a
// simulator whose host dies is restarted by the kernel and restored from its
// last checkpoint (the executor's bus backend). In process nothing is lost:
// the engine runs without one, and a backend error ends the run.
#pragma once

#include <plr/expected.hpp>

namespace plr::episode {

class Recovery {
 public:
  virtual ~Recovery() = default;
  // Keeps the world as it is now (at the start and after each action). An
  // error that lost() recognises sends the engine back to its last
  // checkpoint; any other ends the run.
  virtual plr::Status checkpoint() = 0;
  // Whether `error` (of the backend, or of checkpoint()) means the world went
  // away and may come back.
  virtual bool lost(const plr::Error& error) const = 0;
  // Waits for the world and brings it back to the last checkpoint; an error
  // ends the run.
  virtual plr::Status restore() = 0;
};

}  // namespace plr::episode
