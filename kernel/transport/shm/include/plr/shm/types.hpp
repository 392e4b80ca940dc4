// Vocabulary of the shared-memory transport: errors, policies, configs and
// the per-message header the receiver gets after bounds checks.
#pragma once

#include <sys/types.h>
#include <chrono>
#include <cstdint>

#include <plr/expected.hpp>

namespace plr::shm {

enum class Error : std::uint8_t {
  kInvalidArgument,     // bad name, run id, config value or offset/size
  kAlreadyExists,       // a live owner already holds this segment
  kNotFound,            // no such segment (publisher or server not up yet)
  kPermission,          // segment belongs to someone else or is not 0600
  kOsError,             // shm_open/ftruncate/mmap failed otherwise
  kIncompatible,        // bad magic, layout version, geometry or name in a segment
  kTooLarge,            // loan bigger than the slot size
  kNoData,              // take() with no wait found nothing
  kTimeout,             // waited the whole timeout (reliable: back-pressure)
  kSlotsExhausted,      // keep-last: readers hold every slot
  kTooManySubscribers,  // subscriber table full
  kTooManyClients,      // service client table full
  kPeerDead,            // owner / server / client process is gone
  kClosed,              // the owner closed the segment cleanly
  kUnknownClient,       // reply to a client channel that is no longer ours
  kNoSpace,             // /dev/shm has no room for the segment
};

const char* to_string(Error e) noexcept;

template <class T>
using Result = Expected<T, Error>;

// What happens when a reader is slow.
enum class Policy : std::uint32_t {
  kKeepLast = 1,  // publisher overwrites the oldest unread message; the reader counts dropped_slow
  kReliable = 2,  // publisher's loan waits (up to its timeout) until every reader has moved on
};

// How a reader waits for data.
enum class WaitMode : std::uint32_t {
  // futex in the segment; the publisher wakes only if someone sleeps. With
  // TopicConfig::spin_us > 0 a reader first busy-waits that long after each
  // message it took (spin then sleep): a steady stream never pays a wake-up,
  // an idle topic costs one spin budget and then sleeps.
  kBlocking = 1,
  kPolling = 2,  // busy-poll the ring head: lowest latency, burns the reader's core
};

using Timeout = std::chrono::nanoseconds;
inline constexpr Timeout kNoWait{0};
inline constexpr Timeout kForever = Timeout::max();

struct TopicConfig {
  std::uint32_t slot_count = 16;        // messages in flight per topic (1..4096)
  std::uint32_t slot_size = 64 * 1024;  // payload bytes per slot (1..1 GiB)
  std::uint32_t max_subscribers = 8;    // 1..62
  Policy policy = Policy::kKeepLast;
  WaitMode wait_mode = WaitMode::kBlocking;
  std::uint32_t spin_us = 0;  // kBlocking: busy-wait budget before a futex sleep (0..10000)
};

// Header of a received message, copied out of shared memory once and
// bounds-checked (size fits the slot); the payload itself is still untrusted.
struct MessageInfo {
  std::uint64_t type_id = 0;
  std::uint32_t schema_version = 0;
  std::uint32_t size = 0;
  std::uint64_t seq = 0;             // publisher's sequence number (0, 1, 2, ...)
  std::uint64_t correlation_id = 0;  // services: request id echoed by the reply
};

// What the sender states about a message it publishes.
struct MessageType {
  std::uint64_t type_id = 0;
  std::uint32_t schema_version = 0;
};

// A process identity that survives pid reuse: pid + start time (clock ticks
// since boot, field 22 of /proc/<pid>/stat).
struct ProcessStamp {
  pid_t pid = 0;
  std::uint64_t start_time = 0;

  static ProcessStamp self() noexcept;
  static ProcessStamp of(pid_t pid) noexcept;  // start_time 0 if no such process
  // False once the process has exited (zombies count as dead) or its pid was reused.
  bool alive() const noexcept;
};

// Counters are relaxed atomics so a monitor thread may read them.
struct Counters {
  std::uint64_t published = 0;
  std::uint64_t received = 0;
  std::uint64_t dropped_slow = 0;     // keep-last: overwritten before this reader took them
  std::uint64_t dropped_invalid = 0;  // corrupt header, bad slot index, size out of bounds
};

}  // namespace plr::shm
