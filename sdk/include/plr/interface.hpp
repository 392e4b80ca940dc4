// Declares what a plug-in's nodes advertise and provide, so that the kernel
// can size a run's shared memory (and print it in `plr validate`) before any
// node starts:
//
//   PLR_INTERFACE(plr::topic<msg::WorldState>("world"),
//                 plr::service<msg::ObserveRequest, msg::WorldState>("sim/observe"))
//
// Each message type's bound (the `max_bytes` attribute of its schema) sizes
// the slots; a topic or service left out gets no room counted for it. A
// plug-in that offers nothing on the bus says so with `PLR_INTERFACE()`.
// The conformance suite checks the declaration against what the node does.
#pragma once

#include <plr/plugin_abi.h>

#include <cstddef>

namespace plr {

template <class T>
constexpr plr_port topic(const char* name) {
  return {PLR_PORT_TOPIC, name, T::GetFullyQualifiedName(), nullptr};
}

template <class Request, class Reply>
constexpr plr_port service(const char* name) {
  return {PLR_PORT_SERVICE, name, Request::GetFullyQualifiedName(), Reply::GetFullyQualifiedName()};
}

}  // namespace plr

#define PLR_INTERFACE(...)                                                                     \
  extern "C" __attribute__((visibility("default"))) const plr_interface* plr_plugin_interface( \
      void) {                                                                                  \
    /* One value-initialised port at the end, so that an empty list compiles. */               \
    static const plr_port ports[] = {__VA_ARGS__ __VA_OPT__(, ) plr_port{}};                   \
    static const plr_interface declared = {sizeof(ports) / sizeof(ports[0]) - 1, ports};       \
    return &declared;                                                                          \
  }
