#include "truck/journal.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <fmt/format.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <vector>

#include <plr/frame.hpp>

namespace plr::generator {

namespace {

constexpr std::size_t kHeader = 16;  // size, crc, key

std::uint64_t read_le(const std::uint8_t* p, int bytes) {
  std::uint64_t v = 0;
  for (int i = bytes - 1; i >= 0; --i) v = v << 8 | p[i];
  return v;
}

void put_le(std::vector<std::uint8_t>& out, std::uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) out.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
}

plr::Error io_error(const std::filesystem::path& p, const char* what) {
  return plr::make_error(PLR_ERR_INTERNAL,
                         fmt::format("{}: {}: {}", p.string(), what, std::strerror(errno)));
}

}  // namespace

plr::Expected<std::unique_ptr<Journal>> Journal::open(const std::filesystem::path& file) {
  std::unique_ptr<Journal> j(new Journal());
  j->path_ = file;
  std::size_t good = 0;
  std::error_code ec;
  if (std::filesystem::exists(file, ec)) {
    std::ifstream in(file, std::ios::binary);
    std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                    std::istreambuf_iterator<char>());
    while (good + kHeader <= bytes.size()) {
      const std::uint8_t* p = bytes.data() + good;
      const std::size_t size = read_le(p, 4);
      if (size > actions::kMaxFrameBytes || good + kHeader + size > bytes.size()) break;
      if (plr::crc32(p + 8, size + 8) != read_le(p + 4, 4)) break;
      auto frame = actions::decode_frame(p + kHeader, size, file.string());
      if (!frame || frame->kind != actions::Frame::Kind::kResult || !frame->result) break;
      j->loaded_.emplace(read_le(p + 8, 8), std::move(*frame->result));
      good += kHeader + size;
    }
    j->dropped_bytes_ = bytes.size() - good;
    if (j->dropped_bytes_ > 0) std::filesystem::resize_file(file, good, ec);
    if (ec)
      return plr::make_error(PLR_ERR_INTERNAL, fmt::format("{}: cutting a torn record: {}",
                                                           file.string(), ec.message()));
  }
  j->loaded_count_ = j->loaded_.size();
  j->file_ = std::fopen(file.c_str(), "ab");
  if (!j->file_) return io_error(file, "open");
  return j;
}

Journal::~Journal() {
  if (file_) std::fclose(file_);
}

plr::Status Journal::append(std::uint64_t key, const SimOutcome& outcome) {
  const std::vector<std::uint8_t> frame = actions::frame_result(0, outcome);
  // frame_result() puts its own size in front; the record has it in its header.
  const std::size_t size = frame.size() - 4;
  std::vector<std::uint8_t> record;
  record.reserve(kHeader + size);
  put_le(record, size, 4);
  put_le(record, 0, 4);
  put_le(record, key, 8);
  record.insert(record.end(), frame.begin() + 4, frame.end());
  const std::uint32_t crc = plr::crc32(record.data() + 8, size + 8);
  for (int i = 0; i < 4; ++i) record[4 + i] = static_cast<std::uint8_t>(crc >> (8 * i));
  if (std::fwrite(record.data(), 1, record.size(), file_) != record.size())
    return io_error(path_, "write");
  return {};
}

plr::Status Journal::sync() {
  if (std::fflush(file_) != 0) return io_error(path_, "flush");
  if (::fsync(::fileno(file_)) != 0) return io_error(path_, "fsync");
  return {};
}

}  // namespace plr::generator
