#include "plr/sim/shipped_files.hpp"

#include <dlfcn.h>

#include <algorithm>
#include <cstdlib>
#include <string>
#include <vector>

namespace plr::sim {

plr::Expected<std::filesystem::path> shipped_file(std::string_view relative) {
  namespace fs = std::filesystem;
  std::vector<fs::path> roots;
  if (const char* dir = std::getenv("PLR_DATA_DIR"); dir != nullptr && *dir != '\0')
    roots.emplace_back(dir);
  // Next to the library or executable this function was linked into (a
  // plug-in of the tree), then next to the running program (`plr`, a test
  // runner: what an out-of-tree plug-in is loaded by).
  auto near = [&](const fs::path& binary) {
    std::error_code ec;
    const fs::path here = fs::canonical(binary, ec).parent_path();
    if (ec) return;
    for (const fs::path& root :
         {here.parent_path() / "share" / "plr", here.parent_path().parent_path() / "share" / "plr"})
      if (std::find(roots.begin(), roots.end(), root) == roots.end()) roots.push_back(root);
  };
  Dl_info info{};
  if (dladdr(reinterpret_cast<void*>(&shipped_file), &info) != 0 && info.dli_fname != nullptr)
    near(info.dli_fname);
  near("/proc/self/exe");
  std::string looked;
  for (const fs::path& root : roots) {
    const fs::path file = root / relative;
    std::error_code ec;
    if (fs::is_regular_file(file, ec)) return file;
    looked += (looked.empty() ? "" : ", ") + root.string();
  }
  return plr::make_error(PLR_ERR_INVALID,
                         "shipped file '" + std::string(relative) + "' not found (looked in " +
                             (looked.empty() ? "nowhere" : looked) + "; set PLR_DATA_DIR)");
}

}  // namespace plr::sim
