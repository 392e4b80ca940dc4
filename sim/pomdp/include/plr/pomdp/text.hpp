// Tokens and numbers of the text read here: Cassandra's .pomdp files, the
// text inside POMDPX elements and policy trees all go through these.
#pragma once

#include <charconv>
#include <optional>
#include <string_view>
#include <system_error>
#include <type_traits>
#include <vector>

namespace plr::pomdp::text {

struct Token {
  std::string_view text;
  int line = 1;
  int column = 1;
};

struct TokenRules {
  bool colon_tokens = false;  // ':' is a token of its own (.pomdp)
  bool comments = false;      // '#' starts a comment to the end of the line (.pomdp)
};

// Splits at white space (space, tab, CR, LF, FF, VT), numbering lines from
// `line` and columns from 1.
std::vector<Token> tokenize(std::string_view text, TokenRules rules = {}, int line = 1);
// The token texts alone.
std::vector<std::string_view> words(std::string_view text);

// A finite number spelled by the whole of `s` (a leading '+' allowed).
std::optional<double> to_number(std::string_view s);

// An integer spelled by the whole of `s`, within T's range.
template <class T>
std::optional<T> to_integer(std::string_view s) {
  static_assert(std::is_integral_v<T>);
  T v{};
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), v);
  if (ec != std::errc() || ptr != s.data() + s.size()) return std::nullopt;
  return v;
}

// A non-negative integer spelled by the whole of `s`.
std::optional<long> to_index(std::string_view s);

}  // namespace plr::pomdp::text
