// The offline files (the strategy library, the chooser's model and data
// set): a FlatBuffers buffer in the SDK's frame (plr/frame.hpp: size,
// payload, CRC-32), written with plr::frame() and read back here.
#pragma once

#include <plr/expected.hpp>
#include <plr/frame.hpp>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace plr::sim {

// FlatBuffers reads 8-byte scalars in place, and the body follows a 4-byte
// size: a body off an 8-byte boundary is copied into `aligned`, and `data`
// points there (so a FramedBody moves but does not copy).
struct FramedBody {
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;
  std::vector<std::uint64_t> aligned;

  FramedBody(const std::uint8_t* body, std::size_t n);
  FramedBody(FramedBody&&) noexcept = default;
  FramedBody& operator=(FramedBody&&) noexcept = default;
  FramedBody(const FramedBody&) = delete;
  FramedBody& operator=(const FramedBody&) = delete;
};

// PLR_ERR_INVALID, "<where>: <what>": the one-line form of a bad file's error.
plr::Error invalid_at(const std::string& where, const std::string& what);

// The body of a framed buffer, checked against `max_body` bytes and the
// CRC. `what` names the content in errors ("a library has at least 8
// bytes"); errors are one line, "<origin>: <cause>", with byte offsets.
plr::Expected<FramedBody> unframe(const std::uint8_t* data, std::size_t size, std::size_t max_body,
                                  const std::string& what, const std::string& origin);

// The whole file, refused when larger than `max_bytes`.
plr::Expected<std::vector<std::uint8_t>> read_bounded_file(const std::filesystem::path& file,
                                                           std::size_t max_bytes);

// plr::frame()'s bytes written atomically (plr::write_file_atomically).
plr::Status save_framed(const std::vector<std::uint8_t>& framed, const std::filesystem::path& file);

}  // namespace plr::sim
