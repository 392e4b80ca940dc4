// Loads plug-in libraries, only from the configured search paths, and checks
// them before any of their code beyond the entry point runs.
#pragma once

#include <plr/plugin_abi.h>
#include <plr/expected.hpp>

#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace plr::kernel {

// An open plug-in library; closing it (destructor) unloads the code, so it
// must outlive every node created from it.
class PluginLibrary {
 public:
  PluginLibrary(void* handle, const plr_plugin_descriptor* descriptor, std::string path);
  ~PluginLibrary();
  PluginLibrary(const PluginLibrary&) = delete;
  PluginLibrary& operator=(const PluginLibrary&) = delete;

  const plr_plugin_descriptor& descriptor() const { return *descriptor_; }
  const std::string& path() const { return path_; }
  std::string name() const { return descriptor_->name; }
  // What its nodes advertise and provide (plr/interface.hpp); nullptr when
  // the plug-in declares nothing.
  const plr_interface* declared_interface() const;

 private:
  void* handle_;
  const plr_plugin_descriptor* descriptor_;
  std::string path_;
};

struct PluginInfo {
  std::string name;
  std::string version;
  std::string kind;
  std::string description;
  std::string path;
  unsigned abi_major = 0;
  unsigned abi_minor = 0;
};

class PluginLoader {
 public:
  explicit PluginLoader(std::vector<std::string> search_paths);

  // Loads `<path>/<name>.so` from the first search path that has it. Errors,
  // one line each, naming the file and the cause: not found in the search
  // paths (listing them), outside the search paths (for a name with a '/'),
  // group- or world-writable file or folder, dlopen failure (with dlerror),
  // missing entry point, wrong ABI major, descriptor name differing from the
  // file name, a name already loaded from another file (duplicate).
  Expected<std::shared_ptr<PluginLibrary>> load(const std::string& name);

  // Every loadable plug-in in the search paths (broken ones are skipped and
  // reported through `errors`).
  std::vector<PluginInfo> list(std::vector<std::string>* errors = nullptr);

  const std::vector<std::string>& search_paths() const { return paths_; }

 private:
  // A library handed out earlier: reused while alive (hot swap loads the same
  // file repeatedly), and checked against for duplicate names.
  struct Loaded {
    std::string name;
    std::string file;  // canonical path
    std::weak_ptr<PluginLibrary> library;
  };
  std::vector<std::string> paths_;
  std::mutex mutex_;  // guards loaded_: swaps of different nodes may load at once
  std::vector<Loaded> loaded_;
};

// The kernel's default search path: <folder of the plr binary>/../lib/plugins.
std::string default_plugin_path();

}  // namespace plr::kernel
