#include "mcap_reader.hpp"

#include <zlib.h>
#include <zstd.h>

#include <fstream>

namespace plr::kernel::mcap {

namespace {

// A bounded view that fails, instead of reading past its end.
class Cursor {
 public:
  Cursor(std::string_view bytes, std::uint64_t base) : bytes_(bytes), base_(base) {}
  bool empty() const { return at_ == bytes_.size(); }
  std::uint64_t offset() const { return base_ + at_; }
  std::size_t left() const { return bytes_.size() - at_; }

  template <class T>
  bool num(T& v) {
    if (left() < sizeof(T)) return false;
    std::uint64_t x = 0;
    for (std::size_t i = 0; i < sizeof(T); ++i)
      x |= static_cast<std::uint64_t>(static_cast<std::uint8_t>(bytes_[at_ + i])) << (8 * i);
    v = static_cast<T>(x);
    at_ += sizeof(T);
    return true;
  }
  bool bytes(std::uint64_t n, std::string_view& out) {
    if (n > left()) return false;
    out = bytes_.substr(at_, n);
    at_ += n;
    return true;
  }
  template <class Length>
  bool prefixed(std::string_view& out) {
    Length n = 0;
    return num(n) && bytes(n, out);
  }
  bool str(std::string& out) {
    std::string_view v;
    if (!prefixed<std::uint32_t>(v)) return false;
    out.assign(v);
    return true;
  }
  std::string_view rest() {
    auto r = bytes_.substr(at_);
    at_ = bytes_.size();
    return r;
  }

 private:
  std::string_view bytes_;
  std::uint64_t base_;
  std::size_t at_ = 0;
};

class Parser {
 public:
  Parser(const std::string& origin, const std::function<void(const MessageRecord&)>& on_message,
         Contents& contents, const ReaderLimits& limits)
      : origin_(origin), on_message_(on_message), contents_(contents), limits_(limits) {}

  // Records until DataEnd (returns true) or the end of `c` (false).
  Expected<bool> records(Cursor& c, bool in_chunk) {
    while (!c.empty()) {
      const auto at = c.offset();
      std::uint8_t op = 0;
      std::string_view body;
      if (!c.num(op) || !c.prefixed<std::uint64_t>(body))
        return fail(at, "record truncated (" + std::to_string(c.left()) + " bytes left)");
      Cursor r(body, at + 9);
      switch (static_cast<Op>(op)) {
        case Op::kSchema:
          if (auto s = schema(r, at); !s) return s.error();
          break;
        case Op::kChannel:
          if (auto s = channel(r, at); !s) return s.error();
          break;
        case Op::kMessage:
          if (auto s = message(r, at); !s) return s.error();
          break;
        case Op::kChunk:
          if (in_chunk) return fail(at, "a chunk inside a chunk");
          if (auto s = chunk(r, at); !s) return s.error();
          break;
        case Op::kDataEnd:
          if (in_chunk) return fail(at, "DataEnd inside a chunk");
          return true;
        case Op::kHeader:
        case Op::kFooter:
          return fail(at, "unexpected " + std::string(op == 1 ? "Header" : "Footer") + " record");
        default:
          break;  // indexes, attachments, metadata, and opcodes of later versions: skipped
      }
    }
    return false;
  }

 private:
  Error fail(std::uint64_t at, const std::string& what) const {
    return Error{PLR_ERR_INVALID, origin_ + ": offset " + std::to_string(at) + ": " + what};
  }

  Status schema(Cursor& r, std::uint64_t at) {
    SchemaRecord s;
    std::string_view data;
    if (!r.num(s.id) || !r.str(s.name) || !r.str(s.encoding) || !r.prefixed<std::uint32_t>(data))
      return fail(at, "Schema record truncated");
    if (s.id == 0) return {};  // id 0 is "no schema": ignored, as the format says
    s.data.assign(data);
    contents_.schemas[s.id] = std::move(s);
    return {};
  }

  Status channel(Cursor& r, std::uint64_t at) {
    ChannelRecord c;
    std::string_view metadata;
    if (!r.num(c.id) || !r.num(c.schema_id) || !r.str(c.topic) || !r.str(c.message_encoding) ||
        !r.prefixed<std::uint32_t>(metadata))
      return fail(at, "Channel record truncated");
    if (c.schema_id != 0 && !contents_.schemas.count(c.schema_id))
      return fail(at, "channel '" + c.topic + "' names schema " + std::to_string(c.schema_id) +
                          ", which did not come before it");
    contents_.channels[c.id] = std::move(c);
    return {};
  }

  Status message(Cursor& r, std::uint64_t at) {
    MessageRecord m;
    std::uint16_t channel = 0;
    if (!r.num(channel) || !r.num(m.sequence) || !r.num(m.log_time) || !r.num(m.publish_time))
      return fail(at, "Message record truncated");
    const auto c = contents_.channels.find(channel);
    if (c == contents_.channels.end())
      return fail(
          at, "message on channel " + std::to_string(channel) + ", which did not come before it");
    m.channel = &c->second;
    m.data = r.rest();
    on_message_(m);
    return {};
  }

  Status chunk(Cursor& r, std::uint64_t at) {
    std::uint64_t start = 0, end = 0, size = 0;
    std::uint32_t crc = 0;
    std::string compression;
    std::string_view records;
    if (!r.num(start) || !r.num(end) || !r.num(size) || !r.num(crc) || !r.str(compression) ||
        !r.prefixed<std::uint64_t>(records))
      return fail(at, "Chunk record truncated");
    if (size > limits_.max_chunk_bytes)
      return fail(at, "chunk of " + std::to_string(size) + " bytes uncompressed (limit " +
                          std::to_string(limits_.max_chunk_bytes) + ")");
    std::string plain;
    if (compression.empty()) {
      if (records.size() != size) return fail(at, "chunk size does not match its records");
      plain.assign(records);
    } else if (compression == "zstd") {
      const auto frame = ZSTD_getFrameContentSize(records.data(), records.size());
      if (frame != size) return fail(at, "zstd chunk: frame size does not match the chunk's");
      plain.resize(size);
      const auto n = ZSTD_decompress(plain.data(), plain.size(), records.data(), records.size());
      if (ZSTD_isError(n) || n != size)
        return fail(at, std::string("zstd chunk: ") +
                            (ZSTD_isError(n) ? ZSTD_getErrorName(n) : "size mismatch"));
    } else {
      return fail(at, "chunk compression '" + compression.substr(0, 32) +
                          "' is not supported (none or zstd)");
    }
    if (crc != 0 && crc32(0, reinterpret_cast<const Bytef*>(plain.data()),
                          static_cast<uInt>(plain.size())) != crc)
      return fail(at, "chunk CRC mismatch");
    Cursor inner(plain, 0);
    auto done = records_in(inner, at);
    if (!done) return done.error();
    return {};
  }

  Expected<bool> records_in(Cursor& c, std::uint64_t chunk_at) {
    auto r = records(c, true);
    if (!r) {
      auto e = r.error();
      e.message += " (in the chunk at offset " + std::to_string(chunk_at) + ")";
      return e;
    }
    return r;
  }

  const std::string& origin_;
  const std::function<void(const MessageRecord&)>& on_message_;
  Contents& contents_;
  const ReaderLimits& limits_;
};

}  // namespace

Status read(std::string_view file, const std::string& origin,
            const std::function<void(const MessageRecord&)>& on_message, Contents& contents,
            const ReaderLimits& limits) {
  if (!file.starts_with(kMagic))
    return make_error(PLR_ERR_INVALID, origin + ": not an MCAP file (no magic bytes)");
  Cursor c(file.substr(kMagic.size()), kMagic.size());
  std::uint8_t op = 0;
  std::string_view header;
  if (!c.num(op) || op != static_cast<std::uint8_t>(Op::kHeader) ||
      !c.prefixed<std::uint64_t>(header))
    return make_error(PLR_ERR_INVALID, origin + ": offset 8: expected the Header record");
  Parser parser(origin, on_message, contents, limits);
  auto ended = parser.records(c, false);
  if (!ended) return ended.error();
  if (!*ended)
    return make_error(PLR_ERR_INVALID,
                      origin + ": no DataEnd record: the file is truncated (recording cut short?)");
  return {};
}

Expected<std::string> load(const std::string& path, std::uint64_t max_file_bytes) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return make_error(PLR_ERR_INVALID, path + ": cannot open");
  const auto size = static_cast<std::uint64_t>(in.tellg());
  if (size > max_file_bytes)
    return make_error(PLR_ERR_INVALID, path + ": " + std::to_string(size) + " bytes (limit " +
                                           std::to_string(max_file_bytes) + ")");
  std::string bytes(size, '\0');
  in.seekg(0);
  if (!in.read(bytes.data(), static_cast<std::streamsize>(size)))
    return make_error(PLR_ERR_INVALID, path + ": read failed");
  return bytes;
}

}  // namespace plr::kernel::mcap
