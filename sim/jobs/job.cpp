#include "plr/jobs/job.hpp"

#include <algorithm>

namespace plr::jobs {

bool valid_key(std::string_view key) {
  if (key.empty() || key.size() > kMaxKey || key.front() == '.') return false;
  return std::all_of(key.begin(), key.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
           c == '_' || c == '-';
  });
}

Bytes to_bytes(std::string_view text) {
  return Bytes(text.begin(), text.end());
}

std::string to_text(const Bytes& bytes) {
  return std::string(bytes.begin(), bytes.end());
}

}  // namespace plr::jobs
