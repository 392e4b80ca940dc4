// What runs a job: one handler per kind, input bytes to output bytes. A
// program registers the kinds it serves before it runs jobs; a child
// process forked to run a job inherits them.
#pragma once

#include <plr/expected.hpp>

#include <functional>
#include <map>
#include <string>

#include "plr/jobs/job.hpp"

namespace plr::jobs {

using Handler = std::function<plr::Expected<Bytes>(const Bytes& input)>;

class Kinds {
 public:
  void add(const std::string& kind, Handler handler);
  bool has(const std::string& kind) const { return handlers_.count(kind) > 0; }
  // Runs `job` with its kind's handler, timed; an unknown kind, a handler's
  // error or exception, or an output over kMaxBytes is a result that is
  // not ok. attempts is 1.
  Result run(const Job& job) const;

 private:
  std::map<std::string, Handler> handlers_;
};

}  // namespace plr::jobs
