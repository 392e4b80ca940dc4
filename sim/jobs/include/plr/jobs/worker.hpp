// A worker program's side of SpawnRunner (spawn_runner.hpp): jobs come in
// on stdin, each a JobRequest in a frame (plr/frame.hpp), and each one's
// result goes out on stdout as a JobReply in a frame, in order. Whatever the
// program itself prints goes to stderr: stdout carries nothing but frames.
#pragma once

#include "plr/jobs/kinds.hpp"

namespace plr::jobs {

// Serves jobs until stdin ends (returns 0) or a frame is bad (returns 2,
// the cause on stderr). Call it from main() after registering the kinds.
int serve_jobs(const Kinds& kinds);

}  // namespace plr::jobs
