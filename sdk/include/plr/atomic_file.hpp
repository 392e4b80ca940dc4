// Replacing a file so that a crash or a reader at any moment sees the old or
// the new content, never a part of either: the one way PLR writes a file.
#pragma once

#include <plr/expected.hpp>

#include <string>
#include <string_view>

namespace plr {

// Writes `content` to a temporary file in `path`'s folder, fsyncs it,
// renames it over `path` and fsyncs the folder. The file gets mode 0644; on
// failure `path` is untouched, the temporary file is gone and
// the error names the path and the cause. Link plr::sdk_support.
Status write_file_atomically(const std::string& path, std::string_view content);

}  // namespace plr
