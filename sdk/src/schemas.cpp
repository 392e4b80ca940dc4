#include <plr/embedded_file.hpp>
#include <plr/message.hpp>
#include <plr/schemas.hpp>

#include <flatbuffers/reflection_generated.h>

#include <charconv>
#include <map>
#include <string_view>

extern const plr::EmbeddedFile plr_schema_files[];
extern const std::size_t plr_schema_files_count;

namespace plr {

namespace {

// "//sdk/world.fbs" -> "world", "world.bfbs" -> "world".
std::string_view stem(std::string_view path) {
  if (const auto slash = path.rfind('/'); slash != std::string_view::npos)
    path.remove_prefix(slash + 1);
  return path.substr(0, path.rfind('.'));
}

// The table's `max_bytes` attribute; 0 when absent or not a positive number.
std::size_t declared_max_bytes(const reflection::Object& object) {
  if (object.attributes() == nullptr) return 0;
  const auto* kv = object.attributes()->LookupByKey("max_bytes");
  if (kv == nullptr || kv->value() == nullptr) return 0;
  std::size_t value = 0;
  const auto text = kv->value()->string_view();
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  return ec == std::errc() && end == text.data() + text.size() ? value : 0;
}

struct Registry {
  std::map<std::uint64_t, MessageSchema> by_id;
  std::map<std::string, const MessageSchema*, std::less<>> by_name;
};

// Every table of every schema file, found by reading the files' reflection
// data: a new schema needs no entry here. A table included by several files
// keeps the file that declares it.
Registry load() {
  Registry r;
  for (std::size_t i = 0; i < plr_schema_files_count; ++i) {
    const auto bytes = plr_schema_files[i].bytes();
    flatbuffers::Verifier verifier(reinterpret_cast<const std::uint8_t*>(bytes.data()),
                                   bytes.size());
    if (!reflection::VerifySchemaBuffer(verifier)) continue;
    const auto* schema = reflection::GetSchema(bytes.data());
    if (schema->objects() == nullptr) continue;
    for (const auto* object : *schema->objects()) {
      if (object->is_struct()) continue;
      const std::string name = object->name()->str();
      const bool declared_here =
          object->declaration_file() == nullptr ||
          stem(object->declaration_file()->string_view()) == stem(plr_schema_files[i].name);
      const auto id = fnv1a(name);
      auto [it, fresh] =
          r.by_id.try_emplace(id, MessageSchema{name, bytes, id, declared_max_bytes(*object)});
      if (!fresh && declared_here) it->second.bfbs = bytes;
    }
  }
  for (const auto& [id, s] : r.by_id) r.by_name.emplace(s.name, &s);
  return r;
}

const Registry& registry() {
  static const Registry r = load();
  return r;
}

}  // namespace

const MessageSchema* find_schema(std::uint64_t type_id) {
  const auto& r = registry();
  const auto it = r.by_id.find(type_id);
  return it == r.by_id.end() ? nullptr : &it->second;
}

const MessageSchema* find_schema(std::string_view name) {
  const auto& r = registry();
  const auto it = r.by_name.find(name);
  return it == r.by_name.end() ? nullptr : it->second;
}

}  // namespace plr
