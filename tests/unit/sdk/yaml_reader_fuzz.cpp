// Fuzz target of the YAML reader: any bytes, read the way a file format
// reads them, must end in a value or an error, never a crash or a hang.
//
// Built with clang and -DPLR_FUZZ=ON it is a libFuzzer binary:
//   build-fuzz/bin/sdk_yaml_reader_fuzz tests/unit/sdk/yaml_reader_corpus
// Otherwise a plain program that runs the files it is given once each (the
// corpus, as a test).
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

#ifndef PLR_LIBFUZZER
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <vector>

// Runs each file given, and each file in each folder given, once.
int main(int argc, char** argv) {
  std::vector<std::filesystem::path> files;
  for (int i = 1; i < argc; ++i) {
    if (std::filesystem::is_directory(argv[i])) {
      for (const auto& e : std::filesystem::directory_iterator(argv[i])) files.push_back(e.path());
    } else {
      files.emplace_back(argv[i]);
    }
  }
  for (const auto& f : files) {
    std::ifstream in(f, std::ios::binary);
    if (!in) {
      std::fprintf(stderr, "%s: cannot read\n", f.c_str());
      return 1;
    }
    const std::vector<char> bytes{std::istreambuf_iterator<char>(in), {}};
    LLVMFuzzerTestOneInput(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
  }
  std::printf("%zu inputs read\n", files.size());
  return files.empty() ? 1 : 0;
}
#endif
