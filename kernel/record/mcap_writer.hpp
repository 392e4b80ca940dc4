// Writes an MCAP file: FlatBuffers messages ("flatbuffer" encoding) with
// their binary schemas embedded, in zstd-compressed chunks, each followed by
// its message indexes; at the end a summary (schemas, channels, statistics,
// chunk indexes) and its offsets, so readers can seek. Written to
// "<path>.part" and renamed to `path` by finish(): a file at `path` is
// always complete.
#pragma once

#include "mcap_format.hpp"

#include <plr/expected.hpp>

#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace plr::kernel::mcap {

struct WriterOptions {
  Compression compression = Compression::kZstd;
  std::size_t chunk_size = 1u << 20;  // uncompressed bytes per chunk
};

class Writer {
 public:
  static Expected<std::unique_ptr<Writer>> create(const std::string& path,
                                                  WriterOptions options = {});
  ~Writer();  // unfinished: the partial file is removed
  Writer(const Writer&) = delete;
  Writer& operator=(const Writer&) = delete;

  // Ids start at 1; adding the same schema name or topic again returns its id.
  std::uint16_t add_schema(const std::string& name, std::string_view bfbs);
  std::uint16_t add_channel(const std::string& topic, std::uint16_t schema_id);
  Status write(std::uint16_t channel, std::uint64_t log_time_ns, std::uint64_t publish_time_ns,
               std::string_view data);
  Status finish();

  std::uint64_t messages() const { return message_count_; }
  // The file's bytes so far, the open chunk counted uncompressed with its
  // message index: what the file is at most once that chunk is written.
  std::uint64_t bytes() const;

 private:
  Writer(std::string path, std::FILE* file, WriterOptions options);
  Status flush_chunk();
  Status put(std::string_view bytes);

  struct Schema {
    std::uint16_t id;
    std::string name;
    std::string data;
  };
  struct Channel {
    std::uint16_t id;
    std::uint16_t schema;
    std::string topic;
  };
  struct ChunkIndex {
    std::uint64_t start_time, end_time, offset, length;
    std::map<std::uint16_t, std::uint64_t> index_offsets;
    std::uint64_t index_length, compressed_size, uncompressed_size;
  };

  std::string path_;
  std::FILE* file_;
  WriterOptions options_;
  std::uint64_t offset_ = 0;
  std::uint32_t data_crc_ = 0;
  std::vector<Schema> schemas_;
  std::vector<Channel> channels_;
  // The open chunk: its records, and per channel (log time, offset in them).
  std::string chunk_;
  std::uint64_t chunk_start_ = 0, chunk_end_ = 0;
  std::map<std::uint16_t, std::vector<std::pair<std::uint64_t, std::uint64_t>>> chunk_index_;
  std::vector<ChunkIndex> chunk_indexes_;
  std::map<std::uint16_t, std::uint64_t> channel_counts_;
  std::uint64_t message_count_ = 0, start_time_ = 0, end_time_ = 0;
  std::uint32_t sequence_ = 0;
  bool finished_ = false;
};

}  // namespace plr::kernel::mcap
