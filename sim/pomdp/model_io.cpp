#include "plr/pomdp/model_io.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <system_error>

#include <fmt/format.h>

#include "plr/pomdp/cassandra_reader.hpp"
#include "plr/pomdp/pomdpx_reader.hpp"

namespace plr::pomdp {

plr::Expected<std::string> read_text_file(const std::filesystem::path& file,
                                          std::size_t max_bytes) {
  std::error_code ec;
  const auto size = std::filesystem::file_size(file, ec);
  if (ec) {
    return plr::make_error(PLR_ERR_INVALID,
                           fmt::format("{}:1:1: cannot read: {}", file.string(), ec.message()));
  }
  if (size > max_bytes) {
    return plr::make_error(PLR_ERR_INVALID, fmt::format("{}:1:1: file larger than {} bytes",
                                                        file.string(), max_bytes));
  }
  std::ifstream in(file, std::ios::binary);
  std::string text(static_cast<std::size_t>(size), '\0');
  if (!in.read(text.data(), static_cast<std::streamsize>(size))) {
    return plr::make_error(PLR_ERR_INVALID, fmt::format("{}:1:1: cannot read: {}", file.string(),
                                                        std::strerror(errno)));
  }
  return text;
}

plr::Expected<TabularModel> load_model(const std::filesystem::path& file,
                                       const ReadLimits& limits) {
  if (file.extension() == ".pomdpx") return read_pomdpx(file, limits);
  return read_cassandra(file, limits);
}

}  // namespace plr::pomdp
