// The Foxglove WebSocket protocol (foxglove.websocket.v1), server side:
// PLR's topics as channels (message and schema encoding "flatbuffer", the
// schema a base64 .bfbs), channels the monitor makes itself (encoding "json",
// a JSON Schema), clients' subscriptions, and the binary message frames.
// Read-only: no client publishing, services or parameters.
// https://github.com/foxglove/ws-protocol/blob/main/docs/spec.md
#pragma once

#include <plr/schemas.hpp>

#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace plr::monitor_web {

struct Channel {
  std::uint32_t id = 0;
  std::string topic;
  std::uint64_t type_id = 0;  // the bus topic's type; 0 when the monitor makes the messages
  std::string encoding;       // "flatbuffer" or "json"
  std::string schema_name;
  std::string schema_encoding;  // "flatbuffer" or "jsonschema"
  std::string schema;           // as advertised: base64 .bfbs, or the JSON Schema's text
};

class FoxgloveChannels {
 public:
  static constexpr std::size_t kMaxSubscriptionsPerClient = 256;

  // A new channel for `topic` (nullptr when it exists or its type has no SDK schema).
  const Channel* add(const std::string& topic, std::uint64_t type_id);
  // A channel of JSON messages the monitor makes (nullptr when `topic` exists).
  const Channel* add_json(const std::string& topic, const std::string& schema_name,
                          const std::string& json_schema);
  const Channel* find(const std::string& topic) const;

  // The server's first messages to a client: serverInfo, then every channel.
  std::vector<std::string> hello(const std::string& server_name);
  static std::string advertise(const std::vector<Channel>& channels);

  struct Request {
    std::vector<std::string> replies;        // status messages for the client
    std::vector<std::string> topics_wanted;  // channels now subscribed by someone
  };
  // A client's text message: subscribe and unsubscribe are honoured, anything
  // else is answered with a status error naming it.
  Request handle(std::uint64_t client, std::string_view text);
  void forget(std::uint64_t client);

  // (client, subscription id) of everyone subscribed to `topic`'s channel.
  std::vector<std::pair<std::uint64_t, std::uint32_t>> subscribers(const std::string& topic) const;

  // Opcode 1 "message data": subscription id, receive time (ns), payload.
  static std::string message_frame(std::uint32_t subscription, std::uint64_t stamp_ns,
                                   std::string_view payload);

 private:
  mutable std::mutex m_;
  const Channel* insert(Channel c);

  std::map<std::string, Channel> channels_;  // by topic
  std::map<std::uint32_t, std::string> topic_of_;
  std::uint32_t next_id_ = 1;
  // client -> subscription id -> channel id
  std::map<std::uint64_t, std::map<std::uint32_t, std::uint32_t>> subscriptions_;
};

std::string base64(std::string_view bytes);

}  // namespace plr::monitor_web
