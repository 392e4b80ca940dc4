#include "plr/planning/query_set.hpp"

#include <plr/atomic_file.hpp>
#include <plr/frame.hpp>
#include <plr/messages.hpp>

#include <cstring>
#include <fstream>
#include <iterator>
#include <string>

#include "plr/planning/plan_messages.hpp"

namespace plr::planning {
namespace {

// A world of a few hundred boxes is some 100 kB as a request.
constexpr std::size_t kMaxQueryBytes = 16u << 20;
constexpr std::size_t kMaxFileBytes = 1u << 30;

}  // namespace

std::vector<std::uint8_t> frame_query(const PlanQuery& query, const sim::World& world) {
  flatbuffers::FlatBufferBuilder fbb;
  encode_plan_request(query, world, fbb);
  return plr::frame(fbb.GetBufferPointer(), fbb.GetSize());
}

plr::Status save_query_set(const std::vector<std::vector<std::uint8_t>>& frames,
                           const std::filesystem::path& file) {
  std::string bytes;
  for (const auto& f : frames) bytes.append(f.begin(), f.end());
  return plr::write_file_atomically(file.string(), bytes);
}

plr::Expected<std::vector<RecordedQuery>> load_query_set(const std::filesystem::path& file) {
  const std::string origin = file.string();
  std::ifstream in(file, std::ios::binary);
  if (!in) return plr::make_error(PLR_ERR_INVALID, origin + ": cannot be read");
  const std::vector<std::uint8_t> bytes((std::istreambuf_iterator<char>(in)),
                                        std::istreambuf_iterator<char>());
  if (bytes.size() > kMaxFileBytes)
    return plr::make_error(PLR_ERR_INVALID, origin + ": larger than 1 GiB");
  plr::FrameReader reader(kMaxQueryBytes, origin);
  reader.feed(bytes.data(), bytes.size());
  std::vector<RecordedQuery> out;
  for (;;) {
    auto next = reader.next();
    if (!next) return next.error();
    if (!*next) break;
    const std::vector<std::uint8_t>& payload = **next;
    const std::string where = origin + ": query " + std::to_string(out.size() + 1);
    // FlatBuffers reads 8-byte scalars in place: an aligned copy.
    std::vector<std::uint64_t> aligned((payload.size() + 7) / 8);
    std::memcpy(aligned.data(), payload.data(), payload.size());
    const auto* data = reinterpret_cast<const std::uint8_t*>(aligned.data());
    flatbuffers::Verifier verifier(data, payload.size());
    if (!verifier.VerifyBuffer<msg::PlanRequest>(nullptr))
      return plr::make_error(PLR_ERR_INVALID, where + ": not a PlanRequest");
    auto decoded = decode_plan_request(*flatbuffers::GetRoot<msg::PlanRequest>(data));
    if (!decoded) return plr::make_error(PLR_ERR_INVALID, where + ": " + decoded.error().message);
    out.push_back({std::move(decoded->query), std::move(decoded->world)});
  }
  if (reader.pending() != 0)
    return plr::make_error(PLR_ERR_INVALID,
                           origin + ": ends inside query " + std::to_string(out.size() + 1));
  return out;
}

}  // namespace plr::planning
