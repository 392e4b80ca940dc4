#include "plr/jobs/store.hpp"

#include <plr/atomic_file.hpp>
#include <plr/frame.hpp>

#include <fstream>
#include <iterator>
#include <string_view>

#include "plr/jobs/messages.hpp"

namespace plr::jobs {

namespace fs = std::filesystem;

plr::Expected<Store> Store::open(const fs::path& dir) {
  std::error_code ec;
  for (const char* sub : {"results", "logs"}) {
    fs::create_directories(dir / sub, ec);
    if (ec) return plr::make_error(PLR_ERR_INTERNAL, (dir / sub).string() + ": " + ec.message());
  }
  return Store(dir);
}

fs::path Store::result_file(const std::string& key) const {
  return dir_ / "results" / (key + ".result");
}

fs::path Store::log_file(const std::string& key) const {
  return dir_ / "logs" / (key + ".log");
}

std::optional<Result> Store::load(const std::string& key) const {
  const fs::path file = result_file(key);
  std::error_code ec;
  const auto size = fs::file_size(file, ec);
  if (ec || size > kMaxBytes + 4096) return std::nullopt;
  std::ifstream in(file, std::ios::binary);
  const Bytes bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto payload = plr::unframe(bytes.data(), bytes.size(), kMaxBytes + 4096, file.string());
  if (!payload) return std::nullopt;
  auto message = decode_message(payload->data, payload->size, file.string());
  if (!message || message->type != Message::Type::kReply || message->result.key != key)
    return std::nullopt;
  message->result.stored = true;
  return std::move(message->result);
}

plr::Status Store::save(const Result& result) const {
  if (!valid_key(result.key))
    return plr::make_error(PLR_ERR_INVALID, "result key '" + result.key + "' is no file name");
  const Bytes payload = encode_reply(0, result);
  const Bytes framed = plr::frame(payload.data(), payload.size());
  return plr::write_file_atomically(
      result_file(result.key).string(),
      std::string_view(reinterpret_cast<const char*>(framed.data()), framed.size()));
}

}  // namespace plr::jobs
