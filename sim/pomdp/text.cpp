#include "plr/pomdp/text.hpp"

#include <cmath>

namespace plr::pomdp::text {
namespace {

bool is_space(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' || c == '\v';
}

}  // namespace

std::vector<Token> tokenize(std::string_view text, TokenRules rules, int line) {
  std::vector<Token> out;
  int column = 1;
  std::size_t i = 0;
  const auto advance = [&](std::size_t n) {
    for (std::size_t k = 0; k < n; ++k, ++i) {
      if (text[i] == '\n') {
        ++line;
        column = 1;
      } else {
        ++column;
      }
    }
  };
  const auto ends_token = [&rules](char c) {
    return is_space(c) || (rules.colon_tokens && c == ':') || (rules.comments && c == '#');
  };
  while (i < text.size()) {
    const char c = text[i];
    if (rules.comments && c == '#') {
      while (i < text.size() && text[i] != '\n') advance(1);
    } else if (is_space(c)) {
      advance(1);
    } else if (rules.colon_tokens && c == ':') {
      out.push_back({text.substr(i, 1), line, column});
      advance(1);
    } else {
      std::size_t j = i;
      while (j < text.size() && !ends_token(text[j])) ++j;
      out.push_back({text.substr(i, j - i), line, column});
      advance(j - i);
    }
  }
  return out;
}

std::vector<std::string_view> words(std::string_view text) {
  std::vector<std::string_view> out;
  for (const Token& t : tokenize(text)) out.push_back(t.text);
  return out;
}

std::optional<double> to_number(std::string_view s) {
  double v = 0.0;
  const char* first = s.data();
  if (!s.empty() && s[0] == '+') {
    ++first;
    if (first != s.data() + s.size() && *first == '-') return std::nullopt;
  }
  const auto [ptr, ec] = std::from_chars(first, s.data() + s.size(), v);
  if (ec != std::errc() || ptr != s.data() + s.size() || !std::isfinite(v)) return std::nullopt;
  return v;
}

std::optional<long> to_index(std::string_view s) {
  const auto v = to_integer<long>(s);
  if (!v || *v < 0) return std::nullopt;
  return v;
}

}  // namespace plr::pomdp::text
