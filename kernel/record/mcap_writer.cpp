#include "mcap_writer.hpp"

#include <unistd.h>
#include <zlib.h>
#include <zstd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>

namespace plr::kernel::mcap {

namespace {

void u8(std::string& o, std::uint8_t v) {
  o.push_back(static_cast<char>(v));
}
template <class T>
void le(std::string& o, T v) {
  for (std::size_t i = 0; i < sizeof(T); ++i)
    o.push_back(static_cast<char>((static_cast<std::uint64_t>(v) >> (8 * i)) & 0xff));
}
void str(std::string& o, std::string_view s) {
  le<std::uint32_t>(o, static_cast<std::uint32_t>(s.size()));
  o.append(s);
}
std::string record(Op op, const std::string& content) {
  std::string r;
  u8(r, static_cast<std::uint8_t>(op));
  le<std::uint64_t>(r, content.size());
  r += content;
  return r;
}
std::uint32_t crc(std::uint32_t running, std::string_view bytes) {
  return static_cast<std::uint32_t>(crc32(running, reinterpret_cast<const Bytef*>(bytes.data()),
                                          static_cast<uInt>(bytes.size())));
}

std::string schema_record(std::uint16_t id, const std::string& name, const std::string& data) {
  std::string c;
  le<std::uint16_t>(c, id);
  str(c, name);
  str(c, kEncoding);
  str(c, data);
  return record(Op::kSchema, c);
}

std::string channel_record(std::uint16_t id, std::uint16_t schema, const std::string& topic) {
  std::string c;
  le<std::uint16_t>(c, id);
  le<std::uint16_t>(c, schema);
  str(c, topic);
  str(c, kEncoding);
  le<std::uint32_t>(c, 0);  // metadata: an empty map
  return record(Op::kChannel, c);
}

const char* compression_name(Compression c) {
  switch (c) {
    case Compression::kZstd:
      return "zstd";
    case Compression::kLz4:
      return "lz4";
    case Compression::kNone:
      break;
  }
  return "";
}

}  // namespace

Expected<std::unique_ptr<Writer>> Writer::create(const std::string& path, WriterOptions options) {
  if (options.compression == Compression::kLz4)
    return make_error(PLR_ERR_INVALID, path + ": lz4 chunks are not written; use zstd or none");
  const std::string part = path + ".part";
  std::FILE* f = std::fopen(part.c_str(), "wb");
  if (f == nullptr)
    return make_error(PLR_ERR_INVALID, part + ": cannot create: " + std::strerror(errno));
  auto w = std::unique_ptr<Writer>(new Writer(path, f, options));
  std::string header;
  str(header, kProfile);
  str(header, "plr");
  if (auto s = w->put(std::string(kMagic)); !s) return s.error();
  if (auto s = w->put(record(Op::kHeader, header)); !s) return s.error();
  return w;
}

Writer::Writer(std::string path, std::FILE* file, WriterOptions options)
    : path_(std::move(path)), file_(file), options_(options) {}

Writer::~Writer() {
  if (file_ != nullptr) std::fclose(file_);
  if (!finished_) std::remove((path_ + ".part").c_str());
}

Status Writer::put(std::string_view bytes) {
  if (std::fwrite(bytes.data(), 1, bytes.size(), file_) != bytes.size())
    return make_error(PLR_ERR_INTERNAL, path_ + ".part: write failed: " + std::strerror(errno));
  // The data section's CRC runs from the file's first byte (as the format's
  // reference writer computes it); DataEnd takes it, the summary has its own.
  data_crc_ = crc(data_crc_, bytes);
  offset_ += bytes.size();
  return {};
}

std::uint16_t Writer::add_schema(const std::string& name, std::string_view bfbs) {
  for (const auto& s : schemas_)
    if (s.name == name) return s.id;
  const auto id = static_cast<std::uint16_t>(schemas_.size() + 1);
  schemas_.push_back({id, name, std::string(bfbs)});
  (void)put(schema_record(id, name, schemas_.back().data));
  return id;
}

std::uint16_t Writer::add_channel(const std::string& topic, std::uint16_t schema_id) {
  for (const auto& c : channels_)
    if (c.topic == topic) return c.id;
  const auto id = static_cast<std::uint16_t>(channels_.size() + 1);
  channels_.push_back({id, schema_id, topic});
  (void)put(channel_record(id, schema_id, topic));
  return id;
}

Status Writer::write(std::uint16_t channel, std::uint64_t log_time, std::uint64_t publish_time,
                     std::string_view data) {
  if (channel == 0 || channel > channels_.size())
    return make_error(PLR_ERR_INVALID, path_ + ": no channel " + std::to_string(channel));
  std::string c;
  le<std::uint16_t>(c, channel);
  le<std::uint32_t>(c, sequence_++);
  le<std::uint64_t>(c, log_time);
  le<std::uint64_t>(c, publish_time);
  c.append(data);
  if (chunk_.empty()) chunk_start_ = chunk_end_ = log_time;
  chunk_start_ = std::min(chunk_start_, log_time);
  chunk_end_ = std::max(chunk_end_, log_time);
  chunk_index_[channel].emplace_back(log_time, chunk_.size());
  chunk_ += record(Op::kMessage, c);
  if (message_count_ == 0) start_time_ = end_time_ = log_time;
  start_time_ = std::min(start_time_, log_time);
  end_time_ = std::max(end_time_, log_time);
  ++message_count_;
  ++channel_counts_[channel];
  if (chunk_.size() >= options_.chunk_size) return flush_chunk();
  return {};
}

std::uint64_t Writer::bytes() const {
  std::uint64_t index = 0;
  for (const auto& [channel, entries] : chunk_index_) index += 16 * entries.size() + 16;
  return offset_ + chunk_.size() + index + (chunk_.empty() ? 0 : 64);
}

Status Writer::flush_chunk() {
  if (chunk_.empty()) return {};
  std::string compressed;
  if (options_.compression == Compression::kZstd) {
    compressed.resize(ZSTD_compressBound(chunk_.size()));
    const auto n =
        ZSTD_compress(compressed.data(), compressed.size(), chunk_.data(), chunk_.size(), 3);
    if (ZSTD_isError(n))
      return make_error(PLR_ERR_INTERNAL, path_ + ": zstd: " + ZSTD_getErrorName(n));
    compressed.resize(n);
  } else {
    compressed = chunk_;
  }
  std::string c;
  le<std::uint64_t>(c, chunk_start_);
  le<std::uint64_t>(c, chunk_end_);
  le<std::uint64_t>(c, chunk_.size());
  le<std::uint32_t>(c, crc(0, chunk_));
  str(c, compression_name(options_.compression));
  le<std::uint64_t>(c, compressed.size());
  c += compressed;
  ChunkIndex index{chunk_start_, chunk_end_, offset_, 0, {}, 0, compressed.size(), chunk_.size()};
  const std::string chunk = record(Op::kChunk, c);
  index.length = chunk.size();
  if (auto s = put(chunk); !s) return s;
  const auto indexes_start = offset_;
  for (const auto& [channel, entries] : chunk_index_) {
    std::string m;
    le<std::uint16_t>(m, channel);
    le<std::uint32_t>(m, static_cast<std::uint32_t>(entries.size() * 16));
    for (const auto& [time, at] : entries) {
      le<std::uint64_t>(m, time);
      le<std::uint64_t>(m, at);
    }
    index.index_offsets[channel] = offset_;
    if (auto s = put(record(Op::kMessageIndex, m)); !s) return s;
  }
  index.index_length = offset_ - indexes_start;
  chunk_indexes_.push_back(std::move(index));
  chunk_.clear();
  chunk_index_.clear();
  return {};
}

Status Writer::finish() {
  if (finished_) return {};
  if (auto s = flush_chunk(); !s) return s;
  std::string end;
  le<std::uint32_t>(end, data_crc_);
  if (auto s = put(record(Op::kDataEnd, end)); !s) return s;

  // The summary: one group per record kind, each found through a SummaryOffset.
  const auto summary_start = offset_;
  std::vector<std::tuple<Op, std::uint64_t, std::uint64_t>> groups;
  std::string summary;
  const auto group = [&](Op op, const std::string& records) {
    if (records.empty()) return;
    groups.emplace_back(op, summary_start + summary.size(), records.size());
    summary += records;
  };
  std::string schemas, channels, indexes;
  for (const auto& s : schemas_) schemas += schema_record(s.id, s.name, s.data);
  for (const auto& c : channels_) channels += channel_record(c.id, c.schema, c.topic);
  std::string stats;
  le<std::uint64_t>(stats, message_count_);
  le<std::uint16_t>(stats, static_cast<std::uint16_t>(schemas_.size()));
  le<std::uint32_t>(stats, static_cast<std::uint32_t>(channels_.size()));
  le<std::uint32_t>(stats, 0);  // attachments
  le<std::uint32_t>(stats, 0);  // metadata
  le<std::uint32_t>(stats, static_cast<std::uint32_t>(chunk_indexes_.size()));
  le<std::uint64_t>(stats, start_time_);
  le<std::uint64_t>(stats, end_time_);
  le<std::uint32_t>(stats, static_cast<std::uint32_t>(channel_counts_.size() * 10));
  for (const auto& [channel, n] : channel_counts_) {
    le<std::uint16_t>(stats, channel);
    le<std::uint64_t>(stats, n);
  }
  for (const auto& i : chunk_indexes_) {
    std::string c;
    le<std::uint64_t>(c, i.start_time);
    le<std::uint64_t>(c, i.end_time);
    le<std::uint64_t>(c, i.offset);
    le<std::uint64_t>(c, i.length);
    le<std::uint32_t>(c, static_cast<std::uint32_t>(i.index_offsets.size() * 10));
    for (const auto& [channel, at] : i.index_offsets) {
      le<std::uint16_t>(c, channel);
      le<std::uint64_t>(c, at);
    }
    le<std::uint64_t>(c, i.index_length);
    str(c, compression_name(options_.compression));
    le<std::uint64_t>(c, i.compressed_size);
    le<std::uint64_t>(c, i.uncompressed_size);
    indexes += record(Op::kChunkIndex, c);
  }
  group(Op::kSchema, schemas);
  group(Op::kChannel, channels);
  group(Op::kStatistics, record(Op::kStatistics, stats));
  group(Op::kChunkIndex, indexes);
  const auto offsets_start = summary_start + summary.size();
  for (const auto& [op, start, length] : groups) {
    std::string c;
    u8(c, static_cast<std::uint8_t>(op));
    le<std::uint64_t>(c, start);
    le<std::uint64_t>(c, length);
    summary += record(Op::kSummaryOffset, c);
  }
  // The footer's CRC covers the summary and the footer up to the CRC itself.
  std::string footer;
  le<std::uint64_t>(footer, summary_start);
  le<std::uint64_t>(footer, offsets_start);
  std::string footer_record = record(Op::kFooter, footer + "0000");
  footer_record.resize(footer_record.size() - 4);
  le<std::uint32_t>(footer_record, crc(crc(0, summary), footer_record));
  if (auto s = put(summary + footer_record + std::string(kMagic)); !s) return s;

  const std::string part = path_ + ".part";
  const bool synced = std::fflush(file_) == 0 && ::fsync(::fileno(file_)) == 0;
  std::fclose(file_);
  file_ = nullptr;
  if (!synced)
    return make_error(PLR_ERR_INTERNAL, part + ": flush failed: " + std::strerror(errno));
  std::error_code ec;
  std::filesystem::rename(part, path_, ec);
  if (ec)
    return make_error(PLR_ERR_INTERNAL, path_ + ": cannot rename " + part + ": " + ec.message());
  finished_ = true;
  return {};
}

}  // namespace plr::kernel::mcap
