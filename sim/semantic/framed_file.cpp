#include "plr/sim/framed_file.hpp"

#include <plr/atomic_file.hpp>
#include <plr/frame.hpp>

#include <fmt/format.h>

#include <cstring>
#include <fstream>
#include <string_view>

namespace plr::sim {

plr::Error invalid_at(const std::string& where, const std::string& what) {
  return plr::make_error(PLR_ERR_INVALID, where + ": " + what);
}

FramedBody::FramedBody(const std::uint8_t* body, std::size_t n) : data(body), size(n) {
  if (n == 0 || reinterpret_cast<std::uintptr_t>(body) % alignof(std::uint64_t) == 0) return;
  aligned.resize((n + sizeof(std::uint64_t) - 1) / sizeof(std::uint64_t));
  std::memcpy(aligned.data(), body, n);
  data = reinterpret_cast<const std::uint8_t*>(aligned.data());
}

plr::Expected<FramedBody> unframe(const std::uint8_t* data, std::size_t size, std::size_t max_body,
                                  const std::string& what, const std::string& origin) {
  if (size < 8)
    return invalid_at(origin, fmt::format("truncated: {} bytes, {} has at least 8", size, what));
  auto payload = plr::unframe(data, size, max_body, origin);
  if (!payload) return payload.error();
  const std::uint8_t* fb = payload->data;
  const std::size_t body = payload->size;
  // Every framed body is a FlatBuffers buffer: the identifier test that
  // follows reads its bytes 4..8.
  if (body < 8)
    return invalid_at(origin,
                      fmt::format("bytes 4..{}: {} bytes, too short for {}", body + 4, body, what));
  return FramedBody{fb, body};
}

plr::Expected<std::vector<std::uint8_t>> read_bounded_file(const std::filesystem::path& file,
                                                           std::size_t max_bytes) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(file, ec);
  if (ec) return plr::make_error(PLR_ERR_INVALID, file.string() + ": " + ec.message());
  if (size > max_bytes)
    return invalid_at(file.string(),
                      fmt::format("{} bytes, over the limit of {}", size, max_bytes));
  std::ifstream in(file, std::ios::binary);
  std::vector<std::uint8_t> bytes(static_cast<std::size_t>(size));
  if (!in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(size)))
    return plr::make_error(PLR_ERR_INVALID, file.string() + ": cannot read");
  return bytes;
}

plr::Status save_framed(const std::vector<std::uint8_t>& framed,
                        const std::filesystem::path& file) {
  return plr::write_file_atomically(
      file.string(), std::string_view(reinterpret_cast<const char*>(framed.data()), framed.size()));
}

}  // namespace plr::sim
