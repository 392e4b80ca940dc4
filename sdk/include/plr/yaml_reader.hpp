// The one YAML reader behind every file format (pipeline config, world,
// strategy, lattice): a value tree that remembers where each value stood, and
// typed getters that report what is wrong as
//   "world.yaml:12:5: boxes[3].size: must have exactly 3 items, got 2"
// Nothing throws out of it. A getter that refuses a value records the error in
// its document and returns nothing; the reader goes on (so one run can list
// every problem) and ends with Document::result().
//
//   auto doc = plr::yaml::Document::open("world.yaml", "the world");
//   if (!doc) return doc.error();
//   World world;
//   const plr::yaml::Map top = doc->root().map("a world", {"trailer", "boxes"});
//   world.width = top.required("trailer").map("a trailer", {"width"})
//                     .required("width").positive().value_or(0);
//   for (const plr::yaml::Node& b : top.required("boxes").list("a list of boxes", 0, 10'000))
//     world.boxes.push_back(read_box(b));
//   return doc->result(std::move(world));
//
// Maps and lists are returned by value (safe to chain and to loop over);
// one that was not there, or not a map or list, is empty and false.
// Link plr::sdk_support (yaml-cpp stays private to it).
#pragma once

#include <plr/expected.hpp>

#include <nlohmann/json.hpp>

#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace plr::yaml {

// Where a value came from: "file:line:column", or, for a value the program
// put in (Document::set), that value's label ("--set a.b"; line 0).
struct Location {
  std::string file;
  int line = 0;
  int column = 0;
  std::string str() const;
};

struct Limits {
  std::size_t max_bytes = 16u << 20;  // of the text (Document::open refuses larger files)
  std::size_t max_values = 1u << 20;  // values in the tree, and visited by to_json() (aliases)
  std::size_t max_depth = 64;         // nesting of maps and lists
  // Problems the error lists, first in file order first; 0: all of them.
  std::size_t max_errors = 1;
};

namespace detail {
struct Tree;
}

class Map;
class List;

// One value of a document, as reached from the top: it knows its key path
// ("nodes.a.params.list[2]") and where it stood. A key asked for that is not
// there is an absent Node: present() is false and every getter returns
// nothing without a further error. Valid while its Document lives.
class Node {
 public:
  bool present() const { return tree_ != nullptr; }
  bool is_null() const;
  bool is_scalar() const;
  bool is_map() const;
  bool is_list() const;
  // A scalar's text as written ("" for anything else), and whether it was quoted.
  const std::string& text() const;
  bool quoted() const;

  const std::string& path() const { return path_; }
  // The key of a map entry ("" for the top and for list items).
  const std::string& name() const { return name_; }
  // The value's position; a null value's is its key's (YAML marks it past its end).
  Location location() const;
  Location key_location() const;
  // "a map", "a list", "'x'", "the string 'x'", "an empty string", "nothing".
  std::string describe() const;

  // Typed values. Each records "<location>: <path>: <what is wrong>" and
  // returns nothing when the value does not fit. Plain scalars resolve by the
  // YAML 1.2 core schema; a quoted one is always a string ("yes" too).
  std::optional<std::string> string(std::string_view what = "a string") const;  // non-empty
  std::optional<std::int64_t> integer(
      std::int64_t min = std::numeric_limits<std::int64_t>::min(),
      std::int64_t max = std::numeric_limits<std::int64_t>::max()) const;
  std::optional<double> number(double min = -std::numeric_limits<double>::infinity(),
                               double max = std::numeric_limits<double>::infinity()) const;
  std::optional<double> positive() const;  // a number > 0
  std::optional<bool> boolean() const;
  std::optional<std::string> one_of(const std::vector<std::string>& allowed) const;
  // A map (null reads as an empty one), with duplicate and non-scalar keys
  // reported and left out; with `known`, unknown keys too, naming the closest.
  Map map(std::string_view what = "a map") const;
  Map map(std::string_view what, const std::vector<std::string>& known) const;
  // A list (null reads as an empty one) of min_items..max_items items.
  List list(std::string_view what = "a list", std::size_t min_items = 0,
            std::size_t max_items = std::numeric_limits<std::size_t>::max()) const;
  // Any value as JSON (null for an absent Node); reports keys as map() does,
  // integers beyond 64 bits, .inf/.nan (which JSON cannot hold), and aliases
  // that expand past the limits.
  nlohmann::json to_json() const;

  // Records a problem at this value, or at its key.
  void error(std::string_view what) const;
  void key_error(std::string_view what) const;

 private:
  friend class Map;
  friend class List;
  friend class Document;
  Node() = default;
  Node(detail::Tree* tree, std::uint32_t value, std::uint32_t key, std::uint32_t anchor,
       std::string path, std::string name)
      : tree_(tree),
        value_(value),
        key_(key),
        anchor_(anchor),
        path_(std::move(path)),
        name_(std::move(name)) {}
  Node child(std::uint32_t value, std::uint32_t key, std::string path, std::string name) const;
  nlohmann::json to_json(std::size_t& budget, std::size_t depth) const;

  detail::Tree* tree_ = nullptr;
  std::uint32_t value_ = 0;
  std::uint32_t key_ = 0;     // the key's value in the tree, or kNone
  std::uint32_t anchor_ = 0;  // where errors about the value point
  std::string path_;
  std::string name_;
};

// The entries of a map, in document order. False when there was no map.
class Map {
 public:
  explicit operator bool() const { return ok_; }
  std::vector<Node>::const_iterator begin() const { return entries_.begin(); }
  std::vector<Node>::const_iterator end() const { return entries_.end(); }
  std::size_t size() const { return entries_.size(); }
  // The entry `key`, or an absent Node: quietly for find(), while required()
  // records "missing required key '<key>'" at the map (unless there was no map).
  Node find(std::string_view key) const;
  Node required(std::string_view key) const;

 private:
  friend class Node;
  Map() = default;
  Map(Node self, std::vector<Node> entries)
      : self_(std::move(self)), entries_(std::move(entries)), ok_(true) {}
  Node self_;
  std::vector<Node> entries_;
  bool ok_ = false;
};

// The items of a list. False when there was no list of a fitting length.
class List {
 public:
  explicit operator bool() const { return ok_; }
  std::vector<Node>::const_iterator begin() const { return items_.begin(); }
  std::vector<Node>::const_iterator end() const { return items_.end(); }
  std::size_t size() const { return items_.size(); }
  // Item `i`; one past the end is a bug of the reader: it aborts.
  const Node& operator[](std::size_t i) const;

 private:
  friend class Node;
  List() = default;
  explicit List(std::vector<Node> items) : items_(std::move(items)), ok_(true) {}
  std::vector<Node> items_;
  bool ok_ = false;
};

class Document {
 public:
  // A syntax error or a limit reached is the returned error ("file:line:col:
  // syntax error: ..."); everything after is reported through the getters.
  static Expected<Document> parse(std::string_view text, std::string file, Limits limits = {});
  // Reads at most limits.max_bytes; `what` names the file in errors
  // ("<path>: cannot read <what>: No such file or directory").
  static Expected<Document> open(const std::string& path, std::string_view what = "the file",
                                 Limits limits = {});
  Document(Document&&) noexcept;
  Document& operator=(Document&&) noexcept;
  ~Document();

  Node root() const;
  // Puts `yaml_value` at the dotted `path` before reading (maps on the way
  // are made); it and what it holds are located as `label`. Problems, such
  // as a value that does not parse, are recorded as "<label>: <path>: ...".
  void set(std::string_view path, std::string_view yaml_value, const std::string& label);

  bool ok() const;
  // PLR_ERR_INVALID with the problems recorded, one line each, file order
  // first, labelled values after (Limits::max_errors of them).
  Error error() const;
  template <class T>
  Expected<T> result(T value) const {
    if (!ok()) return error();
    return value;
  }

 private:
  explicit Document(std::unique_ptr<detail::Tree> tree);
  std::unique_ptr<detail::Tree> tree_;  // on the heap: Nodes point to it
};

// A settings file: `path` opened as Document::open does, then each
// "key=value" override (as --set gives them) put in, located as "--set key".
// An override without '=' is the error.
Expected<Document> open_with_overrides(const std::string& path, std::string_view what,
                                       const std::vector<std::string>& overrides);

// " (did you mean 'x'?)" for a near miss of `word`, else " (<label>: a, b, c)".
std::string did_you_mean(std::string_view word, const std::vector<std::string>& choices,
                         std::string_view label);

}  // namespace plr::yaml
