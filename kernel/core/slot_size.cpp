#include "slot_size.hpp"

#include <plr/schemas.hpp>

#include <algorithm>

namespace plr::kernel {

std::size_t message_bound(std::uint64_t type_id) {
  const auto* schema = find_schema(type_id);
  return schema != nullptr && schema->max_bytes > 0 ? schema->max_bytes : kDefaultSlotSize;
}

std::size_t slot_size(const TopicSettings& settings,
                      std::initializer_list<std::uint64_t> type_ids) {
  if (settings.slot_size) return *settings.slot_size;
  std::size_t bytes = 0;
  for (const auto id : type_ids) bytes = std::max(bytes, message_bound(id));
  return bytes > 0 ? bytes : kDefaultSlotSize;
}

}  // namespace plr::kernel
