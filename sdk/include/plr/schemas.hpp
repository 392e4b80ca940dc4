// The binary FlatBuffers schemas (.bfbs, `flatc --schema -b`) of every SDK
// message type, compiled into the SDK support library: what a recording
// embeds and what a Foxglove client is sent to decode a topic.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace plr {

struct MessageSchema {
  std::string name;       // fully qualified table name, "plr.msg.WorldState"
  std::string_view bfbs;  // the reflection schema of the file declaring it
  std::uint64_t type_id;  // MessageTraits<T>::type_id()
  // The table's declared largest message (attribute max_bytes); 0: none.
  std::size_t max_bytes = 0;
};

// The schema of a message type by its type id; nullptr when the SDK has no such table.
const MessageSchema* find_schema(std::uint64_t type_id);
// ... and by its fully qualified name.
const MessageSchema* find_schema(std::string_view name);

}  // namespace plr
