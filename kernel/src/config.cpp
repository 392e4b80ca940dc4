#include "config.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <string_view>
#include <tuple>

namespace plr::kernel {

std::string SourceLocation::str() const {
  if (line <= 0) return file;
  return file + ":" + std::to_string(line) + ":" + std::to_string(column);
}

const NodeConfig* Config::node(const std::string& name) const {
  for (const auto& n : nodes)
    if (n.name == name) return &n;
  return nullptr;
}

const HostConfig* Config::host(const std::string& name) const {
  for (const auto& h : hosts)
    if (h.name == name) return &h;
  return nullptr;
}

TopicConfig Config::topic(const std::string& name) const {
  for (const auto& t : topics)
    if (t.name == name) return t;
  TopicConfig defaults;
  defaults.name = name;
  return defaults;
}

namespace {

namespace fs = std::filesystem;

const std::vector<std::string> kTopKeys = {
    "pipeline", "plugin_paths", "clock",  "cpu_wake_latency_us",
    "hosts",    "nodes",        "topics", "remote"};
const std::vector<std::string> kHostKeys = {"restart", "max_restarts", "backoff_ms"};
const std::vector<std::string> kNodeKeys = {"plugin", "host", "params", "remap"};
const std::vector<std::string> kTopicKeys = {"policy", "depth", "slot_size", "busy_poll",
                                             "spin_us"};
const std::vector<std::string> kRemoteKeys = {"dds"};
const std::vector<std::string> kDdsKeys = {"domain",
                                           "interfaces",
                                           "export",
                                           "import",
                                           "resend_on_provider_loss",
                                           "allow_remote_control",
                                           "security_dir"};

std::string join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& item : items) out += (out.empty() ? "" : ", ") + item;
  return out;
}

// Whether `path` is `prefix` or lies below it ("a.b" is below "a", so is "a[0]").
bool starts_with_path(const std::string& path, const std::string& prefix) {
  return path == prefix ||
         (path.size() > prefix.size() && path.compare(0, prefix.size(), prefix) == 0 &&
          (path[prefix.size()] == '.' || path[prefix.size()] == '['));
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

// " (did you mean 'x'?)" for a near miss, else the list of choices.
std::string hint(const std::string& word, const std::vector<std::string>& choices,
                 const std::string& list_label) {
  const std::string* best = nullptr;
  std::size_t best_distance = std::numeric_limits<std::size_t>::max();
  for (const auto& c : choices) {
    const std::size_t d = typo_distance(word, c);
    if (d < best_distance) best = &c, best_distance = d;
  }
  if (best != nullptr && best_distance <= std::max<std::size_t>(1, word.size() / 3))
    return " (did you mean '" + *best + "'?)";
  return " (" + list_label + ": " + join(choices) + ")";
}

bool only_chars(const std::string& s, std::string_view extra) {
  if (s.empty()) return false;
  return std::all_of(s.begin(), s.end(), [&](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
           extra.find(c) != std::string_view::npos;
  });
}

// "letters, digits, '_' and '/'" for extra = "_/".
std::string allowed_chars(std::string_view extra) {
  std::vector<std::string> parts = {"letters", "digits"};
  for (char c : extra) parts.push_back(std::string("'") + c + "'");
  std::string out;
  for (std::size_t i = 0; i < parts.size(); ++i)
    out += (i == 0 ? "" : i + 1 == parts.size() ? " and " : ", ") + parts[i];
  return out;
}

bool is_quoted(const YAML::Node& n) {
  return n.Tag() == "!" || n.Tag() == "tag:yaml.org,2002:str";
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

// YAML 1.2 core schema floats, without .inf and .nan (see to_json).
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

std::string describe(const YAML::Node& n) {
  switch (n.Type()) {
    case YAML::NodeType::Map:
      return "a map";
    case YAML::NodeType::Sequence:
      return "a list";
    case YAML::NodeType::Scalar:
      return (is_quoted(n) ? "the string '" : "'") + n.Scalar() + "'";
    default:
      return "nothing";
  }
}

struct Entry {
  std::string name;
  YAML::Node key;
  YAML::Node value;
  std::string path;
};

struct Diagnostic {
  bool from_override;
  int line;
  int column;
  std::string text;
};

// Walks the YAML tree, converting it into a Config and collecting every
// error found, so one run shows the user all of them.
class Checker {
 public:
  Checker(std::string file, std::vector<std::string> override_paths)
      : file_(std::move(file)), overrides_(std::move(override_paths)) {}

  // A value that an override put there is reported as "--set <path>"; the
  // YAML it came from has no position in the file.
  SourceLocation where(const YAML::Node& at, const std::string& path) const {
    for (auto o = overrides_.rbegin(); o != overrides_.rend(); ++o)
      if (starts_with_path(path, *o)) return {"--set " + *o, 0, 0};
    const YAML::Mark mark = at.Mark();
    if (mark.is_null()) {
      // Maps created on the way to an override's target have no mark.
      for (auto o = overrides_.rbegin(); o != overrides_.rend(); ++o)
        if (!path.empty() && starts_with_path(*o, path)) return {"--set " + *o, 0, 0};
      return {file_, 1, 1};
    }
    return {file_, mark.line + 1, mark.column + 1};
  }

  void error(const YAML::Node& at, const std::string& path, const std::string& what) {
    const SourceLocation loc = where(at, path);
    diagnostics_.push_back({loc.line == 0, loc.line, loc.column,
                            loc.str() + ": " + (path.empty() ? "" : path + ": ") + what});
  }
  void error(const Entry& e, const std::string& what) { error(anchor(e), e.path, what); }

  void override_error(const std::string& override_path, const std::string& path,
                      const std::string& what) {
    diagnostics_.push_back({true, 0, 0, "--set " + override_path + ": " + path + ": " + what});
  }

  bool ok() const { return diagnostics_.empty(); }

  std::string message() {
    std::stable_sort(diagnostics_.begin(), diagnostics_.end(),
                     [](const Diagnostic& a, const Diagnostic& b) {
                       return std::tie(a.from_override, a.line, a.column) <
                              std::tie(b.from_override, b.line, b.column);
                     });
    std::string out;
    for (const auto& d : diagnostics_) out += (out.empty() ? "" : "\n") + d.text;
    return out;
  }

  // A null value's mark points past it (to the next token), so errors about
  // it point at its key instead.
  static YAML::Node anchor(const Entry& e) {
    return e.value.IsNull() || !e.value.IsDefined() ? e.key : e.value;
  }

  // The entries of a map in document order. Duplicate, non-scalar and
  // (given `known`) unknown keys are reported and left out.
  std::vector<Entry> entries(const YAML::Node& map, const std::string& path,
                             const std::vector<std::string>* known) {
    std::vector<Entry> out;
    for (auto it = map.begin(); it != map.end(); ++it) {
      const YAML::Node key = it->first;
      if (!key.IsScalar()) {
        error(key, path, "a key must be a plain name, got " + describe(key));
        continue;
      }
      Entry e{key.Scalar(), key, it->second, child_path(path, key.Scalar())};
      if (known != nullptr && std::find(known->begin(), known->end(), e.name) == known->end()) {
        error(key, e.path, "unknown key '" + e.name + "'" + hint(e.name, *known, "known keys"));
        continue;
      }
      const auto first = std::find_if(out.begin(), out.end(),
                                      [&](const Entry& other) { return other.name == e.name; });
      if (first != out.end()) {
        error(key, e.path,
              "duplicate key '" + e.name + "' (first defined at " +
                  where(first->key, first->path).str() + ")");
        continue;
      }
      out.push_back(std::move(e));
    }
    return out;
  }

  // A map that may also be left empty (null).
  bool optional_map(const Entry& e, const std::string& what) {
    if (e.value.IsNull() || e.value.IsMap()) return true;
    error(e, "expected " + what + ", got " + describe(e.value));
    return false;
  }

  std::optional<std::string> string_value(const Entry& e) {
    if (!e.value.IsScalar()) {
      error(e, "expected a string, got " + describe(e.value));
      return std::nullopt;
    }
    if (e.value.Scalar().empty()) {
      error(e, "expected a non-empty string");
      return std::nullopt;
    }
    return e.value.Scalar();
  }

  std::optional<std::int64_t> int_value(const Entry& e, std::int64_t min, std::int64_t max) {
    const PlainInt parsed =
        e.value.IsScalar() && !is_quoted(e.value) ? plain_int(e.value.Scalar()) : PlainInt{};
    if (!parsed.is_int) {
      error(e, "expected an integer, got " + describe(e.value));
      return std::nullopt;
    }
    if (!parsed.in_range || parsed.value < min || parsed.value > max) {
      const std::string got = ", got " + e.value.Scalar();
      if (parsed.in_range && parsed.value < min && min == 1) {
        error(e, "must be positive" + got);
      } else if (parsed.in_range && parsed.value < min && min == 0) {
        error(e, "must not be negative" + got);
      } else {
        error(e, "must be between " + std::to_string(min) + " and " + std::to_string(max) + got);
      }
      return std::nullopt;
    }
    return parsed.value;
  }

  std::optional<bool> bool_value(const Entry& e) {
    const auto b =
        e.value.IsScalar() && !is_quoted(e.value) ? plain_bool(e.value.Scalar()) : std::nullopt;
    if (!b) error(e, "expected true or false, got " + describe(e.value));
    return b;
  }

  std::optional<std::string> enum_value(const Entry& e, const std::vector<std::string>& allowed) {
    if (!e.value.IsScalar()) {
      error(e, "expected one of: " + join(allowed) + ", got " + describe(e.value));
      return std::nullopt;
    }
    const std::string& s = e.value.Scalar();
    if (std::find(allowed.begin(), allowed.end(), s) != allowed.end()) return s;
    error(e, "'" + s + "' is not one of: " + join(allowed));
    return std::nullopt;
  }

  // A list of strings; `name_chars`, if given, are the characters allowed
  // besides letters and digits.
  std::optional<std::vector<std::string>> string_list(const Entry& e,
                                                      std::optional<std::string_view> name_chars,
                                                      const std::string& what) {
    if (e.value.IsNull()) return std::vector<std::string>{};
    if (!e.value.IsSequence()) {
      error(e, "expected a list of " + what + ", got " + describe(e.value));
      return std::nullopt;
    }
    std::vector<std::string> out;
    bool ok = true;
    for (std::size_t i = 0; i < e.value.size(); ++i) {
      const YAML::Node item = e.value[i];
      const std::string path = e.path + "[" + std::to_string(i) + "]";
      if (!item.IsScalar() || item.Scalar().empty()) {
        error(item.IsNull() ? anchor(e) : item, path,
              "expected " + what + ", got " + describe(item));
        ok = false;
      } else if (name_chars && !only_chars(item.Scalar(), *name_chars)) {
        error(item, path, "'" + item.Scalar() + "' may contain only " + allowed_chars(*name_chars));
        ok = false;
      } else {
        out.push_back(item.Scalar());
      }
    }
    if (!ok) return std::nullopt;
    return out;
  }

  // A name made of letters, digits and `extra`; reports `what` otherwise.
  bool check_name(const YAML::Node& at, const std::string& path, const std::string& name,
                  const std::string& what, std::string_view extra) {
    if (only_chars(name, extra)) return true;
    error(at, path, what + " '" + name + "' may contain only " + allowed_chars(extra));
    return false;
  }

  // Any YAML as JSON: plain scalars resolve per the YAML 1.2 core schema,
  // quoted scalars stay strings.
  nlohmann::json to_json(const YAML::Node& n, const std::string& path) {
    switch (n.Type()) {
      case YAML::NodeType::Scalar: {
        const std::string& s = n.Scalar();
        if (is_quoted(n)) return s;
        if (auto b = plain_bool(s)) return *b;
        const PlainInt i = plain_int(s);
        if (i.is_int && !i.in_range) {
          error(n, path, "integer " + s + " is out of range (64 bits, signed)");
          return nullptr;
        }
        if (i.is_int) return i.value;
        if (is_special_float(s)) {
          error(n, path, "'" + s + "' (infinity or NaN) has no JSON form");
          return nullptr;
        }
        if (auto f = plain_float(s)) return *f;
        return s;
      }
      case YAML::NodeType::Sequence: {
        nlohmann::json array = nlohmann::json::array();
        for (std::size_t i = 0; i < n.size(); ++i) {
          array.push_back(to_json(n[i], path + "[" + std::to_string(i) + "]"));
        }
        return array;
      }
      case YAML::NodeType::Map: {
        nlohmann::json object = nlohmann::json::object();
        for (const Entry& e : entries(n, path, nullptr)) object[e.name] = to_json(e.value, e.path);
        return object;
      }
      default:
        return nullptr;
    }
  }

 private:
  std::string file_;
  std::vector<std::string> overrides_;
  std::vector<Diagnostic> diagnostics_;
};

const Entry* find(const std::vector<Entry>& entries, const std::string& name) {
  for (const auto& e : entries)
    if (e.name == name) return &e;
  return nullptr;
}

constexpr std::string_view kNodeNameChars = "_";
constexpr std::string_view kBusNameChars = "_/";

std::string resolve_path(const fs::path& base, const std::string& path) {
  const fs::path p(path);
  return (p.is_absolute() ? p : base / p).lexically_normal().string();
}

// Returns false if the hosts section is unusable, so node hosts cannot be checked.
bool parse_hosts(Checker& c, const Entry* e, Config& config) {
  const bool usable = e == nullptr || c.optional_map(*e, "a map of host name -> settings");
  if (e != nullptr && usable) {
    for (const Entry& h : c.entries(e->value, e->path, nullptr)) {
      c.check_name(h.key, h.path, h.name, "host name", kNodeNameChars);
      HostConfig host;
      host.name = h.name;
      host.where = c.where(h.key, h.path);
      if (c.optional_map(h, "a map of host settings")) {
        const auto settings = c.entries(h.value, h.path, &kHostKeys);
        if (const Entry* s = find(settings, "restart")) {
          if (auto v = c.enum_value(*s, {"never", "on-failure"}))
            host.restart = *v == "never" ? RestartPolicy::Never : RestartPolicy::OnFailure;
        }
        if (const Entry* s = find(settings, "max_restarts")) {
          if (auto v = c.int_value(*s, 0, std::numeric_limits<int>::max()))
            host.max_restarts = static_cast<int>(*v);
        }
        if (const Entry* s = find(settings, "backoff_ms")) {
          if (auto v = c.int_value(*s, 0, std::numeric_limits<int>::max()))
            host.backoff_ms = static_cast<int>(*v);
        }
      }
      config.hosts.push_back(std::move(host));
    }
  }
  if (config.host("main") == nullptr) {
    HostConfig main;
    main.name = "main";
    main.where = {config.file, 0, 0};
    config.hosts.insert(config.hosts.begin(), std::move(main));
  }
  return usable;
}

void parse_node(Checker& c, const Entry& n, Config& config, bool hosts_ok) {
  c.check_name(n.key, n.path, n.name, "node name", kNodeNameChars);
  NodeConfig node;
  node.name = n.name;
  node.where = c.where(n.key, n.path);
  if (!c.optional_map(n, "a map with a 'plugin' key")) return;
  const auto fields = c.entries(n.value, n.path, &kNodeKeys);
  if (const Entry* f = find(fields, "plugin")) {
    if (auto v = c.string_value(*f)) {
      if (c.check_name(Checker::anchor(*f), f->path, *v, "plug-in name", "_-")) node.plugin = *v;
    }
  } else {
    c.error(n.key, n.path, "missing required key 'plugin'");
  }
  if (const Entry* f = find(fields, "host")) {
    if (auto v = c.string_value(*f)) {
      node.host = *v;
      if (hosts_ok && config.host(*v) == nullptr) {
        std::vector<std::string> names;
        for (const auto& h : config.hosts) names.push_back(h.name);
        c.error(*f, "host '" + *v + "' is not defined in 'hosts'" + hint(*v, names, "defined"));
      }
    }
  }
  if (const Entry* f = find(fields, "params")) {
    if (c.optional_map(*f, "a map of parameters") && f->value.IsMap())
      node.params = c.to_json(f->value, f->path);
  }
  if (const Entry* f = find(fields, "remap")) {
    if (c.optional_map(*f, "a map of name -> bus name")) {
      for (const Entry& r : c.entries(f->value, f->path, nullptr)) {
        const bool key_ok =
            c.check_name(r.key, r.path, r.name, "topic or service name", kBusNameChars);
        auto target = c.string_value(r);
        if (target && key_ok &&
            c.check_name(Checker::anchor(r), r.path, *target, "topic or service name",
                         kBusNameChars))
          node.remap[r.name] = *target;
      }
    }
  }
  config.nodes.push_back(std::move(node));
}

void parse_nodes(Checker& c, const YAML::Node& root, const Entry* e, Config& config,
                 bool hosts_ok) {
  if (e == nullptr) {
    c.error(root, "", "missing required key 'nodes'");
    return;
  }
  if (!c.optional_map(*e, "a map of node name -> node")) return;
  if (e->value.IsNull() || e->value.size() == 0) {
    c.error(*e, "no nodes defined (at least one is required)");
    return;
  }
  for (const Entry& n : c.entries(e->value, e->path, nullptr)) parse_node(c, n, config, hosts_ok);
}

void parse_topics(Checker& c, const Entry& e, Config& config) {
  if (!c.optional_map(e, "a map of topic name -> settings")) return;
  for (const Entry& t : c.entries(e.value, e.path, nullptr)) {
    c.check_name(t.key, t.path, t.name, "topic name", kBusNameChars);
    TopicConfig topic;
    topic.name = t.name;
    topic.where = c.where(t.key, t.path);
    if (c.optional_map(t, "a map of topic settings")) {
      const auto settings = c.entries(t.value, t.path, &kTopicKeys);
      if (const Entry* s = find(settings, "policy")) {
        if (auto v = c.enum_value(*s, {"keep_last", "reliable"}))
          topic.policy = *v == "keep_last" ? TopicPolicy::KeepLast : TopicPolicy::Reliable;
      }
      constexpr auto kMax = std::numeric_limits<std::int64_t>::max();
      if (const Entry* s = find(settings, "depth")) {
        if (auto v = c.int_value(*s, 1, kMax)) topic.depth = static_cast<std::size_t>(*v);
      }
      if (const Entry* s = find(settings, "slot_size")) {
        if (auto v = c.int_value(*s, 1, kMax)) topic.slot_size = static_cast<std::size_t>(*v);
      }
      if (const Entry* s = find(settings, "busy_poll")) {
        if (auto v = c.bool_value(*s)) topic.busy_poll = *v;
      }
      if (const Entry* s = find(settings, "spin_us")) {
        if (auto v = c.int_value(*s, 0, 10'000)) topic.spin_us = static_cast<std::uint32_t>(*v);
      }
    }
    config.topics.push_back(std::move(topic));
  }
}

void parse_remote(Checker& c, const Entry& e, const fs::path& folder, Config& config) {
  if (!c.optional_map(e, "a map with a 'dds' key")) return;
  const auto remote = c.entries(e.value, e.path, &kRemoteKeys);
  const Entry* d = find(remote, "dds");
  if (d == nullptr || !c.optional_map(*d, "a map of DDS settings")) return;
  DdsConfig& dds = config.dds;
  dds.enabled = true;
  const auto settings = c.entries(d->value, d->path, &kDdsKeys);
  if (const Entry* s = find(settings, "domain")) {
    // Cyclone DDS maps domains 0..232 onto UDP ports; higher ones overflow.
    if (auto v = c.int_value(*s, 0, 232)) dds.domain = static_cast<int>(*v);
  }
  if (const Entry* s = find(settings, "interfaces")) {
    if (auto v = c.string_list(*s, std::nullopt, "interface names")) dds.interfaces = *v;
  }
  if (const Entry* s = find(settings, "export")) {
    if (auto v = c.string_list(*s, "_/*", "topic or service patterns")) dds.export_patterns = *v;
  }
  if (const Entry* s = find(settings, "import")) {
    if (auto v = c.string_list(*s, "_/*", "topic or service patterns")) dds.import_patterns = *v;
  }
  if (const Entry* s = find(settings, "resend_on_provider_loss")) {
    if (auto v = c.string_list(*s, "_/*", "service patterns")) dds.resend_patterns = *v;
  }
  if (const Entry* s = find(settings, "security_dir")) {
    if (s->value.IsScalar() && s->value.Scalar().empty()) {
      dds.security_dir.clear();
    } else if (auto v = c.string_value(*s)) {
      dds.security_dir = resolve_path(folder, *v);
    }
  }
  if (const Entry* s = find(settings, "allow_remote_control")) {
    if (auto v = c.bool_value(*s)) {
      dds.allow_remote_control = *v;
      if (*v && dds.security_dir.empty())
        c.error(*s, "remote control needs 'security_dir' (DDS Security material)");
    }
  }
}

Config build(Checker& c, const YAML::Node& root, const std::string& file_name) {
  Config config;
  const fs::path file = fs::absolute(file_name).lexically_normal();
  config.file = file.string();
  config.pipeline = file.stem().string();
  const auto top = c.entries(root, "", &kTopKeys);
  if (const Entry* e = find(top, "pipeline")) {
    if (auto v = c.string_value(*e)) config.pipeline = *v;
  }
  if (const Entry* e = find(top, "plugin_paths")) {
    if (auto v = c.string_list(*e, std::nullopt, "folder paths")) {
      for (const auto& p : *v) config.plugin_paths.push_back(resolve_path(file.parent_path(), p));
    }
  }
  if (const Entry* e = find(top, "clock")) {
    if (auto v = c.enum_value(*e, {"wall", "sim"})) config.clock = *v;
  }
  if (const Entry* e = find(top, "cpu_wake_latency_us")) {
    if (auto v = c.int_value(*e, 0, std::numeric_limits<std::int32_t>::max()))
      config.cpu_wake_latency_us = static_cast<std::int32_t>(*v);
  }
  const bool hosts_ok = parse_hosts(c, find(top, "hosts"), config);
  parse_nodes(c, root, find(top, "nodes"), config, hosts_ok);
  if (const Entry* e = find(top, "topics")) parse_topics(c, *e, config);
  if (const Entry* e = find(top, "remote")) parse_remote(c, *e, file.parent_path(), config);
  return config;
}

std::vector<std::string> split_path(const std::string& path) {
  std::vector<std::string> parts;
  std::size_t start = 0;
  while (true) {
    const std::size_t dot = path.find('.', start);
    parts.push_back(path.substr(start, dot - start));
    if (dot == std::string::npos) return parts;
    start = dot + 1;
  }
}

Status check_override_path(const std::string& path) {
  for (const auto& key : split_path(path)) {
    if (key.empty())
      return make_error(PLR_ERR_INVALID, "--set " + path + ": empty key in the path");
  }
  return {};
}

// Sets the value at the override's path, creating maps on the way.
void apply(Checker& c, YAML::Node& root, const Override& o) {
  YAML::Node value;
  try {
    value = YAML::Load(o.value);
  } catch (const YAML::ParserException& e) {
    c.override_error(o.path, o.path, "invalid YAML value '" + o.value + "': " + e.msg);
    return;
  }
  const auto keys = split_path(o.path);
  YAML::Node at = root;
  std::string path;
  for (std::size_t i = 0; i < keys.size(); ++i) {
    if (!at.IsMap() && !at.IsNull()) {
      c.override_error(o.path, path.empty() ? "(top level)" : path,
                       "expected a map to set '" + keys[i] + "' in, got " + describe(at));
      return;
    }
    if (i + 1 == keys.size()) {
      at[keys[i]] = value;
      return;
    }
    YAML::Node next = at[keys[i]];
    if (!next.IsDefined() || next.IsNull()) next = YAML::Node(YAML::NodeType::Map);
    at.reset(next);  // rebinds; operator= would overwrite the node's content
    path = child_path(path, keys[i]);
  }
}

}  // namespace

Expected<Override> parse_override(const std::string& text) {
  const std::size_t eq = text.find('=');
  if (eq == std::string::npos || eq == 0)
    return make_error(PLR_ERR_INVALID, "--set " + text + ": expected key.path=value");
  Override o{text.substr(0, eq), text.substr(eq + 1)};
  if (auto checked = check_override_path(o.path); !checked) return checked.error();
  return o;
}

Expected<Config> parse_config(const std::string& yaml_text, const std::string& file_name,
                              const std::vector<Override>& overrides) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::ParserException& e) {
    return make_error(PLR_ERR_INVALID, file_name + ":" + std::to_string(e.mark.line + 1) + ":" +
                                           std::to_string(e.mark.column + 1) +
                                           ": syntax error: " + e.msg);
  }
  std::vector<std::string> override_paths;
  for (const auto& o : overrides) override_paths.push_back(o.path);
  Checker c(file_name, override_paths);
  for (const auto& o : overrides) {
    if (auto checked = check_override_path(o.path); !checked) return checked.error();
    apply(c, root, o);
  }
  if (!c.ok()) return make_error(PLR_ERR_INVALID, c.message());
  if (!root.IsMap()) {
    c.error(root, "",
            root.IsNull() ? "the config is empty (expected a map with a 'nodes' key)"
                          : "expected a map at the top level, got " + describe(root));
    return make_error(PLR_ERR_INVALID, c.message());
  }
  Config config = build(c, root, file_name);
  if (!c.ok()) return make_error(PLR_ERR_INVALID, c.message());
  return config;
}

Expected<Config> load_config(const std::string& file, const std::vector<Override>& overrides) {
  std::error_code ec;
  if (fs::is_directory(file, ec))
    return make_error(PLR_ERR_INVALID, file + ": cannot read the config: it is a folder");
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    return make_error(PLR_ERR_INVALID, file + ": cannot read the config: " + std::strerror(errno));
  }
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad())
    return make_error(PLR_ERR_INVALID, file + ": cannot read the config: " + std::strerror(errno));
  return parse_config(text.str(), file, overrides);
}

}  // namespace plr::kernel
