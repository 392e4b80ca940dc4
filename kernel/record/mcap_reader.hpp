// Reads an MCAP file's data section in order: schemas, channels and
// messages, also inside chunks (uncompressed or zstd). Every size is checked
// against what is left and against the limits before it is used; an error
// is one line, "<origin>: offset N: <what>".
#pragma once

#include "mcap_format.hpp"

#include <plr/expected.hpp>

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <string_view>

namespace plr::kernel::mcap {

struct ReaderLimits {
  std::uint64_t max_chunk_bytes = 256u << 20;  // uncompressed, per chunk
};

struct SchemaRecord {
  std::uint16_t id = 0;
  std::string name, encoding, data;
};

struct ChannelRecord {
  std::uint16_t id = 0;
  std::uint16_t schema_id = 0;
  std::string topic, message_encoding;
};

struct MessageRecord {
  const ChannelRecord* channel = nullptr;
  std::uint32_t sequence = 0;
  std::uint64_t log_time = 0, publish_time = 0;
  std::string_view data;  // valid during the callback
};

struct Contents {
  std::map<std::uint16_t, SchemaRecord> schemas;
  std::map<std::uint16_t, ChannelRecord> channels;
};

// Calls `on_message` for each message in file order; `contents` holds the
// schemas and channels seen so far. A message's channel must come first.
Status read(std::string_view file, const std::string& origin,
            const std::function<void(const MessageRecord&)>& on_message, Contents& contents,
            const ReaderLimits& limits = {});

// The whole file from disk (bounded by `max_file_bytes`).
Expected<std::string> load(const std::string& path, std::uint64_t max_file_bytes = 4ull << 30);

}  // namespace plr::kernel::mcap
