// What the remote tools (`plr monitor`, `plr record --remote`, `plr swap
// --remote`...) share: a DDS participant of their own on a kernel domain,
// with readers and writers of PLR envelopes, and how a kernel is named.
#pragma once

#include "dds_bridge.hpp"
#include "envelope.h"
#include "monitor.hpp"

#include <cstring>
#include <set>
#include <string>
#include <type_traits>

namespace plr::kernel {

class DdsTool {
 public:
  DdsTool() = default;
  DdsTool(const DdsTool&) = delete;
  DdsTool& operator=(const DdsTool&) = delete;
  // The whole Cyclone instance goes, threads included: a receive thread still
  // decrypting at exit would use OpenSSL after its exit handler freed it.
  ~DdsTool() { dds_delete(DDS_CYCLONEDDS_HANDLE); }

  Status open(const DdsToolOptions& o);
  dds_entity_t participant() const { return participant_; }
  // On PLR's control topics (announce, telemetry, control, result).
  dds_entity_t reader(const char* topic, std::int32_t depth, bool transient);
  dds_entity_t writer(const char* topic, std::int32_t depth, bool transient);
  // On any envelope topic, with the caller's QoS.
  dds_entity_t reader(const char* topic, const dds_qos_t* qos);

  // Valid samples, sender checked, to fn(envelope) or fn(envelope, info);
  // `gone` gets kernels whose instance died.
  template <class Fn>
  void take(dds_entity_t reader, Fn&& fn, std::set<std::string>* gone = nullptr) {
    void* samples[32];
    dds_sample_info_t infos[32];
    for (;;) {
      samples[0] = nullptr;
      const auto n = dds_take(reader, samples, infos, 32, 32);
      if (n <= 0) return;
      for (int i = 0; i < n; ++i) {
        const auto& e = *static_cast<const plr_dds_Envelope*>(samples[i]);
        const bool sane = e.kernel && ::strnlen(e.kernel, 129) <= 128 && e.target && e.name &&
                          (e.payload._length == 0 || e.payload._buffer);
        if (!sane) {
          ++invalid;
          continue;
        }
        if (!infos[i].valid_data) {
          if (gone && infos[i].instance_state != DDS_IST_ALIVE) gone->insert(e.kernel);
          continue;
        }
        if constexpr (std::is_invocable_v<Fn, const plr_dds_Envelope&, const dds_sample_info_t&>)
          fn(e, infos[i]);
        else
          fn(e);
      }
      dds_return_loan(reader, samples, n);
    }
  }

  std::uint64_t invalid = 0;

 private:
  dds_entity_t participant_ = 0;
};

// Whether kernel `id` ("demo@box:12") is the one `wanted` names: the full
// id, "demo@box" or "demo".
bool names_kernel(const std::string& id, const std::string& wanted);

}  // namespace plr::kernel
