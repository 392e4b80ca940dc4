// Records topics of a bus into an MCAP file (`plr run --record FILE`). It
// attaches to the bus as a link, so it hears of every topic advertised here,
// and reads the kernels' telemetry for the topics of other hosts (which come
// to this bus only once subscribed); it subscribes to those its patterns
// match ('*' wildcard) whose type has an SDK schema. Each message is written
// with its schema; log time = when the bus delivered it to the recorder,
// publish time = when it was published.
//
// Split in parts, so a run of any length records within a bound: once a
// part would pass `max_bytes`, it is finished (complete, readable alone,
// with every schema and channel) and renamed STEM.1.EXT (STEM.1.EXT to
// STEM.2.EXT, ...; the oldest beyond STEM.<keep>.EXT is removed), and the
// next part starts at `path`. At most keep + 1 parts of max_bytes each plus
// its summary (schemas, channels and chunk indexes: a few KiB).
#pragma once

#include "bus.hpp"
#include "mcap_writer.hpp"

#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <vector>

namespace plr::kernel {

struct RecordLimits {
  std::uint64_t max_bytes = std::uint64_t{256} << 20;
  int keep = 3;
};

// Part `k` of the recording at `path`: run.mcap, k = 2 -> run.2.mcap (0: `path`).
std::string record_part(const std::string& path, int k);

class Recorder final : public Link, public Endpoint {
 public:
  static Expected<std::unique_ptr<Recorder>> create(Bus& bus, const std::string& path,
                                                    std::vector<std::string> patterns,
                                                    RecordLimits limits = {});
  ~Recorder() override;

  // Waits for what was delivered, writes the summary and renames the file in place.
  Status finish();

  std::uint64_t messages() const;
  const std::string& path() const { return path_; }

  // Link
  Endpoint& link_endpoint() override { return *this; }
  void topic_advertised(const std::string& topic, std::uint64_t type_id,
                        std::uint32_t schema_version) override;
  void topic_subscribed(const std::string&, std::uint64_t) override {}
  void service_provided(const std::string&, std::uint64_t, std::uint64_t) override {}
  bool forward_call(const std::string&, const MsgRef&, std::uint64_t) override { return false; }

  // Endpoint
  NodeThread& node_thread() override { return thread_; }
  const std::string& endpoint_name() const override { return name_; }

 private:
  static constexpr const char* kTelemetryTopic = "kernel/telemetry";
  struct Topic {
    Recorder* recorder;
    std::uint16_t channel;  // 0: not recorded
    bool discovery;         // kernel telemetry: names other hosts' topics
  };
  struct ChannelDef {
    std::string topic, schema_name, bfbs;
  };
  Recorder(Bus& bus, std::string path, std::vector<std::string> patterns, RecordLimits limits,
           std::unique_ptr<mcap::Writer> writer);
  // Finishes this part and starts the next (m_ held).
  Status next_part();
  void subscribe(const std::string& topic, std::uint64_t type_id);
  static void on_message(void* user, const plr_msg* msg);

  Bus& bus_;
  std::string path_;
  std::vector<std::string> patterns_;
  std::string name_ = "recorder";
  mutable std::mutex m_;
  RecordLimits limits_;
  std::unique_ptr<mcap::Writer> writer_;
  std::uint64_t earlier_messages_ = 0;    // in the parts before this one
  std::vector<ChannelDef> channel_defs_;  // in the order of their ids
  std::set<std::string> seen_;
  std::map<std::string, std::unique_ptr<Topic>> topics_;
  std::vector<std::uint64_t> subscriptions_;
  Status error_;
  NodeThread thread_{"recorder", 1u << 16};
};

// Whether `name` matches `pattern` ('*' matches any run of characters).
bool topic_matches(std::string_view pattern, std::string_view name);

}  // namespace plr::kernel
