#include "plr/actions/fingerprint.hpp"

#include <plr/frame.hpp>

#include <fmt/format.h>

#include <fstream>
#include <iterator>
#include <vector>

#include "plr/sim/shipped_files.hpp"

namespace plr::actions {

plr::Expected<std::string> action_model_fingerprint() {
  std::vector<std::uint8_t> bytes;
  for (const char* name : {"robots/unloader.urdf", "robots/unloader_lattice.yaml"}) {
    auto file = sim::shipped_file(name);
    if (!file) return file.error();
    std::ifstream in(*file, std::ios::binary);
    if (!in) return plr::make_error(PLR_ERR_UNAVAILABLE, file->string() + ": cannot read");
    bytes.insert(bytes.end(), std::istreambuf_iterator<char>(in), {});
  }
  return fmt::format("v{}-{:08x}", kActionModelVersion, plr::crc32(bytes.data(), bytes.size()));
}

}  // namespace plr::actions
