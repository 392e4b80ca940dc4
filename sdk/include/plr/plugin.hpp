// Turns a Node subclass into the plug-in's C entry point:
//
//   PLR_PLUGIN(MyPlanner, "my_planner", "1.2.0", PLR_KIND_PLANNER, "what it does")
//
// Exceptions and C++ types stop here; only the C descriptor leaves the library.
#pragma once

#include <plr/plugin_abi.h>
#include <plr/node.hpp>

#include <cstdio>
#include <new>

namespace plr::detail {

inline plr_status write_error(const Status& s, char* err, std::size_t n) {
  if (s) return PLR_OK;
  if (err != nullptr && n > 0) std::snprintf(err, n, "%s", s.error().message.c_str());
  return s.error().code;
}

template <class T>
struct PluginTrampolines {
  static void* create(const plr_host_api* host) {
    try {
      return static_cast<Node*>(new T(host));
    } catch (...) {
      return nullptr;
    }
  }
  static void destroy(void* node) { delete static_cast<Node*>(node); }
  static plr_status configure(void* n, char* err, std::size_t sz) {
    return write_error(static_cast<Node*>(n)->configure(), err, sz);
  }
  static plr_status activate(void* n, char* err, std::size_t sz) {
    return write_error(static_cast<Node*>(n)->activate(), err, sz);
  }
  static plr_status deactivate(void* n, char* err, std::size_t sz) {
    return write_error(static_cast<Node*>(n)->deactivate(), err, sz);
  }
  static plr_status cleanup(void* n, char* err, std::size_t sz) {
    return write_error(static_cast<Node*>(n)->cleanup(), err, sz);
  }
};

}  // namespace plr::detail

#define PLR_PLUGIN(Class, Name, Version, Kind, Description)                                        \
  extern "C" __attribute__((visibility("default"))) const plr_plugin_descriptor* plr_plugin_entry( \
      void) {                                                                                      \
    using T = ::plr::detail::PluginTrampolines<Class>;                                             \
    static const plr_plugin_descriptor descriptor = {                                              \
        PLR_ABI_MAJOR,                                                                             \
        PLR_ABI_MINOR,                                                                             \
        Name,                                                                                      \
        Version,                                                                                   \
        Description,                                                                               \
        Kind,                                                                                      \
        {&T::create, &T::destroy, &T::configure, &T::activate, &T::deactivate, &T::cleanup}};      \
    return &descriptor;                                                                            \
  }
