// A file compiled into a binary (sdk/cmake/embed_files.cmake): schemas the
// recorder embeds in a recording, the pages a web monitor serves.
#pragma once

#include <cstddef>
#include <string_view>

namespace plr {

struct EmbeddedFile {
  const char* name;  // file name, without directories
  const unsigned char* data;
  std::size_t size;

  std::string_view bytes() const { return {reinterpret_cast<const char*>(data), size}; }
};

}  // namespace plr
