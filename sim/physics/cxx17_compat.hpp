// Force-included into plr_sim_physics, the one target built as C++17
// (Simbody's headers do not compile as C++20): what the SDK's C++20 headers
// it includes (plr/expected.hpp) need from the C++20 standard library.
#pragma once

#include <type_traits>

#if __cplusplus < 202002L
namespace std {  // NOLINT(cert-dcl58-cpp): the C++20 names, as C++20 defines them
template <class T>
struct remove_cvref {
  using type = remove_cv_t<remove_reference_t<T>>;
};
template <class T>
using remove_cvref_t = typename remove_cvref<T>::type;
}  // namespace std
#endif
