// A minimal expected<T, E> (g++ 12 has no std::expected). No exceptions, no
// heap: the data path of the shared-memory transport returns these.
#pragma once

#include <cstdlib>
#include <type_traits>
#include <utility>
#include <variant>

namespace plr::shm {

template <class E>
struct Unexpected {
  E error;
};

template <class E>
constexpr Unexpected<E> unexpected(E e) noexcept {
  return Unexpected<E>{e};
}

// Accessing value() of an error (or error() of a value) is a broken invariant:
// abort rather than throw.
template <class T, class E>
class [[nodiscard]] Expected {
 public:
  template <class U = T, class = std::enable_if_t<std::is_constructible_v<T, U&&>>>
  Expected(U&& v) noexcept : v_(std::in_place_index<0>, std::forward<U>(v)) {}
  Expected(Unexpected<E> e) noexcept : v_(std::in_place_index<1>, e.error) {}

  bool has_value() const noexcept { return v_.index() == 0; }
  explicit operator bool() const noexcept { return has_value(); }

  T& value() & noexcept { return *checked(std::get_if<0>(&v_)); }
  const T& value() const& noexcept { return *checked(std::get_if<0>(&v_)); }
  T&& value() && noexcept { return std::move(*checked(std::get_if<0>(&v_))); }
  E error() const noexcept { return *checked(std::get_if<1>(&v_)); }

  T& operator*() & noexcept { return value(); }
  const T& operator*() const& noexcept { return value(); }
  T&& operator*() && noexcept { return std::move(*this).value(); }
  T* operator->() noexcept { return &value(); }
  const T* operator->() const noexcept { return &value(); }

 private:
  template <class P>
  static P* checked(P* p) noexcept {
    if (p == nullptr) std::abort();
    return p;
  }
  std::variant<T, E> v_;
};

template <class E>
class [[nodiscard]] Expected<void, E> {
 public:
  Expected() noexcept = default;
  Expected(Unexpected<E> e) noexcept : ok_(false), e_(e.error) {}

  bool has_value() const noexcept { return ok_; }
  explicit operator bool() const noexcept { return ok_; }
  E error() const noexcept {
    if (ok_) std::abort();
    return e_;
  }

 private:
  bool ok_ = true;
  E e_{};
};

}  // namespace plr::shm
