// The MCAP container format (https://mcap.dev/spec, major version 0), as
// much of it as PLR's recorder writes and its reader needs: little-endian
// records <opcode:u8><length:u64><content>, framed by magic bytes.
#pragma once

#include <cstdint>
#include <string_view>

namespace plr::kernel::mcap {

inline constexpr std::string_view kMagic{"\x89MCAP0\r\n", 8};
inline constexpr std::string_view kProfile = "";  // no ROS profile: plain FlatBuffers
inline constexpr std::string_view kEncoding = "flatbuffer";

enum class Op : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kAttachment = 0x09,
  kAttachmentIndex = 0x0A,
  kStatistics = 0x0B,
  kMetadata = 0x0C,
  kMetadataIndex = 0x0D,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

enum class Compression { kNone, kZstd, kLz4 };

}  // namespace plr::kernel::mcap
