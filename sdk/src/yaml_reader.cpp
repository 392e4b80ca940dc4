#include <plr/yaml_reader.hpp>

#include <fmt/format.h>
#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <sstream>
#include <tuple>
#include <unordered_map>

namespace plr::yaml {
namespace detail {

enum class Kind : std::uint8_t { kNull, kScalar, kList, kMap };

struct Value {
  Kind kind = Kind::kNull;
  bool quoted = false;
  int line = 0;  // 1-based; 0 for a value made by Document::set or for an empty document
  int column = 0;
  std::uint32_t label = 0;  // 1 + index into Tree::labels; 0 for a value of the text
  std::string text;
  std::vector<std::uint32_t> children;  // a list's items; a map's key, value, key, value, ...
};

struct Diagnostic {
  bool labelled;
  int line;
  int column;
  std::string text;
};

struct Tree {
  std::string file;
  Limits limits;
  std::vector<Value> values;  // an alias shares the value it names, so this is a DAG
  std::uint32_t root = 0;
  std::vector<std::string> labels;
  std::vector<Diagnostic> diagnostics;
};

}  // namespace detail

namespace {

using detail::Kind;
using detail::Tree;
using detail::Value;

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
// A runaway reader cannot grow the error list without bound.
constexpr std::size_t kMaxDiagnostics = 10'000;

// One line each, however the text was written.
std::string one_line(std::string_view s) {
  std::string out;
  for (char c : s) {
    if (c == '\n')
      out += "\\n";
    else if (c == '\r')
      out += "\\r";
    else if (static_cast<unsigned char>(c) < 0x20 && c != '\t')
      out += '?';
    else
      out += c;
  }
  return out;
}

Location position(const Tree& t, std::uint32_t i) {
  const Value& v = t.values[i];
  if (v.label != 0) return {t.labels[v.label - 1], 0, 0};
  if (v.line == 0) return {t.file, 1, 1};
  return {t.file, v.line, v.column};
}

void record(Tree& t, const Location& at, std::string_view path, std::string_view what) {
  if (t.diagnostics.size() >= kMaxDiagnostics) return;
  std::string text = at.str() + ": ";
  if (!path.empty()) text += std::string(path) + ": ";
  text += what;
  t.diagnostics.push_back({at.line == 0, at.line, at.column, one_line(text)});
}

// Enough of a scalar to recognise it; the location says where the rest is.
std::string shown(const std::string& text) {
  return text.size() > 60 ? text.substr(0, 57) + "..." : text;
}

std::string describe_value(const Value& v) {
  switch (v.kind) {
    case Kind::kMap:
      return "a map";
    case Kind::kList:
      return "a list";
    case Kind::kScalar:
      if (v.text.empty()) return "an empty string";
      return (v.quoted ? "the string '" : "'") + shown(v.text) + "'";
    case Kind::kNull:
      break;
  }
  return "nothing";
}

std::string join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& item : items) out += (out.empty() ? "" : ", ") + item;
  return out;
}

std::string child_path(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

// Edit distance that counts a swap of neighbours as one edit, the commonest typo.
std::size_t typo_distance(std::string_view a, std::string_view b) {
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1])
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  }
  return d[a.size()][b.size()];
}

// YAML 1.2 core schema booleans; "yes"/"on" stay strings (the "Norway problem").
std::optional<bool> plain_bool(const std::string& s) {
  if (s == "true" || s == "True" || s == "TRUE") return true;
  if (s == "false" || s == "False" || s == "FALSE") return false;
  return std::nullopt;
}

struct PlainInt {
  bool is_int = false;
  bool in_range = false;
  std::int64_t value = 0;
};

// YAML 1.2 core schema integers: decimal with optional sign, 0o octal, 0x hex.
PlainInt plain_int(const std::string& s) {
  std::string_view digits = s;
  int base = 10;
  bool negative = false;
  if (digits.substr(0, 2) == "0x") {
    base = 16, digits.remove_prefix(2);
  } else if (digits.substr(0, 2) == "0o") {
    base = 8, digits.remove_prefix(2);
  } else if (!digits.empty() && (digits[0] == '-' || digits[0] == '+')) {
    negative = digits[0] == '-';
    digits.remove_prefix(1);
  }
  if (digits.empty()) return {};
  std::uint64_t magnitude = 0;
  const auto [end, ec] =
      std::from_chars(digits.data(), digits.data() + digits.size(), magnitude, base);
  if (end != digits.data() + digits.size()) return {};
  const std::uint64_t limit =
      static_cast<std::uint64_t>(std::numeric_limits<std::int64_t>::max()) + (negative ? 1 : 0);
  if (ec == std::errc::result_out_of_range || magnitude > limit) return {true, false, 0};
  const auto value =
      negative ? static_cast<std::int64_t>(0 - magnitude) : static_cast<std::int64_t>(magnitude);
  return {true, true, value};
}

// YAML 1.2 core schema floats, without .inf and .nan (is_special_float).
std::optional<double> plain_float(const std::string& s) {
  std::string_view text = s;
  if (!text.empty() && text[0] == '+') text.remove_prefix(1);
  const std::size_t first = !text.empty() && text[0] == '-' ? 1 : 0;
  if (text.size() <= first ||
      !(std::isdigit(static_cast<unsigned char>(text[first])) || text[first] == '.'))
    return std::nullopt;
  double value = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), value);
  if (ec != std::errc() || end != text.data() + text.size()) return std::nullopt;
  return value;
}

bool is_special_float(const std::string& s) {
  static const std::vector<std::string> specials = {".inf",  ".Inf",  ".INF",  "+.inf",
                                                    "+.Inf", "+.INF", "-.inf", "-.Inf",
                                                    "-.INF", ".nan",  ".NaN",  ".NAN"};
  return std::find(specials.begin(), specials.end(), s) != specials.end();
}

// Why the parse stopped early (a limit), with the position.
struct Stop {
  YAML::Mark mark;
  std::string why;
};

// Builds the tree from yaml-cpp's events, so positions, quoting and aliases
// are ours to keep and bound.
class Builder final : public YAML::EventHandler {
 public:
  explicit Builder(Tree& tree) : t_(tree) {}
  std::uint32_t root() const { return root_; }

  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& mark, YAML::anchor_t anchor) override {
    add(Kind::kNull, mark, anchor, false, {});
  }
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t anchor) override {
    const auto it = anchors_.find(anchor);
    // The parser refuses unknown anchors; one still open would make a cycle.
    if (it == anchors_.end() || std::find(open_.begin(), open_.end(), it->second) != open_.end())
      throw Stop{mark, "an alias refers to a value that holds it"};
    attach(it->second);
  }
  void OnScalar(const YAML::Mark& mark, const std::string& tag, YAML::anchor_t anchor,
                const std::string& value) override {
    // yaml-cpp tags a quoted scalar "!" (non-specific), an explicit string !!str.
    add(Kind::kScalar, mark, anchor, tag == "!" || tag == "tag:yaml.org,2002:str", value);
  }
  void OnSequenceStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor,
                       YAML::EmitterStyle::value) override {
    open(add(Kind::kList, mark, anchor, false, {}), mark);
  }
  void OnSequenceEnd() override { open_.pop_back(); }
  void OnMapStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t anchor,
                  YAML::EmitterStyle::value) override {
    open(add(Kind::kMap, mark, anchor, false, {}), mark);
  }
  void OnMapEnd() override { open_.pop_back(); }

 private:
  std::uint32_t add(Kind kind, const YAML::Mark& mark, YAML::anchor_t anchor, bool quoted,
                    const std::string& text) {
    if (t_.values.size() >= t_.limits.max_values)
      throw Stop{mark, fmt::format("more than {} values", t_.limits.max_values)};
    const auto i = static_cast<std::uint32_t>(t_.values.size());
    Value v;
    v.kind = kind;
    v.quoted = quoted;
    v.line = mark.is_null() ? 0 : mark.line + 1;
    v.column = mark.is_null() ? 0 : mark.column + 1;
    v.text = text;
    t_.values.push_back(std::move(v));
    if (anchor != YAML::NullAnchor) anchors_[anchor] = i;
    attach(i);
    return i;
  }
  void attach(std::uint32_t i) {
    if (open_.empty()) {
      if (root_ == kNone) root_ = i;
    } else {
      t_.values[open_.back()].children.push_back(i);
    }
  }
  void open(std::uint32_t i, const YAML::Mark& mark) {
    if (open_.size() >= t_.limits.max_depth)
      throw Stop{mark, fmt::format("nested deeper than {} levels", t_.limits.max_depth)};
    open_.push_back(i);
  }

  Tree& t_;
  std::uint32_t root_ = kNone;
  std::vector<std::uint32_t> open_;
  std::unordered_map<YAML::anchor_t, std::uint32_t> anchors_;
};

std::string at_mark(const std::string& file, const YAML::Mark& mark) {
  if (mark.is_null() || mark.line < 0) return file;
  return fmt::format("{}:{}:{}", file, mark.line + 1, mark.column + 1);
}

// Adds the first document of `text` to the tree; its top value, or why not.
Expected<std::uint32_t> build(Tree& t, std::string_view text, const std::string& where) {
  if (text.size() > t.limits.max_bytes)
    return make_error(PLR_ERR_INVALID,
                      fmt::format("{}: larger than {} bytes", where, t.limits.max_bytes));
  try {
    std::istringstream in{std::string(text)};
    YAML::Parser parser(in);
    Builder builder(t);
    parser.HandleNextDocument(builder);
    if (builder.root() != kNone) return builder.root();
    // No document at all: an empty one.
    t.values.emplace_back();
    return static_cast<std::uint32_t>(t.values.size() - 1);
  } catch (const Stop& s) {
    return make_error(PLR_ERR_INVALID, at_mark(where, s.mark) + ": " + s.why);
  } catch (const YAML::Exception& e) {
    return make_error(PLR_ERR_INVALID, at_mark(where, e.mark) + ": syntax error: " + e.msg);
  } catch (const std::exception& e) {
    return make_error(PLR_ERR_INVALID, where + ": cannot parse: " + e.what());
  }
}

}  // namespace

std::string Location::str() const {
  if (line <= 0) return file;
  return file + ":" + std::to_string(line) + ":" + std::to_string(column);
}

Expected<Document> open_with_overrides(const std::string& path, std::string_view what,
                                       const std::vector<std::string>& overrides) {
  auto doc = Document::open(path, what);
  if (!doc) return doc.error();
  for (const std::string& o : overrides) {
    const auto eq = o.find('=');
    if (eq == std::string::npos)
      return make_error(PLR_ERR_INVALID, "--set " + o + ": expected key=value");
    doc->set(o.substr(0, eq), o.substr(eq + 1), "--set " + o.substr(0, eq));
  }
  return doc;
}

std::string did_you_mean(std::string_view word, const std::vector<std::string>& choices,
                         std::string_view label) {
  const std::string* best = nullptr;
  std::size_t best_distance = std::numeric_limits<std::size_t>::max();
  for (const auto& c : choices) {
    const std::size_t d = typo_distance(word, c);
    if (d < best_distance) best = &c, best_distance = d;
  }
  if (best != nullptr && best_distance <= std::max<std::size_t>(1, word.size() / 3))
    return " (did you mean '" + *best + "'?)";
  return " (" + std::string(label) + ": " + join(choices) + ")";
}

// --- Node --------------------------------------------------------------------

bool Node::is_null() const {
  return present() && tree_->values[value_].kind == Kind::kNull;
}
bool Node::is_scalar() const {
  return present() && tree_->values[value_].kind == Kind::kScalar;
}
bool Node::is_map() const {
  return present() && tree_->values[value_].kind == Kind::kMap;
}
bool Node::is_list() const {
  return present() && tree_->values[value_].kind == Kind::kList;
}

const std::string& Node::text() const {
  static const std::string kEmpty;
  return is_scalar() ? tree_->values[value_].text : kEmpty;
}

bool Node::quoted() const {
  return is_scalar() && tree_->values[value_].quoted;
}

Location Node::location() const {
  if (!present()) return {};
  const Value& v = tree_->values[value_];
  if (v.label != 0) return {tree_->labels[v.label - 1], 0, 0};
  return position(*tree_, anchor_);
}

Location Node::key_location() const {
  if (!present() || key_ == kNone || tree_->values[value_].label != 0) return location();
  return position(*tree_, key_);
}

std::string Node::describe() const {
  return present() ? describe_value(tree_->values[value_]) : "nothing";
}

void Node::error(std::string_view what) const {
  if (present()) record(*tree_, location(), path_, what);
}

void Node::key_error(std::string_view what) const {
  if (present()) record(*tree_, key_location(), path_, what);
}

Node Node::child(std::uint32_t value, std::uint32_t key, std::string path, std::string name) const {
  // A null value's mark points past it (to the next token), so errors about
  // it point at its key, or for a list item at the list.
  std::uint32_t anchor = value;
  if (tree_->values[value].kind == Kind::kNull) anchor = key != kNone ? key : anchor_;
  return Node(tree_, value, key, anchor, std::move(path), std::move(name));
}

std::optional<std::string> Node::string(std::string_view what) const {
  if (!present()) return std::nullopt;
  if (!is_scalar() || text().empty()) {
    error(fmt::format("expected {}, got {}", what, describe()));
    return std::nullopt;
  }
  return text();
}

std::optional<std::int64_t> Node::integer(std::int64_t min, std::int64_t max) const {
  if (!present()) return std::nullopt;
  const PlainInt parsed = is_scalar() && !quoted() ? plain_int(text()) : PlainInt{};
  if (!parsed.is_int) {
    error("expected an integer, got " + describe());
    return std::nullopt;
  }
  if (parsed.in_range && parsed.value >= min && parsed.value <= max) return parsed.value;
  const std::string got = ", got " + shown(text());
  if (parsed.in_range && parsed.value < min && min == 1)
    error("must be positive" + got);
  else if (parsed.in_range && parsed.value < min && min == 0)
    error("must not be negative" + got);
  else
    error(fmt::format("must be between {} and {}{}", min, max, got));
  return std::nullopt;
}

std::optional<double> Node::number(double min, double max) const {
  if (!present()) return std::nullopt;
  std::optional<double> value;
  if (is_scalar() && !quoted()) {
    const PlainInt i = plain_int(text());
    value = i.is_int && i.in_range ? static_cast<double>(i.value) : plain_float(text());
  }
  if (!value || !std::isfinite(*value)) {
    error(is_scalar() && !quoted() && is_special_float(text())
              ? "expected a finite number, got " + describe()
              : "expected a number, got " + describe());
    return std::nullopt;
  }
  if (*value >= min && *value <= max) return value;
  const std::string got = ", got " + shown(text());
  constexpr double kInf = std::numeric_limits<double>::infinity();
  if (min == 0 && max == kInf)
    error("must not be negative" + got);
  else if (max == kInf)
    error(fmt::format("must be at least {}{}", min, got));
  else if (min == -kInf)
    error(fmt::format("must be at most {}{}", max, got));
  else
    error(fmt::format("must be between {} and {}{}", min, max, got));
  return std::nullopt;
}

std::optional<double> Node::positive() const {
  const auto value = number();
  if (!value || *value > 0) return value;
  error("must be positive, got " + shown(text()));
  return std::nullopt;
}

std::optional<bool> Node::boolean() const {
  if (!present()) return std::nullopt;
  const auto b = is_scalar() && !quoted() ? plain_bool(text()) : std::nullopt;
  if (!b) error("expected true or false, got " + describe());
  return b;
}

std::optional<std::string> Node::one_of(const std::vector<std::string>& allowed) const {
  if (!present()) return std::nullopt;
  if (!is_scalar()) {
    error("expected one of: " + join(allowed) + ", got " + describe());
    return std::nullopt;
  }
  if (std::find(allowed.begin(), allowed.end(), text()) != allowed.end()) return text();
  error("'" + text() + "' is not one of: " + join(allowed));
  return std::nullopt;
}

Map Node::map(std::string_view what) const {
  if (!present()) return {};
  if (is_null()) return Map(*this, {});
  if (!is_map()) {
    error(fmt::format("expected {}, got {}", what, describe()));
    return {};
  }
  const std::vector<std::uint32_t> children = tree_->values[value_].children;
  std::vector<Node> entries;
  for (std::size_t i = 0; i + 1 < children.size(); i += 2) {
    const Value& key = tree_->values[children[i]];
    if (key.kind != Kind::kScalar) {
      record(*tree_, position(*tree_, children[i]), path_,
             "a key must be a plain name, got " + describe_value(key));
      continue;
    }
    Node entry = child(children[i + 1], children[i], child_path(path_, key.text), key.text);
    const auto first = std::find_if(entries.begin(), entries.end(),
                                    [&](const Node& other) { return other.name_ == entry.name_; });
    if (first != entries.end()) {
      entry.key_error("duplicate key '" + entry.name_ + "' (first defined at " +
                      first->key_location().str() + ")");
      continue;
    }
    entries.push_back(std::move(entry));
  }
  return Map(*this, std::move(entries));
}

Map Node::map(std::string_view what, const std::vector<std::string>& known) const {
  Map m = map(what);
  std::erase_if(m.entries_, [&](const Node& e) {
    if (std::find(known.begin(), known.end(), e.name()) != known.end()) return false;
    e.key_error("unknown key '" + e.name() + "'" + did_you_mean(e.name(), known, "known keys"));
    return true;
  });
  return m;
}

List Node::list(std::string_view what, std::size_t min_items, std::size_t max_items) const {
  if (!present()) return {};
  if (!is_null() && !is_list()) {
    error(fmt::format("expected {}, got {}", what, describe()));
    return {};
  }
  const std::vector<std::uint32_t> children =
      is_null() ? std::vector<std::uint32_t>{} : tree_->values[value_].children;
  const std::size_t n = children.size();
  if (n < min_items || n > max_items) {
    if (min_items == max_items)
      error(fmt::format("must have exactly {} items, got {}", min_items, n));
    else if (n < min_items)
      error(fmt::format("must have at least {} items, got {}", min_items, n));
    else
      error(fmt::format("must have at most {} items, got {}", max_items, n));
    return {};
  }
  std::vector<Node> items;
  items.reserve(n);
  for (std::size_t i = 0; i < n; ++i)
    items.push_back(child(children[i], kNone, fmt::format("{}[{}]", path_, i), ""));
  return List(std::move(items));
}

nlohmann::json Node::to_json() const {
  if (!present()) return nullptr;
  std::size_t budget = tree_->limits.max_values;
  return to_json(budget, 0);
}

nlohmann::json Node::to_json(std::size_t& budget, std::size_t depth) const {
  if (budget == 0) return nullptr;
  // Aliases may repeat a value many times over (a "billion laughs"), and nest
  // one anchored value in another deeper than the text does.
  if (--budget == 0 || depth > tree_->limits.max_depth) {
    error(budget == 0
              ? fmt::format("more than {} values with aliases expanded", tree_->limits.max_values)
              : fmt::format("nested deeper than {} levels with aliases expanded",
                            tree_->limits.max_depth));
    budget = 0;
    return nullptr;
  }
  const Value& v = tree_->values[value_];
  switch (v.kind) {
    case Kind::kScalar: {
      const std::string& s = v.text;
      if (v.quoted) return s;
      if (auto b = plain_bool(s)) return *b;
      const PlainInt i = plain_int(s);
      if (i.is_int && !i.in_range) {
        error("integer " + shown(s) + " is out of range (64 bits, signed)");
        return nullptr;
      }
      if (i.is_int) return i.value;
      if (is_special_float(s)) {
        error("'" + s + "' (infinity or NaN) has no JSON form");
        return nullptr;
      }
      if (auto f = plain_float(s)) return *f;
      return s;
    }
    case Kind::kList: {
      nlohmann::json array = nlohmann::json::array();
      for (const Node& item : list()) array.push_back(item.to_json(budget, depth + 1));
      return array;
    }
    case Kind::kMap: {
      nlohmann::json object = nlohmann::json::object();
      for (const Node& e : map()) object[e.name()] = e.to_json(budget, depth + 1);
      return object;
    }
    case Kind::kNull:
      break;
  }
  return nullptr;
}

// --- Map ---------------------------------------------------------------------

Node Map::find(std::string_view key) const {
  for (const auto& e : entries_)
    if (e.name() == key) return e;
  return {};
}

Node Map::required(std::string_view key) const {
  Node found = find(key);
  if (!found.present()) self_.key_error(fmt::format("missing required key '{}'", key));
  return found;
}

// --- List --------------------------------------------------------------------

const Node& List::operator[](std::size_t i) const {
  if (i >= items_.size()) {
    std::fprintf(stderr, "plr::yaml::List: item %zu of %zu\n", i, items_.size());
    std::abort();
  }
  return items_[i];
}

// --- Document ----------------------------------------------------------------

Document::Document(std::unique_ptr<detail::Tree> tree) : tree_(std::move(tree)) {}
Document::Document(Document&&) noexcept = default;
Document& Document::operator=(Document&&) noexcept = default;
Document::~Document() = default;

Expected<Document> Document::parse(std::string_view text, std::string file, Limits limits) {
  auto tree = std::make_unique<Tree>();
  tree->file = std::move(file);
  tree->limits = limits;
  auto root = build(*tree, text, tree->file);
  if (!root) return root.error();
  tree->root = *root;
  return Document(std::move(tree));
}

Expected<Document> Document::open(const std::string& path, std::string_view what, Limits limits) {
  const auto fail = [&](const std::string& why) {
    return make_error(PLR_ERR_INVALID, fmt::format("{}: cannot read {}: {}", path, what, why));
  };
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return fail(std::strerror(errno));
  struct stat st {};
  if (::fstat(fd, &st) == 0 && S_ISDIR(st.st_mode)) {
    ::close(fd);
    return fail("it is a folder");
  }
  std::string text;
  char buf[1 << 16];
  for (;;) {
    const ssize_t n = ::read(fd, buf, sizeof buf);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) {
      const int e = errno;
      ::close(fd);
      return fail(std::strerror(e));
    }
    if (n == 0) break;
    text.append(buf, static_cast<std::size_t>(n));
    if (text.size() > limits.max_bytes) {
      ::close(fd);
      return fail(fmt::format("larger than {} bytes", limits.max_bytes));
    }
  }
  ::close(fd);
  return parse(text, path, limits);
}

Node Document::root() const {
  return Node(tree_.get(), tree_->root, kNone, tree_->root, "", "");
}

void Document::set(std::string_view path, std::string_view yaml_value, const std::string& label) {
  Tree& t = *tree_;
  const auto fail = [&](const std::string& where, const std::string& what) {
    if (t.diagnostics.size() < kMaxDiagnostics)
      t.diagnostics.push_back(
          {true, 0, 0, one_line(label + ": " + (where.empty() ? "" : where + ": ") + what)});
  };
  std::vector<std::string> keys;
  for (std::size_t start = 0;;) {
    const std::size_t dot = path.find('.', start);
    keys.emplace_back(path.substr(start, dot == std::string_view::npos ? dot : dot - start));
    if (keys.back().empty()) return fail("", "empty key in the path");
    if (dot == std::string_view::npos) break;
    start = dot + 1;
  }
  t.labels.push_back(label);
  const auto label_id = static_cast<std::uint32_t>(t.labels.size());
  const std::size_t first_new = t.values.size();
  auto value = build(t, yaml_value, label);
  if (!value) {
    t.values.resize(first_new);
    // yaml-cpp's own words, after "<label>: syntax error: ".
    const std::string& message = value.error().message;
    const auto cause = message.find("syntax error: ");
    return fail(std::string(path),
                "invalid YAML value '" + std::string(yaml_value) +
                    "': " + (cause == std::string::npos ? message : message.substr(cause + 14)));
  }
  const auto made = [&](Kind kind, std::string text = {}) {
    Value v;
    v.kind = kind;
    v.label = label_id;
    v.text = std::move(text);
    t.values.push_back(std::move(v));
    return static_cast<std::uint32_t>(t.values.size() - 1);
  };
  for (std::size_t i = first_new; i < t.values.size(); ++i) t.values[i].label = label_id;

  std::uint32_t at = t.root;
  std::string walked;
  for (std::size_t i = 0; i < keys.size(); ++i) {
    if (t.values[at].kind == Kind::kNull) {
      t.values[at].kind = Kind::kMap;
      // The empty document's top keeps its place in the file.
      if (at != t.root) t.values[at].label = label_id;
    }
    if (t.values[at].kind != Kind::kMap)
      return fail(
          walked.empty() ? "(top level)" : walked,
          "expected a map to set '" + keys[i] + "' in, got " + describe_value(t.values[at]));
    std::size_t slot = 0;  // position of the entry's value in `children`, 0 when absent
    const auto& children = t.values[at].children;
    for (std::size_t c = 0; c + 1 < children.size() && slot == 0; c += 2) {
      const Value& key = t.values[children[c]];
      if (key.kind == Kind::kScalar && key.text == keys[i]) slot = c + 1;
    }
    const bool last = i + 1 == keys.size();
    if (slot == 0) {
      const std::uint32_t key = made(Kind::kScalar, keys[i]);
      const std::uint32_t next = last ? *value : made(Kind::kMap);
      t.values[at].children.push_back(key);
      t.values[at].children.push_back(next);
      at = next;
    } else if (last) {
      t.values[at].children[slot] = *value;
    } else {
      at = t.values[at].children[slot];
    }
    walked = child_path(walked, keys[i]);
  }
}

bool Document::ok() const {
  return tree_->diagnostics.empty();
}

Error Document::error() const {
  auto diagnostics = tree_->diagnostics;
  std::stable_sort(diagnostics.begin(), diagnostics.end(),
                   [](const detail::Diagnostic& a, const detail::Diagnostic& b) {
                     return std::tie(a.labelled, a.line, a.column) <
                            std::tie(b.labelled, b.line, b.column);
                   });
  const std::size_t shown = tree_->limits.max_errors == 0
                                ? diagnostics.size()
                                : std::min(diagnostics.size(), tree_->limits.max_errors);
  std::string text;
  for (std::size_t i = 0; i < shown; ++i) text += (i == 0 ? "" : "\n") + diagnostics[i].text;
  return make_error(PLR_ERR_INVALID, std::move(text));
}

}  // namespace plr::yaml
