#include "plugin_loader.hpp"

#include <dlfcn.h>
#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <optional>

namespace plr::kernel {

namespace fs = std::filesystem;

PluginLibrary::PluginLibrary(void* handle, const plr_plugin_descriptor* descriptor,
                             std::string path)
    : handle_(handle), descriptor_(descriptor), path_(std::move(path)) {}

PluginLibrary::~PluginLibrary() {
  if (handle_ != nullptr) dlclose(handle_);
}

const plr_interface* PluginLibrary::declared_interface() const {
  auto fn = reinterpret_cast<plr_interface_fn>(dlsym(handle_, PLR_INTERFACE_SYMBOL));
  return fn != nullptr ? fn() : nullptr;
}

PluginLoader::PluginLoader(std::vector<std::string> search_paths)
    : paths_(std::move(search_paths)) {}

namespace {

std::string join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& item : items) out += (out.empty() ? "" : ", ") + item;
  return out;
}

Error refuse(const std::string& file, const std::string& cause, plr_status code = PLR_ERR_INVALID) {
  return make_error(code, file + ": refused: " + cause);
}

// Anyone but root and us who can write the file, or replace it or any folder
// on its way from the root, could run code inside the kernel: each must be
// owned by root or us and writable by no one else, as sudo and ssh check
// theirs. A sticky folder (/tmp) is fine: others cannot rename what is ours.
std::optional<std::string> unsafe(const fs::path& path, const std::string& what) {
  struct stat st {};
  if (lstat(path.c_str(), &st) != 0)
    return "cannot check " + what + " " + path.string() + ": " + std::strerror(errno);
  const uid_t me = geteuid();
  if (st.st_uid != 0 && st.st_uid != me)
    return what + " " + path.string() + " is owned by uid " + std::to_string(st.st_uid) +
           " (only root or uid " + std::to_string(me) + " may own it)";
  if (S_ISLNK(st.st_mode)) return std::nullopt;  // its folder is checked; links cannot change
  const bool sticky_dir = S_ISDIR(st.st_mode) && (st.st_mode & S_ISVTX) != 0;
  if ((st.st_mode & (S_IWGRP | S_IWOTH)) == 0 || sticky_dir) return std::nullopt;
  char mode[8];
  std::snprintf(mode, sizeof mode, "%04o", static_cast<unsigned>(st.st_mode & 07777));
  return what + " " + path.string() + " is group- or world-writable (mode " + mode + ")";
}

// The folder and every folder above it up to the root.
std::optional<std::string> unsafe_folders(fs::path dir) {
  for (;;) {
    if (auto problem = unsafe(dir, "folder")) return problem;
    if (dir == dir.root_path() || !dir.has_parent_path()) return std::nullopt;
    dir = dir.parent_path();
  }
}

// Closes a library that failed its checks.
struct DlCloser {
  void operator()(void* handle) const { dlclose(handle); }
};

}  // namespace

Expected<std::shared_ptr<PluginLibrary>> PluginLoader::load(const std::string& name) {
  const std::string file_name = name + ".so";
  if (name.empty()) return refuse(file_name, "empty plug-in name");
  if (name.find('/') != std::string::npos || name.find("..") != std::string::npos) {
    return refuse(file_name,
                  "a plug-in name must not contain '/' or '..', which would load from outside "
                  "the search paths (" +
                      join(paths_) + ")");
  }

  fs::path found;
  for (const auto& dir : paths_) {
    std::error_code ec;
    if (fs::exists(fs::path(dir) / file_name, ec)) {
      found = fs::path(dir) / file_name;
      break;
    }
  }
  if (found.empty()) {
    // A config naming a plug-in that is not there is bad input, in every command.
    return make_error(PLR_ERR_INVALID, file_name + ": not found in the plug-in search paths: " +
                                           (paths_.empty() ? "(none configured)" : join(paths_)));
  }
  const std::string file = found.lexically_normal().string();
  std::error_code ec;
  const fs::path real = fs::canonical(found, ec);
  if (ec) return refuse(file, "cannot resolve the path: " + ec.message());

  std::lock_guard lock(mutex_);
  std::erase_if(loaded_, [](const Loaded& l) { return l.library.expired(); });
  for (const auto& l : loaded_) {
    // Its last user may drop a library at any time, outside this lock: only
    // a library still alive now is shared, or makes another file a duplicate.
    auto library = l.library.lock();
    if (!library) continue;
    if (l.file == real.string()) return library;
    if (l.name == name)
      return refuse(file, "duplicate: plug-in '" + name + "' is already loaded from " + l.file);
  }

  if (!fs::is_regular_file(real, ec)) return refuse(file, "not a regular file");
  // The folders as configured and the real ones, which differ where a link is on the way.
  if (auto problem = unsafe(real, "file")) return refuse(file, *problem);
  for (const auto& dir : {fs::absolute(found).lexically_normal().parent_path(), real.parent_path()})
    if (auto problem = unsafe_folders(dir)) return refuse(file, *problem);

  dlerror();  // clears an earlier error, so the message below is this call's
  std::unique_ptr<void, DlCloser> handle(dlopen(real.c_str(), RTLD_NOW | RTLD_LOCAL));
  if (!handle) {
    const char* why = dlerror();
    return refuse(file, std::string("dlopen failed: ") + (why != nullptr ? why : "unknown error"));
  }
  auto entry = reinterpret_cast<plr_plugin_entry_fn>(dlsym(handle.get(), PLR_ENTRY_SYMBOL));
  if (entry == nullptr) {
    return refuse(file, std::string("no entry point '") + PLR_ENTRY_SYMBOL +
                            "' (not a PLR plug-in, or built without PLR_PLUGIN)");
  }
  const plr_plugin_descriptor* d = entry();
  if (d == nullptr) return refuse(file, "the entry point returned no descriptor");
  // Only the major is certain to be where this kernel expects it; nothing
  // else in the descriptor may be read before this check.
  if (d->abi_major != PLR_ABI_MAJOR) {
    return refuse(file, "wrong plug-in ABI major: found " + std::to_string(d->abi_major) +
                            ", expected " + std::to_string(PLR_ABI_MAJOR) +
                            " (rebuild the plug-in against this SDK)");
  }
  if (d->abi_minor > PLR_ABI_MINOR) {
    return refuse(file, "needs plug-in ABI " + std::to_string(d->abi_major) + "." +
                            std::to_string(d->abi_minor) + ", this kernel provides " +
                            std::to_string(PLR_ABI_MAJOR) + "." + std::to_string(PLR_ABI_MINOR));
  }
  if (d->name == nullptr || name != d->name) {
    return refuse(file, std::string("the descriptor names the plug-in '") +
                            (d->name != nullptr ? d->name : "") + "', but the file is " +
                            file_name + " (they must match)");
  }
  const plr_node_api& api = d->node;
  if (api.create == nullptr || api.destroy == nullptr || api.configure == nullptr ||
      api.activate == nullptr || api.deactivate == nullptr || api.cleanup == nullptr)
    return refuse(file, "the descriptor lacks node functions");

  auto library = std::make_shared<PluginLibrary>(handle.release(), d, file);
  loaded_.push_back({name, real.string(), library});
  return library;
}

std::vector<PluginInfo> PluginLoader::list(std::vector<std::string>* errors) {
  auto report = [&](std::string message) {
    if (errors != nullptr) errors->push_back(std::move(message));
  };
  std::vector<PluginInfo> out;
  std::vector<std::string> seen;
  for (const auto& dir : paths_) {
    std::vector<fs::path> files;
    std::error_code ec;
    for (fs::directory_iterator it(dir, ec); !ec && it != fs::directory_iterator();
         it.increment(ec)) {
      if (it->path().extension() == ".so") files.push_back(it->path());
    }
    if (ec) {
      report(dir + ": cannot list plug-ins: " + ec.message());
      continue;
    }
    std::sort(files.begin(), files.end());
    for (const auto& f : files) {
      const std::string name = f.stem().string();
      if (std::find(seen.begin(), seen.end(), name) != seen.end()) {
        report(f.string() + ": ignored: shadowed by " + name + ".so in an earlier search path");
        continue;
      }
      seen.push_back(name);
      auto library = load(name);  // dropped at the end of this iteration, unloading it again
      if (!library) {
        report(library.error().message);
        continue;
      }
      const plr_plugin_descriptor& d = (*library)->descriptor();
      out.push_back({d.name, d.version != nullptr ? d.version : "", plr_kind_name(d.kind),
                     d.description != nullptr ? d.description : "", (*library)->path(), d.abi_major,
                     d.abi_minor});
    }
  }
  return out;
}

std::string default_plugin_path() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  if (ec) return {};
  const fs::path dir = exe.parent_path() / ".." / "lib" / "plugins";
  const fs::path canonical = fs::weakly_canonical(dir, ec);
  return (ec ? dir.lexically_normal() : canonical).string();
}

}  // namespace plr::kernel
