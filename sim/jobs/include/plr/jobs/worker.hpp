// A worker's side of ProcessRunner (process_runner.hpp): jobs come in
// on stdin, each a JobRequest in a frame (plr/frame.hpp), and each one's
// result goes out on stdout as a JobReply in a frame, in order. Whatever the
// program itself prints goes to stderr: stdout carries nothing but frames.
#pragma once

#include <filesystem>

#include "plr/jobs/kinds.hpp"

namespace plr::jobs {

// Serves jobs until stdin ends (returns 0) or a frame is bad (returns 2,
// the cause on stderr). Call it from main() after registering the kinds.
// With `log_dir`, what a job prints goes to <log_dir>/<key>.log.
int serve_jobs(const Kinds& kinds, const std::filesystem::path& log_dir = {});

}  // namespace plr::jobs
