// Crash-safe file replacement, for everything sim/ and its plug-ins write.
#pragma once

#include <filesystem>
#include <string>

namespace plr::sim {

// Temporary file, fsync, rename over `file`, fsync of the directory. Throws
// WorldFileError naming the file on failure.
void write_file_atomically(const std::filesystem::path& file, const std::string& content);

}  // namespace plr::sim
