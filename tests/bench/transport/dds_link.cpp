#include <dds/dds.h>

#include <chrono>
#include <thread>
#include <vector>

#include "bench_msg.h"
#include "links.hpp"

namespace plr::bench {
namespace {

class DdsLink final : public Link {
 public:
  ~DdsLink() override {
    if (participant_ > 0) dds_delete(participant_);
  }

  bool init(bool sender, std::size_t max_size, std::string& error) {
    participant_ = dds_create_participant(DDS_DOMAIN_DEFAULT, nullptr, nullptr);
    if (participant_ < 0) return fail(error, "create participant", participant_);
    dds_qos_t* qos = dds_create_qos();
    dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(10));
    dds_qset_history(qos, DDS_HISTORY_KEEP_ALL, 0);
    const dds_entity_t data =
        dds_create_topic(participant_, &plrbench_Msg_desc, "plr_bench_data", qos, nullptr);
    const dds_entity_t ack =
        dds_create_topic(participant_, &plrbench_Msg_desc, "plr_bench_ack", qos, nullptr);
    if (data < 0 || ack < 0) {
      dds_delete_qos(qos);
      return fail(error, "create topic", data < 0 ? data : ack);
    }
    writer_ = dds_create_writer(participant_, sender ? data : ack, qos, nullptr);
    reader_ = dds_create_reader(participant_, sender ? ack : data, qos, nullptr);
    dds_delete_qos(qos);
    if (writer_ < 0 || reader_ < 0) return fail(error, "create writer/reader", -1);
    waitset_ = dds_create_waitset(participant_);
    const dds_entity_t cond = dds_create_readcondition(reader_, DDS_ANY_STATE);
    if (dds_waitset_attach(waitset_, cond, 0) < 0) return fail(error, "attach", -1);
    payload_.assign(max_size, 0x5a);
    // Set-up only: wait until both directions are matched (discovery).
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    for (;;) {
      dds_publication_matched_status_t pm{};
      dds_subscription_matched_status_t sm{};
      dds_get_publication_matched_status(writer_, &pm);
      dds_get_subscription_matched_status(reader_, &sm);
      if (pm.current_count > 0 && sm.current_count > 0) return true;
      if (std::chrono::steady_clock::now() > deadline) return fail(error, "discovery timeout", -1);
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  }

  bool send(std::size_t size, std::uint64_t stamp, std::uint64_t seq) override {
    return write(size, stamp, seq);
  }
  bool wait_ack(std::uint64_t& seq) override {
    std::uint64_t stamp = 0;
    return take(stamp, seq);
  }
  bool receive(std::uint64_t& stamp, std::uint64_t& seq) override { return take(stamp, seq); }
  bool ack(std::uint64_t seq) override { return write(0, 0, seq); }

 private:
  static bool fail(std::string& error, const char* what, dds_return_t rc) {
    error = std::string("dds: ") + what + " (" + dds_strretcode(rc) + ")";
    return false;
  }

  bool write(std::size_t size, std::uint64_t stamp, std::uint64_t seq) {
    plrbench_Msg m{};
    m.stamp_ns = stamp;
    m.seq = seq;
    m.payload._buffer = payload_.data();
    m.payload._length = static_cast<std::uint32_t>(size);
    m.payload._maximum = static_cast<std::uint32_t>(size);
    m.payload._release = false;
    return dds_write(writer_, &m) == DDS_RETCODE_OK;
  }

  bool take(std::uint64_t& stamp, std::uint64_t& seq) {
    for (;;) {
      void* samples[1] = {nullptr};
      dds_sample_info_t info[1];
      const dds_return_t n = dds_take(reader_, samples, info, 1, 1);
      if (n < 0) return false;
      if (n == 1) {
        const bool valid = info[0].valid_data;
        if (valid) {
          const auto* m = static_cast<const plrbench_Msg*>(samples[0]);
          stamp = m->stamp_ns;
          seq = m->seq;
        }
        dds_return_loan(reader_, samples, n);
        if (valid) return true;
        continue;
      }
      if (dds_waitset_wait(waitset_, nullptr, 0, DDS_SECS(10)) <= 0) return false;
    }
  }

  dds_entity_t participant_ = 0, writer_ = 0, reader_ = 0, waitset_ = 0;
  std::vector<unsigned char> payload_;
};

}  // namespace

Link* make_dds_link(bool sender, std::size_t max_size, std::string& error) {
  auto* l = new DdsLink();
  if (!l->init(sender, max_size, error)) {
    delete l;
    return nullptr;
  }
  return l;
}

}  // namespace plr::bench
