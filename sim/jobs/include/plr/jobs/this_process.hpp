// What this process is: the program a task command starts with, and the
// command line a file records as how it was made.
#pragma once

#include <string>

namespace plr::jobs {

// This process's program, by absolute path.
std::string this_program();

// This process's command line, its arguments separated by spaces.
std::string command_line();

}  // namespace plr::jobs
