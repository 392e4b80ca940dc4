// The MCAP writer and reader (kernel/record): what one writes the other
// reads back, and a damaged file gets an error naming where and what.
#include "mcap_reader.hpp"
#include "mcap_writer.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <filesystem>
#include <vector>

namespace plr::kernel::mcap {
namespace {

namespace fs = std::filesystem;

fs::path temp_file(const std::string& name) {
  return fs::temp_directory_path() / (name + "_" + std::to_string(::getpid()) + ".mcap");
}

struct Read {
  Status status;
  std::vector<std::tuple<std::string, std::uint64_t, std::string>> messages;  // topic, time, data
  Contents contents;
};

Read read_bytes(const std::string& bytes) {
  Read r;
  r.status = read(
      bytes, "test.mcap",
      [&](const MessageRecord& m) {
        r.messages.emplace_back(m.channel->topic, m.log_time, std::string(m.data));
      },
      r.contents);
  return r;
}

// Two channels, over several chunks when `chunk_size` is small, zstd or not.
std::string write_sample(Compression compression, int messages = 50, std::size_t chunk_size = 256) {
  const auto path = temp_file("sample");
  WriterOptions o;
  o.compression = compression;
  o.chunk_size = chunk_size;
  auto w = Writer::create(path.string(), o);
  EXPECT_TRUE(w) << w.error().message;
  const auto schema = (*w)->add_schema("plr.msg.Count", "bfbs-bytes");
  const auto a = (*w)->add_channel("count", schema);
  const auto b = (*w)->add_channel("doubled", schema);
  EXPECT_EQ((*w)->add_channel("count", schema), a);
  for (int i = 0; i < messages; ++i)
    EXPECT_TRUE((*w)->write(i % 3 ? a : b, 1000u * i, 999u * i, "message " + std::to_string(i)));
  EXPECT_FALSE(fs::exists(path)) << "visible before finish()";
  EXPECT_TRUE((*w)->finish());
  auto bytes = load(path.string());
  EXPECT_TRUE(bytes);
  fs::remove(path);
  return *bytes;
}

TEST(Mcap, WhatTheWriterWritesTheReaderReads) {
  for (auto c : {Compression::kZstd, Compression::kNone}) {
    const auto r = read_bytes(write_sample(c));
    ASSERT_TRUE(r.status) << r.status.error().message;
    ASSERT_EQ(r.messages.size(), 50u);
    for (int i = 0; i < 50; ++i) {
      EXPECT_EQ(std::get<0>(r.messages[i]), i % 3 ? "count" : "doubled");
      EXPECT_EQ(std::get<1>(r.messages[i]), 1000u * i);
      EXPECT_EQ(std::get<2>(r.messages[i]), "message " + std::to_string(i));
    }
    ASSERT_EQ(r.contents.schemas.size(), 1u);
    EXPECT_EQ(r.contents.schemas.at(1).name, "plr.msg.Count");
    EXPECT_EQ(r.contents.schemas.at(1).encoding, "flatbuffer");
    EXPECT_EQ(r.contents.schemas.at(1).data, "bfbs-bytes");
    EXPECT_EQ(r.contents.channels.at(1).message_encoding, "flatbuffer");
  }
}

TEST(Mcap, ZstdChunksAreSmaller) {
  EXPECT_LT(write_sample(Compression::kZstd, 400, 1u << 20).size(),
            write_sample(Compression::kNone, 400, 1u << 20).size() / 2);
}

TEST(Mcap, ADamagedFileIsAnErrorSayingWhereAndWhat) {
  const auto good = write_sample(Compression::kZstd);
  EXPECT_EQ(read_bytes("not an mcap").status.error().message,
            "test.mcap: not an MCAP file (no magic bytes)");
  // Cut inside the data section.
  auto r = read_bytes(good.substr(0, good.size() / 2));
  ASSERT_FALSE(r.status);
  EXPECT_NE(r.status.error().message.find("test.mcap: offset "), std::string::npos);
  EXPECT_NE(r.status.error().message.find("truncated"), std::string::npos)
      << r.status.error().message;
  // A flipped byte inside the first chunk's compressed records.
  const auto chunk = good.find(std::string(1, '\x06'), 8 + 9);
  ASSERT_NE(chunk, std::string::npos);
  auto damaged = good;
  damaged[chunk + 9 + 8 * 3 + 4 + 4 + 4 + 8 + 20] ^= 0x55;
  r = read_bytes(damaged);
  ASSERT_FALSE(r.status);
  EXPECT_NE(r.status.error().message.find("offset " + std::to_string(chunk)), std::string::npos)
      << r.status.error().message;
}

TEST(Mcap, AChunkOverTheLimitIsRefusedBeforeItIsInflated) {
  const auto good = write_sample(Compression::kZstd);
  Contents contents;
  ReaderLimits limits;
  limits.max_chunk_bytes = 64;
  const auto s = read(
      good, "test.mcap", [](const MessageRecord&) {}, contents, limits);
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("bytes uncompressed (limit 64)"), std::string::npos)
      << s.error().message;
}

TEST(Mcap, AnUnfinishedRecordingLeavesNoFile) {
  const auto path = temp_file("unfinished");
  {
    auto w = Writer::create(path.string());
    ASSERT_TRUE(w);
    (*w)->add_channel("count", (*w)->add_schema("plr.msg.Count", "x"));
    ASSERT_TRUE((*w)->write(1, 1, 1, "m"));
  }
  EXPECT_FALSE(fs::exists(path));
  EXPECT_FALSE(fs::exists(path.string() + ".part"));
}

}  // namespace
}  // namespace plr::kernel::mcap
