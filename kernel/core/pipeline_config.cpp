#include "pipeline_config.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <string_view>

namespace plr::kernel {

const NodeConfig* PipelineConfig::node(const std::string& name) const {
  for (const auto& n : nodes)
    if (n.name == name) return &n;
  return nullptr;
}

const HostConfig* PipelineConfig::host(const std::string& name) const {
  for (const auto& h : hosts)
    if (h.name == name) return &h;
  return nullptr;
}

TopicSettings PipelineConfig::topic(const std::string& name) const {
  for (const auto& t : topics)
    if (t.name == name) return t;
  TopicSettings defaults;
  defaults.name = name;
  return defaults;
}

namespace {

namespace fs = std::filesystem;
using yaml::List;
using yaml::Map;
using yaml::Node;

// `shared` holds values several nodes use, each defined once with an anchor
// (&name) and referenced from the nodes' params with an alias (*name); the
// kernel reads nothing else from it.
const std::vector<std::string> kTopKeys = {
    "pipeline", "plugin_paths", "clock", "cpu_wake_latency_us", "hosts", "nodes",
    "topics",   "remote",       "shared"};
const std::vector<std::string> kHostKeys = {"restart", "max_restarts", "restart_window_s",
                                            "backoff_ms"};
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

constexpr std::string_view kNodeNameChars = "_";
constexpr std::string_view kBusNameChars = "_/";
// A message of the largest kind (a world state with its octree) is tens of
// MiB; a topic's segment holds `depth` slots of this size.
constexpr std::int64_t kMaxSlotSize = std::int64_t{256} << 20;
constexpr std::int64_t kMaxTopicDepth = 4096;

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

// An entry's key made of letters, digits and `extra`; reported at the key otherwise.
bool check_key_name(const Node& entry, const std::string& what, std::string_view extra) {
  if (only_chars(entry.name(), extra)) return true;
  entry.key_error(what + " '" + entry.name() + "' may contain only " + allowed_chars(extra));
  return false;
}

// A value `name` made of letters, digits and `extra`; reported at the value otherwise.
bool check_value_name(const Node& value, const std::string& name, const std::string& what,
                      std::string_view extra) {
  if (only_chars(name, extra)) return true;
  value.error(what + " '" + name + "' may contain only " + allowed_chars(extra));
  return false;
}

// A list of non-empty strings (null: none); `name_chars`, if given, are the
// characters allowed besides letters and digits. Nothing when any is wrong.
std::optional<std::vector<std::string>> string_list(const Node& n,
                                                    std::optional<std::string_view> name_chars,
                                                    const std::string& what) {
  const List items = n.list("a list of " + what);
  if (!items) return std::nullopt;
  std::vector<std::string> out;
  bool ok = true;
  for (const Node& item : items) {
    if (!item.is_scalar() || item.text().empty()) {
      item.error("expected " + what + ", got " + item.describe());
      ok = false;
    } else if (name_chars && !only_chars(item.text(), *name_chars)) {
      item.error("'" + item.text() + "' may contain only " + allowed_chars(*name_chars));
      ok = false;
    } else {
      out.push_back(item.text());
    }
  }
  if (!ok) return std::nullopt;
  return out;
}

std::string resolve_path(const fs::path& base, const std::string& path) {
  const fs::path p(path);
  return (p.is_absolute() ? p : base / p).lexically_normal().string();
}

// Returns false if the hosts section is unusable, so node hosts cannot be checked.
bool parse_hosts(const Node& section, PipelineConfig& config) {
  const Map hosts = section.map("a map of host name -> settings");
  for (const Node& h : hosts) {
    check_key_name(h, "host name", kNodeNameChars);
    HostConfig host;
    host.name = h.name();
    host.where = h.key_location();
    const Map settings = h.map("a map of host settings", kHostKeys);
    if (auto v = settings.find("restart").one_of({"never", "on-failure"}))
      host.restart = *v == "never" ? RestartPolicy::Never : RestartPolicy::OnFailure;
    if (auto v = settings.find("max_restarts").integer(0, std::numeric_limits<int>::max()))
      host.max_restarts = static_cast<int>(*v);
    // A day: longer would count a crash of yesterday against today's run.
    if (auto v = settings.find("restart_window_s").number(0.001, 86400)) host.restart_window_s = *v;
    // A minute at most between a crash and its restart, however many.
    if (auto v = settings.find("backoff_ms").integer(0, 60'000))
      host.backoff_ms = static_cast<int>(*v);
    config.hosts.push_back(std::move(host));
  }
  if (config.host("main") == nullptr) {
    HostConfig main;
    main.name = "main";
    main.where = {config.file, 0, 0};
    config.hosts.insert(config.hosts.begin(), std::move(main));
  }
  return !section.present() || static_cast<bool>(hosts);
}

void parse_node(const Node& n, PipelineConfig& config, bool hosts_ok) {
  check_key_name(n, "node name", kNodeNameChars);
  NodeConfig node;
  node.name = n.name();
  node.where = n.key_location();
  const Map fields = n.map("a map with a 'plugin' key", kNodeKeys);
  if (!fields) return;
  const Node plugin = fields.required("plugin");
  if (auto v = plugin.string()) {
    if (check_value_name(plugin, *v, "plug-in name", "_-")) node.plugin = *v;
  }
  const Node host = fields.find("host");
  if (auto v = host.string()) {
    node.host = *v;
    if (hosts_ok && config.host(*v) == nullptr) {
      std::vector<std::string> names;
      for (const auto& h : config.hosts) names.push_back(h.name);
      host.error("host '" + *v + "' is not defined in 'hosts'" +
                 yaml::did_you_mean(*v, names, "defined"));
    }
  }
  // Checked here, not with map(): to_json() reports the map's keys itself.
  const Node params = fields.find("params");
  if (params.is_map())
    node.params = params.to_json();
  else if (params.present() && !params.is_null())
    params.error("expected a map of parameters, got " + params.describe());
  for (const Node& r : fields.find("remap").map("a map of name -> bus name")) {
    const bool key_ok = check_key_name(r, "topic or service name", kBusNameChars);
    auto target = r.string();
    if (target && key_ok && check_value_name(r, *target, "topic or service name", kBusNameChars))
      node.remap[r.name()] = *target;
  }
  config.nodes.push_back(std::move(node));
}

void parse_nodes(const Map& top, PipelineConfig& config, bool hosts_ok) {
  const Node section = top.required("nodes");
  const Map nodes = section.map("a map of node name -> node");
  if (!nodes) return;
  if (nodes.size() == 0) {
    section.error("no nodes defined (at least one is required)");
    return;
  }
  for (const Node& n : nodes) parse_node(n, config, hosts_ok);
}

void parse_topics(const Node& section, PipelineConfig& config) {
  for (const Node& t : section.map("a map of topic name -> settings")) {
    check_key_name(t, "topic name", kBusNameChars);
    TopicSettings topic;
    topic.name = t.name();
    topic.where = t.key_location();
    const Map settings = t.map("a map of topic settings", kTopicKeys);
    if (auto v = settings.find("policy").one_of({"keep_last", "reliable"}))
      topic.policy = *v == "keep_last" ? TopicPolicy::KeepLast : TopicPolicy::Reliable;
    if (auto v = settings.find("depth").integer(1, kMaxTopicDepth))
      topic.depth = static_cast<std::size_t>(*v);
    // Shared memory holds a slot size in 32 bits; 4294967297 was cut to 1
    // and the topic silently delivered nothing.
    if (auto v = settings.find("slot_size").integer(1, kMaxSlotSize))
      topic.slot_size = static_cast<std::size_t>(*v);
    if (auto v = settings.find("busy_poll").boolean()) topic.busy_poll = *v;
    if (auto v = settings.find("spin_us").integer(0, 10'000))
      topic.spin_us = static_cast<std::uint32_t>(*v);
    config.topics.push_back(std::move(topic));
  }
}

void parse_remote(const Node& section, const fs::path& folder, PipelineConfig& config) {
  const Node d = section.map("a map with a 'dds' key", kRemoteKeys).find("dds");
  const Map settings = d.map("a map of DDS settings", kDdsKeys);
  if (!settings) return;
  DdsConfig& dds = config.dds;
  dds.enabled = true;
  // Cyclone DDS maps domains 0..232 onto UDP ports; higher ones overflow.
  if (auto v = settings.find("domain").integer(0, 232)) dds.domain = static_cast<int>(*v);
  const Node interfaces = settings.find("interfaces");
  if (auto v = string_list(interfaces, std::nullopt, "interface names")) {
    // Cyclone reads no interface as "pick one": the first real one.
    if (v->empty() && interfaces.present() && !interfaces.is_null())
      interfaces.error(
          "an empty list would let DDS choose a network interface; name at least "
          "one ('lo': this machine only)");
    else if (!v->empty())
      dds.interfaces = *v;
  }
  if (auto v = string_list(settings.find("export"), "_/*", "topic or service patterns"))
    dds.export_patterns = *v;
  if (auto v = string_list(settings.find("import"), "_/*", "topic or service patterns"))
    dds.import_patterns = *v;
  if (auto v = string_list(settings.find("resend_on_provider_loss"), "_/*", "service patterns"))
    dds.resend_patterns = *v;
  const Node security = settings.find("security_dir");
  if (security.is_scalar() && security.text().empty()) {
    dds.security_dir.clear();
  } else if (auto v = security.string()) {
    dds.security_dir = resolve_path(folder, *v);
  }
  const Node control = settings.find("allow_remote_control");
  if (auto v = control.boolean()) {
    dds.allow_remote_control = *v;
    if (*v && dds.security_dir.empty())
      control.error("remote control needs 'security_dir' (DDS Security material)");
  }
}

PipelineConfig build(const Node& root, const std::string& file_name) {
  PipelineConfig config;
  const fs::path file = fs::absolute(file_name).lexically_normal();
  config.file = file.string();
  config.pipeline = file.stem().string();
  const Map top = root.map("a map with a 'nodes' key", kTopKeys);
  const Node name = top.find("pipeline");
  if (auto v = name.string()) config.pipeline = *v;
  // The name becomes the control socket's file name.
  if (auto ok = check_name(config.pipeline, "pipeline"); !ok) {
    if (name.present())
      name.error(ok.error().message.substr(std::string("pipeline: ").size()));
    else
      root.error(ok.error().message + " (the file's name; set 'pipeline')");
  }
  if (auto v = string_list(top.find("plugin_paths"), std::nullopt, "folder paths")) {
    for (const auto& p : *v) config.plugin_paths.push_back(resolve_path(file.parent_path(), p));
  }
  if (auto v = top.find("clock").one_of({"wall", "sim"})) config.clock = *v;
  if (auto v = top.find("cpu_wake_latency_us").integer(0, std::numeric_limits<std::int32_t>::max()))
    config.cpu_wake_latency_us = static_cast<std::int32_t>(*v);
  const bool hosts_ok = parse_hosts(top.find("hosts"), config);
  parse_nodes(top, config, hosts_ok);
  parse_topics(top.find("topics"), config);
  parse_remote(top.find("remote"), file.parent_path(), config);
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

// A config lists every problem at once, one line each.
yaml::Limits config_limits() {
  yaml::Limits limits;
  limits.max_errors = 0;
  return limits;
}

// Who reads a file of PLR's other formats (a hint after the error).
std::string reader_of(const std::string& format) {
  if (format == "plr-evaluation") return " (`plr evaluate FILE` reads it)";
  if (format == "plr-chooser-training") return " (`plr chooser train FILE` reads it)";
  if (format == "plr-world") return " (a simulator node's `world_file` param reads it)";
  return "";
}

// Overrides first, then the checks; nothing of the config is used before they pass.

Expected<PipelineConfig> read(Expected<yaml::Document> doc, const std::string& file_name,
                              const std::vector<Override>& overrides) {
  if (!doc) return doc.error();
  for (const auto& o : overrides) {
    if (auto checked = check_override_path(o.path); !checked) return checked.error();
    doc->set(o.path, o.value, "--set " + o.path);
  }
  if (!doc->ok()) return doc->error();
  const Node root = doc->root();
  if (!root.is_map()) {
    root.error(root.is_null() ? "the config is empty (expected a map with a 'nodes' key)"
                              : "expected a map at the top level, got " + root.describe());
    return doc->error();
  }
  // PLR's other files (an evaluation's or a training's settings, a world)
  // say what they are: named as such rather than read as a pipeline.
  if (const Node format = root.map().find("format"); format.present()) {
    const std::string what = format.string("a file format name").value_or("");
    if (!what.empty())
      format.error(fmt::format("a '{}' file, not a pipeline config{}", what, reader_of(what)));
    return doc->error();
  }
  return doc->result(build(root, file_name));
}

}  // namespace

Status check_name(const std::string& name, const std::string& what) {
  if (!name.empty() && name.size() <= 64 && name.front() != '.' && only_chars(name, "_-."))
    return {};
  return make_error(PLR_ERR_INVALID,
                    fmt::format("{}: '{}' is not a name: 1 to 64 letters, digits, '_', '-' and "
                                "'.', not starting with '.'",
                                what, printable(name.substr(0, 80))));
}

std::string printable(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (const unsigned char c : text) {
    if (c >= 0x20 && c < 0x7f)
      out += static_cast<char>(c);
    else
      out += fmt::format("\\x{:02x}", c);
  }
  return out;
}

Expected<Override> parse_override(const std::string& text) {
  const std::size_t eq = text.find('=');
  if (eq == std::string::npos || eq == 0)
    return make_error(PLR_ERR_INVALID, "--set " + text + ": expected key.path=value");
  Override o{text.substr(0, eq), text.substr(eq + 1)};
  if (auto checked = check_override_path(o.path); !checked) return checked.error();
  return o;
}

Expected<PipelineConfig> parse_pipeline_config(const std::string& yaml_text,
                                               const std::string& file_name,
                                               const std::vector<Override>& overrides) {
  return read(yaml::Document::parse(yaml_text, file_name, config_limits()), file_name, overrides);
}

Expected<PipelineConfig> load_pipeline_config(const std::string& file,
                                              const std::vector<Override>& overrides) {
  return read(yaml::Document::open(file, "the config", config_limits()), file, overrides);
}

}  // namespace plr::kernel
