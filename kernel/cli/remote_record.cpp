// `plr record --remote KERNEL FILE`: a DDS participant of its own that finds
// the topics kernels export (DDS discovery of their writers on
// "plr/topic/..."), reads them with the writers' reliability, and writes
// each message with its SDK schema into an MCAP file. Nothing is sent to the
// kernels: recording a robot cannot change what it does.
#include "commands.hpp"
#include "dds_tool.hpp"
#include "mcap_writer.hpp"
#include "recorder.hpp"

#include <plr/schemas.hpp>

#include <fmt/format.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <iostream>
#include <map>
#include <set>
#include <thread>

namespace plr::kernel {

namespace {

using Clock = std::chrono::steady_clock;

std::atomic<int> g_signal{0};

// Larger payloads are counted and dropped: a peer cannot make the file (or
// this process) grow by one message without bound.
constexpr std::uint32_t kMaxPayload = 64u << 20;
// Samples a reader keeps until taken: a burst between two takes.
constexpr std::int32_t kReaderDepth = 1024;

std::uint64_t wall_ns() {
  return static_cast<std::uint64_t>(std::chrono::duration_cast<std::chrono::nanoseconds>(
                                        std::chrono::system_clock::now().time_since_epoch())
                                        .count());
}

class RemoteRecorder {
 public:
  RemoteRecorder(DdsTool& tool, const RemoteRecordOptions& o, mcap::Writer& writer)
      : tool_(tool), options_(o), writer_(writer) {}

  // Readers for exported topics that appeared since the last call.
  void discover(dds_entity_t publications) {
    void* samples[16];
    dds_sample_info_t infos[16];
    for (;;) {
      samples[0] = nullptr;
      const auto n = dds_take(publications, samples, infos, 16, 16);
      if (n <= 0) return;
      for (int i = 0; i < n; ++i) {
        const auto& p = *static_cast<const dds_builtintopic_endpoint_t*>(samples[i]);
        if (infos[i].valid_data && p.topic_name != nullptr) follow(p.topic_name, p.qos);
      }
      dds_return_loan(publications, samples, n);
    }
  }

  Status take() {
    for (const auto& [name, reader] : readers_) {
      if (reader <= 0) continue;  // could not be read: said once when found
      Status s;
      tool_.take(reader, [&](const plr_dds_Envelope& e, const dds_sample_info_t& info) {
        if (s) s = record(e, info);
      });
      if (!s) return s;
    }
    return {};
  }

  std::size_t topics() const { return channels_.size(); }
  std::uint64_t refused() const { return refused_ + tool_.invalid; }

 private:
  void follow(const std::string& dds_topic, const dds_qos_t* writer_qos) {
    if (!dds_topic.starts_with("plr/topic/") || readers_.count(dds_topic)) return;
    dds_reliability_kind_t reliability = DDS_RELIABILITY_BEST_EFFORT;
    dds_duration_t blocking = 0;
    if (writer_qos == nullptr || !dds_qget_reliability(writer_qos, &reliability, &blocking))
      reliability = DDS_RELIABILITY_BEST_EFFORT;
    dds_qos_t* q = dds_create_qos();
    dds_qset_reliability(q, reliability, DDS_MSECS(100));
    dds_qset_history(q, DDS_HISTORY_KEEP_LAST, kReaderDepth);
    const auto r = tool_.reader(dds_topic.c_str(), q);
    dds_delete_qos(q);
    if (r < 0) {
      std::cerr << fmt::format("plr: record: cannot read '{}': {}\n", dds_topic, dds_strretcode(r));
      readers_[dds_topic] = 0;
      return;
    }
    readers_[dds_topic] = r;
  }

  Status record(const plr_dds_Envelope& e, const dds_sample_info_t& info) {
    if (e.kind != static_cast<std::uint8_t>(EnvelopeKind::kTopic) ||
        e.payload._length > kMaxPayload || ::strnlen(e.name, kMaxNameSize + 1) > kMaxNameSize) {
      ++refused_;
      return {};
    }
    if (options_.kernel != "*" && !names_kernel(e.kernel, options_.kernel)) return {};
    const std::string topic = e.name;
    bool wanted = options_.topics.empty();
    for (const auto& p : options_.topics) wanted = wanted || topic_matches(p, topic);
    if (!wanted) return {};
    auto it = channels_.find(topic);
    if (it == channels_.end()) {
      const MessageSchema* schema = find_schema(e.type_id);
      if (schema == nullptr) {
        if (unknown_.insert(topic).second)
          std::cerr << fmt::format(
              "plr: record: topic '{}' not recorded: its type {:016x} has no SDK schema\n", topic,
              e.type_id);
        return {};
      }
      it = channels_
               .emplace(topic, Channel{writer_.add_channel(
                                           topic, writer_.add_schema(schema->name, schema->bfbs)),
                                       e.type_id})
               .first;
    }
    if (it->second.type_id != e.type_id) {
      ++refused_;  // one topic, one type: a kernel sending another is wrong
      return {};
    }
    const auto stamp =
        info.source_timestamp > 0 ? static_cast<std::uint64_t>(info.source_timestamp) : wall_ns();
    return writer_.write(it->second.id, wall_ns(), stamp,
                         {reinterpret_cast<const char*>(e.payload._buffer), e.payload._length});
  }

  struct Channel {
    std::uint16_t id;
    std::uint64_t type_id;
  };
  DdsTool& tool_;
  const RemoteRecordOptions& options_;
  mcap::Writer& writer_;
  std::map<std::string, dds_entity_t> readers_;  // by DDS topic; 0: could not be read
  std::map<std::string, Channel> channels_;      // by bus topic
  std::set<std::string> unknown_;
  std::uint64_t refused_ = 0;
};

}  // namespace

int remote_record(const RemoteRecordOptions& options) {
  if (options.kernel.empty()) {
    fail("record --remote: name the kernel (id, pipeline@hostname, pipeline, or '*')");
    return 2;
  }
  DdsTool tool;
  if (auto s = tool.open(options.dds); !s) return fail(s.error().message);
  const auto publications =
      dds_create_reader(tool.participant(), DDS_BUILTIN_TOPIC_DCPSPUBLICATION, nullptr, nullptr);
  if (publications < 0)
    return fail(fmt::format("dds: cannot read the domain's publications: {}",
                            dds_strretcode(publications)));
  auto writer = mcap::Writer::create(options.file);
  if (!writer) return fail(writer.error().message);
  g_signal = 0;
  std::signal(SIGINT, [](int sig) { g_signal = sig; });
  std::signal(SIGTERM, [](int sig) { g_signal = sig; });

  RemoteRecorder recorder(tool, options, **writer);
  const auto end = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                      std::chrono::duration<double>(options.duration_s));
  Status status;
  while (g_signal == 0 && (options.duration_s <= 0.0 || Clock::now() < end)) {
    recorder.discover(publications);
    if (status = recorder.take(); !status) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  // What arrived before the stop is written too: a stopped recording keeps it.
  if (status) status = recorder.take();
  const auto finished = (*writer)->finish();
  if (!status) return fail("record: " + status.error().message);
  if (!finished) return fail("record: " + finished.error().message);
  std::cerr << fmt::format("plr: recorded {} messages on {} topics to {}", (*writer)->messages(),
                           recorder.topics(), options.file);
  if (recorder.refused() > 0)
    std::cerr << fmt::format(" ({} malformed or oversized samples refused)", recorder.refused());
  std::cerr << "\n";
  // As `plr run` reports a signal: 128 + its number (docs/errors.md).
  return g_signal != 0 ? 128 + g_signal.load() : 0;
}

}  // namespace plr::kernel
