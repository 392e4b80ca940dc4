// The one frame PLR puts around a payload, in files and on pipes: a 4-byte
// little-endian size N, N bytes of payload, a 4-byte CRC-32 (zlib's) of
// those N bytes. The size tells a record cut short from a whole one, the
// CRC an altered one. Link plr::sdk_support.
#pragma once

#include <plr/expected.hpp>

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace plr {

inline constexpr std::size_t kFrameOverhead = 8;

std::uint32_t crc32(const std::uint8_t* data, std::size_t size);

std::vector<std::uint8_t> frame(const std::uint8_t* payload, std::size_t size);

// The payload of exactly one frame filling `size` bytes, checked against
// `max_payload` and the CRC. Errors are one line, "<origin>: <cause>", with
// byte offsets.
struct Unframed {
  const std::uint8_t* data = nullptr;
  std::size_t size = 0;
};
plr::Expected<Unframed> unframe(const std::uint8_t* data, std::size_t size, std::size_t max_payload,
                                const std::string& origin);

// Frames one at a time from a stream whose bytes come in pieces (a pipe).
class FrameReader {
 public:
  FrameReader(std::size_t max_payload, std::string origin)
      : max_payload_(max_payload), origin_(std::move(origin)) {}
  void feed(const std::uint8_t* data, std::size_t size);
  // The next whole frame's payload; nullopt until one has come in; an error
  // for a frame over the limit or failing its CRC (the stream is lost then).
  plr::Expected<std::optional<std::vector<std::uint8_t>>> next();
  // Reads from `fd` until a whole frame is in; nullopt at the end of input.
  plr::Expected<std::optional<std::vector<std::uint8_t>>> read(int fd);
  // Bytes received that are not yet a whole frame.
  std::size_t pending() const { return buffer_.size(); }

 private:
  std::size_t max_payload_;
  std::string origin_;
  std::vector<std::uint8_t> buffer_;
};

// Writes all of `bytes` to `fd`, retrying interrupted and partial writes;
// false when the reader is gone or the write fails.
bool write_all(int fd, const std::uint8_t* data, std::size_t size);
inline bool write_all(int fd, const std::vector<std::uint8_t>& bytes) {
  return write_all(fd, bytes.data(), bytes.size());
}

}  // namespace plr
