#include "plr/frame.hpp"

#include <unistd.h>
#include <zlib.h>

#include <fmt/format.h>

#include <cerrno>
#include <cstring>
#include <limits>

namespace plr {

namespace {

std::uint32_t read_u32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | static_cast<std::uint32_t>(p[1]) << 8 |
         static_cast<std::uint32_t>(p[2]) << 16 | static_cast<std::uint32_t>(p[3]) << 24;
}

void write_u32(std::vector<std::uint8_t>& out, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

plr::Error invalid(const std::string& origin, const std::string& what) {
  return plr::make_error(PLR_ERR_INVALID, origin + ": " + what);
}

}  // namespace

std::uint32_t crc32(const std::uint8_t* data, std::size_t size) {
  uLong c = ::crc32(0L, Z_NULL, 0);
  // zlib takes at most a uInt per call.
  constexpr std::size_t kChunk = std::numeric_limits<uInt>::max();
  while (size > 0) {
    const std::size_t n = std::min(size, kChunk);
    c = ::crc32(c, data, static_cast<uInt>(n));
    data += n;
    size -= n;
  }
  return static_cast<std::uint32_t>(c);
}

std::vector<std::uint8_t> frame(const std::uint8_t* payload, std::size_t size) {
  std::vector<std::uint8_t> out;
  out.reserve(size + kFrameOverhead);
  write_u32(out, static_cast<std::uint32_t>(size));
  out.insert(out.end(), payload, payload + size);
  write_u32(out, crc32(payload, size));
  return out;
}

plr::Expected<Unframed> unframe(const std::uint8_t* data, std::size_t size, std::size_t max_payload,
                                const std::string& origin) {
  if (size < kFrameOverhead)
    return invalid(origin, fmt::format("truncated: {} bytes, a frame has at least 8", size));
  const std::size_t n = read_u32(data);
  if (n > max_payload)
    return invalid(origin,
                   fmt::format("bytes 0..4: size {} is over the limit of {}", n, max_payload));
  if (size < n + kFrameOverhead)
    return invalid(origin, fmt::format("truncated: {} of {} bytes", size, n + kFrameOverhead));
  if (size > n + kFrameOverhead)
    return invalid(origin, fmt::format("byte {}: {} bytes after the end of the frame",
                                       n + kFrameOverhead, size - n - kFrameOverhead));
  if (crc32(data + 4, n) != read_u32(data + 4 + n))
    return invalid(origin, fmt::format("bytes 4..{}: checksum mismatch (corrupt)", n + 4));
  return Unframed{data + 4, n};
}

void FrameReader::feed(const std::uint8_t* data, std::size_t size) {
  buffer_.insert(buffer_.end(), data, data + size);
}

plr::Expected<std::optional<std::vector<std::uint8_t>>> FrameReader::next() {
  if (buffer_.size() < 4) return std::optional<std::vector<std::uint8_t>>{};
  const std::size_t n = read_u32(buffer_.data());
  if (n > max_payload_)
    return invalid(origin_,
                   fmt::format("frame of {} bytes, over the limit of {}", n, max_payload_));
  if (buffer_.size() < n + kFrameOverhead) return std::optional<std::vector<std::uint8_t>>{};
  const std::uint8_t* payload = buffer_.data() + 4;
  if (crc32(payload, n) != read_u32(payload + n))
    return invalid(origin_, "frame: checksum mismatch (corrupt)");
  std::vector<std::uint8_t> out(payload, payload + n);
  buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<long>(n + kFrameOverhead));
  return std::optional<std::vector<std::uint8_t>>{std::move(out)};
}

plr::Expected<std::optional<std::vector<std::uint8_t>>> FrameReader::read(int fd) {
  while (true) {
    auto got = next();
    if (!got || *got) return got;
    std::uint8_t chunk[1 << 16];
    const ssize_t n = ::read(fd, chunk, sizeof chunk);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return invalid(origin_, std::strerror(errno));
    if (n == 0) {
      if (buffer_.empty()) return std::optional<std::vector<std::uint8_t>>{};
      return invalid(origin_, fmt::format("input ends inside a frame ({} bytes)", buffer_.size()));
    }
    feed(chunk, static_cast<std::size_t>(n));
  }
}

bool write_all(int fd, const std::uint8_t* data, std::size_t size) {
  while (size > 0) {
    const ssize_t n = ::write(fd, data, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    data += n;
    size -= static_cast<std::size_t>(n);
  }
  return true;
}

}  // namespace plr
