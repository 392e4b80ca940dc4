// Fuzz target: the YAML reader under every file format (plr/yaml_reader.hpp).
// Any bytes, read the way a file format reads them, must end in a value or
// an error, never a crash or a hang.
#include <plr/yaml_reader.hpp>

#include <cstddef>
#include <cstdint>
#include <string_view>

namespace {

// Every getter on every value, as a reader that knows nothing would call them.
void walk(const plr::yaml::Node& n, int depth) {
  (void)n.location();
  (void)n.key_location();
  (void)n.describe();
  (void)n.string();
  (void)n.integer(-5, 5);
  (void)n.number(0, 1);
  (void)n.positive();
  (void)n.boolean();
  (void)n.one_of({"a", "b"});
  if (depth > 8) return;  // aliases make a DAG; the tree's own depth is bounded
  const plr::yaml::Map m = n.map("a map", {"a", "b", "nodes"});
  (void)m.required("a");
  for (const auto& e : m) walk(e, depth + 1);
  for (const auto& item : n.list("a list", 0, 64)) walk(item, depth + 1);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  plr::yaml::Limits limits;
  limits.max_bytes = 1 << 16;
  limits.max_values = 1 << 12;
  limits.max_errors = 0;
  auto doc = plr::yaml::Document::parse(std::string_view(reinterpret_cast<const char*>(data), size),
                                        "fuzz.yaml", limits);
  if (!doc) return 0;
  doc->set("nodes.a.params.k", std::string_view(reinterpret_cast<const char*>(data), size),
           "--set nodes.a.params.k");
  (void)doc->root().to_json();
  walk(doc->root(), 0);
  if (!doc->ok()) (void)doc->error();
  return 0;
}
