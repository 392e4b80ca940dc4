// Internal: crash-safe file replacement for strategy files.
#pragma once

#include <filesystem>
#include <string>

namespace plr::sim {

// Writes a temporary file next to `file`, fsyncs it, renames it over `file`
// and fsyncs the folder, so a reader sees the old or the new file, never half
// of one. Returns an empty string, or the cause of the failure.
std::string write_atomically(const std::filesystem::path& file, const std::string& content);

}  // namespace plr::sim
