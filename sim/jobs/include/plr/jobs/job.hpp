// A job: a kind (which handler runs it), a key (its result's name in a
// store) and input bytes. Its result: output bytes or an error. docs/jobs.md.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace plr::jobs {

using Bytes = std::vector<std::uint8_t>;

// A job's input or output, and a key, are refused past these.
inline constexpr std::size_t kMaxBytes = std::size_t{1} << 28;
inline constexpr std::size_t kMaxKey = 128;

struct Job {
  std::string kind;
  std::string key;
  Bytes input;
};

struct Result {
  std::string key;
  bool ok = false;
  Bytes output;       // when ok
  std::string error;  // when not
  double wall_s = 0.0;
  std::uint32_t attempts = 0;
  bool stored = false;  // read from the store, not run now
};

// A key names a file: 1..kMaxKey of [A-Za-z0-9._-], not starting with '.'.
bool valid_key(std::string_view key);

Bytes to_bytes(std::string_view text);
std::string to_text(const Bytes& bytes);

}  // namespace plr::jobs
