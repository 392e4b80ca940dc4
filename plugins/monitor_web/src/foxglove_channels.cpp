#include "foxglove_channels.hpp"

#include <nlohmann/json.hpp>

namespace plr::monitor_web {

namespace {

std::string status(int level, const std::string& message) {
  return nlohmann::json{{"op", "status"}, {"level", level}, {"message", message}}.dump();
}

void put_le(std::string& out, std::uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) out.push_back(static_cast<char>((v >> (8 * i)) & 0xff));
}

}  // namespace

std::string base64(std::string_view in) {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((in.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 2 < in.size(); i += 3) {
    const std::uint32_t n = static_cast<std::uint8_t>(in[i]) << 16 |
                            static_cast<std::uint8_t>(in[i + 1]) << 8 |
                            static_cast<std::uint8_t>(in[i + 2]);
    for (int s : {18, 12, 6, 0}) out.push_back(kAlphabet[(n >> s) & 63]);
  }
  if (i < in.size()) {
    std::uint32_t n = static_cast<std::uint8_t>(in[i]) << 16;
    if (i + 1 < in.size()) n |= static_cast<std::uint8_t>(in[i + 1]) << 8;
    out.push_back(kAlphabet[(n >> 18) & 63]);
    out.push_back(kAlphabet[(n >> 12) & 63]);
    out.push_back(i + 1 < in.size() ? kAlphabet[(n >> 6) & 63] : '=');
    out.push_back('=');
  }
  return out;
}

const Channel* FoxgloveChannels::add(const std::string& topic, std::uint64_t type_id) {
  const auto* schema = find_schema(type_id);
  if (schema == nullptr) return nullptr;
  return insert(
      {0, topic, type_id, "flatbuffer", schema->name, "flatbuffer", base64(schema->bfbs)});
}

const Channel* FoxgloveChannels::add_json(const std::string& topic, const std::string& schema_name,
                                          const std::string& json_schema) {
  return insert({0, topic, 0, "json", schema_name, "jsonschema", json_schema});
}

const Channel* FoxgloveChannels::insert(Channel c) {
  std::lock_guard lock(m_);
  if (channels_.count(c.topic)) return nullptr;
  c.id = next_id_++;
  topic_of_[c.id] = c.topic;
  auto& kept = channels_[c.topic];
  kept = std::move(c);
  return &kept;
}

const Channel* FoxgloveChannels::find(const std::string& topic) const {
  std::lock_guard lock(m_);
  const auto it = channels_.find(topic);
  return it == channels_.end() ? nullptr : &it->second;
}

std::string FoxgloveChannels::advertise(const std::vector<Channel>& channels) {
  nlohmann::json list = nlohmann::json::array();
  for (const auto& c : channels)
    list.push_back({{"id", c.id},
                    {"topic", c.topic},
                    {"encoding", c.encoding},
                    {"schemaName", c.schema_name},
                    {"schema", c.schema},
                    {"schemaEncoding", c.schema_encoding}});
  return nlohmann::json{{"op", "advertise"}, {"channels", std::move(list)}}.dump();
}

std::vector<std::string> FoxgloveChannels::hello(const std::string& server_name) {
  std::vector<std::string> out;
  out.push_back(nlohmann::json{{"op", "serverInfo"},
                               {"name", server_name},
                               {"capabilities", nlohmann::json::array()},
                               {"supportedEncodings", nlohmann::json::array()},
                               {"metadata", nlohmann::json::object()}}
                    .dump());
  std::vector<Channel> all;
  {
    std::lock_guard lock(m_);
    for (const auto& [topic, c] : channels_) all.push_back(c);
  }
  if (!all.empty()) out.push_back(advertise(all));
  return out;
}

FoxgloveChannels::Request FoxgloveChannels::handle(std::uint64_t client, std::string_view text) {
  Request r;
  const auto j = nlohmann::json::parse(text, nullptr, false);
  const std::string op =
      j.is_object() && j.contains("op") && j["op"].is_string() ? j["op"].get<std::string>() : "";
  const auto list = [&](const char* key) {
    return j.contains(key) && j[key].is_array() ? j[key] : nlohmann::json::array();
  };
  std::lock_guard lock(m_);
  if (op == "subscribe") {
    auto& mine = subscriptions_[client];
    for (const auto& s : list("subscriptions")) {
      if (!s.is_object() || !s.contains("id") || !s["id"].is_number_unsigned() ||
          !s.contains("channelId") || !s["channelId"].is_number_unsigned()) {
        r.replies.push_back(status(2, "subscribe: each subscription needs id and channelId"));
        continue;
      }
      const auto id = s["id"].get<std::uint32_t>();
      const auto channel = s["channelId"].get<std::uint32_t>();
      const auto topic = topic_of_.find(channel);
      if (topic == topic_of_.end()) {
        r.replies.push_back(status(2, "subscribe: no channel " + std::to_string(channel)));
      } else if (mine.size() >= kMaxSubscriptionsPerClient && !mine.count(id)) {
        r.replies.push_back(status(2, "subscribe: too many subscriptions"));
      } else {
        mine[id] = channel;
        r.topics_wanted.push_back(topic->second);
      }
    }
  } else if (op == "unsubscribe") {
    auto& mine = subscriptions_[client];
    for (const auto& id : list("subscriptionIds"))
      if (id.is_number_unsigned()) mine.erase(id.get<std::uint32_t>());
  } else {
    r.replies.push_back(status(2, "unsupported operation '" + op + "' (this server is read-only)"));
  }
  return r;
}

void FoxgloveChannels::forget(std::uint64_t client) {
  std::lock_guard lock(m_);
  subscriptions_.erase(client);
}

std::vector<std::pair<std::uint64_t, std::uint32_t>> FoxgloveChannels::subscribers(
    const std::string& topic) const {
  std::vector<std::pair<std::uint64_t, std::uint32_t>> out;
  std::lock_guard lock(m_);
  const auto c = channels_.find(topic);
  if (c == channels_.end()) return out;
  for (const auto& [client, subs] : subscriptions_)
    for (const auto& [sub, channel] : subs)
      if (channel == c->second.id) out.emplace_back(client, sub);
  return out;
}

std::string FoxgloveChannels::message_frame(std::uint32_t subscription, std::uint64_t stamp_ns,
                                            std::string_view payload) {
  std::string out;
  out.reserve(13 + payload.size());
  out.push_back(1);
  put_le(out, subscription, 4);
  put_le(out, stamp_ns, 8);
  out.append(payload);
  return out;
}

}  // namespace plr::monitor_web
