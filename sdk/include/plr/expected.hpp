// PLR's one result type: a value or the reason there is none
// (docs/errors.md). Errors are values: nothing throws across the bus.
//
//   Expected<Plan> plan(const Query& q);        // E = plr::Error: code + one-line text
//   Status save();                              // Expected<void>
//   Expected<Slot, shm::Error> loan();          // E an enum: no heap, for the data path
//
// Reading the wrong alternative (value() of an error, error() of a value) is
// a bug in the caller: it aborts with a message instead of throwing.
#pragma once

#include <plr/plugin_abi.h>

#include <cstdio>
#include <cstdlib>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>

namespace plr {

struct Error {
  plr_status code = PLR_ERR_INTERNAL;
  std::string message;
};

inline Error make_error(plr_status code, std::string message) {
  return Error{code, std::move(message)};
}

namespace detail {

template <class E>
[[noreturn]] void bad_access(const char* what, const E* error) noexcept {
  if constexpr (std::is_same_v<E, Error>) {
    if (error != nullptr) {
      std::fprintf(stderr, "plr::Expected: %s (the error: %s)\n", what, error->message.c_str());
      std::abort();
    }
  }
  std::fprintf(stderr, "plr::Expected: %s\n", what);
  std::abort();
}

}  // namespace detail

template <class T, class E = Error>
class [[nodiscard]] Expected {
  static_assert(!std::is_same_v<std::remove_cv_t<T>, E>, "a value and an error of one type");

 public:
  // Implicit from a value or an error, so a function returns either as is.
  // (C++17 spelling: code built against Simbody's headers includes this.)
  template <class U = T,
            std::enable_if_t<
                std::is_constructible_v<T, U&&> &&
                    !std::is_same_v<std::remove_cv_t<std::remove_reference_t<U>>, Expected> &&
                    !std::is_same_v<std::remove_cv_t<std::remove_reference_t<U>>, E>,
                int> = 0>
  Expected(U&& value) : v_(std::in_place_index<0>, std::forward<U>(value)) {}  // NOLINT
  Expected(E error) : v_(std::in_place_index<1>, std::move(error)) {}          // NOLINT

  bool has_value() const noexcept { return v_.index() == 0; }
  explicit operator bool() const noexcept { return has_value(); }

  T& value() & noexcept { return *checked(std::get_if<0>(&v_)); }
  const T& value() const& noexcept { return *checked(std::get_if<0>(&v_)); }
  T&& value() && noexcept { return std::move(*checked(std::get_if<0>(&v_))); }
  const E& error() const noexcept {
    if (has_value()) detail::bad_access<E>("error() of a value", nullptr);
    return *std::get_if<1>(&v_);
  }

  T& operator*() & noexcept { return value(); }
  const T& operator*() const& noexcept { return value(); }
  T&& operator*() && noexcept { return std::move(*this).value(); }
  T* operator->() noexcept { return &value(); }
  const T* operator->() const noexcept { return &value(); }

 private:
  template <class P>
  P* checked(P* p) const noexcept {
    if (p == nullptr) detail::bad_access("value() of an error", std::get_if<1>(&v_));
    return p;
  }

  std::variant<T, E> v_;
};

template <class E>
class [[nodiscard]] Expected<void, E> {
 public:
  Expected() noexcept = default;
  Expected(E error) : error_(std::move(error)), ok_(false) {}  // NOLINT

  bool has_value() const noexcept { return ok_; }
  explicit operator bool() const noexcept { return ok_; }
  const E& error() const noexcept {
    if (ok_) detail::bad_access<E>("error() of a success", nullptr);
    return error_;
  }

 private:
  E error_{};
  bool ok_ = true;
};

using Status = Expected<void>;

}  // namespace plr
