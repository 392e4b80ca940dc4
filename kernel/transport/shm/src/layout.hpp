// Byte layout of the shared segments. Everything another process can write is
// read once into local variables and bounds-checked before use.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>

#include "plr/shm/types.hpp"

namespace plr::shm::detail {

inline constexpr std::uint64_t kMagic = 0x316d68732d726c70ULL;  // "plr-shm1"
inline constexpr std::uint32_t kLayoutVersion = 2;
inline constexpr std::size_t kLine = 64;
inline constexpr std::size_t kPage = 4096;  // tmpfs hands out whole pages
inline constexpr std::uint32_t kMaxSlots = 4096;
inline constexpr std::uint32_t kMaxSlotSize = 1u << 30;
inline constexpr std::uint32_t kMaxSubscribers = 62;  // one reader bit each in a 64-bit word
inline constexpr std::uint64_t kWriterBit = 1ULL << 63;
// The publisher's own hold on a slot it published in place, for readers in
// its process (Publisher::publish_shared).
inline constexpr std::uint64_t kOwnerBit = 1ULL << 62;
inline constexpr std::uint32_t kMaxSpinUs = 10'000;
inline constexpr std::uint64_t kNeverWritten = ~0ULL;
inline constexpr std::size_t kNameBytes = 128;
inline constexpr std::int32_t kReclaiming = -1;  // SubscriberEntry::pid while being freed

static_assert(std::atomic<std::uint64_t>::is_always_lock_free);
static_assert(std::atomic<std::uint32_t>::is_always_lock_free);

constexpr std::size_t align_up(std::size_t n, std::size_t a) {
  return (n + a - 1) / a * a;
}

enum class SegmentKind : std::uint32_t { kTopic = 1, kService = 2 };

// A futex word plus a sleeper count, so the waker skips the syscall when
// nobody sleeps.
struct alignas(kLine) Notifier {
  std::atomic<std::uint32_t> word;
  std::atomic<std::uint32_t> sleepers;
};

struct alignas(kLine) SegmentHeader {
  std::uint64_t magic;
  std::uint32_t layout_version;
  SegmentKind kind;
  std::uint64_t total_size;
  std::int32_t owner_pid;
  std::uint32_t reserved;
  std::uint64_t owner_start;
  char name[kNameBytes];  // topic or service name, NUL-terminated (catches hash collisions)
  std::atomic<std::uint32_t> closed;
};

struct RingGeometry {
  std::uint32_t slot_count;
  std::uint32_t slot_size;  // payload capacity
  std::uint32_t max_subscribers;
  Policy policy;
  WaitMode wait_mode;
  std::uint32_t spin_us;  // kBlocking: busy-wait this long before sleeping
};

struct alignas(kLine) RingHeader {
  RingGeometry geo;
  alignas(kLine) std::atomic<std::uint64_t> head;  // next sequence number to publish
  Notifier data;                                   // readers sleep here
  Notifier space;                                  // a reliable publisher sleeps here
};

struct alignas(kLine) SubscriberEntry {
  std::atomic<std::int32_t> pid;  // 0 = free; claimed by CAS
  std::atomic<std::uint32_t> active;
  std::atomic<std::uint64_t> start_time;
  std::atomic<std::uint64_t> cursor;  // next sequence number this reader wants
};

struct alignas(kLine) SlotHeader {
  // kWriterBit while the publisher owns the slot; bit i while reader i holds
  // it; kOwnerBit while readers in the publisher's process hold it.
  std::atomic<std::uint64_t> readers;
  std::atomic<std::uint64_t> seq;  // kNeverWritten until first publish
  std::uint64_t type_id;
  std::uint64_t correlation_id;
  std::uint32_t schema_version;
  std::uint32_t size;
  std::uint32_t offset;
  std::uint32_t check;  // detects torn or scribbled headers
};

constexpr std::uint32_t header_check(std::uint64_t seq, std::uint64_t type, std::uint64_t corr,
                                     std::uint32_t version, std::uint32_t size,
                                     std::uint32_t offset) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (std::uint64_t v :
       {seq, type, corr, std::uint64_t{version}, std::uint64_t{size}, std::uint64_t{offset}}) {
    h = (h ^ v) * 0x100000001b3ULL;
  }
  return static_cast<std::uint32_t>(h ^ (h >> 32));
}

// Descriptor ring entry: sequence number (high 48 bits) and slot index (low 16).
constexpr std::uint64_t pack_desc(std::uint64_t seq, std::uint32_t slot) {
  return (seq << 16) | slot;
}
constexpr std::uint64_t desc_seq(std::uint64_t d) {
  return d >> 16;
}
constexpr std::uint32_t desc_slot(std::uint64_t d) {
  return static_cast<std::uint32_t>(d & 0xffff);
}
inline constexpr std::uint64_t kNoDesc = ~0ULL;  // never matches a cursor

}  // namespace plr::shm::detail

namespace plr::shm::detail {

enum class ClientState : std::uint32_t { kFree = 0, kActive = 1, kLeaving = 2 };

struct alignas(kLine) ServiceHeader {
  std::uint32_t max_clients;
  RingGeometry geo;   // of every request and reply ring (one reader, reliable)
  Notifier doorbell;  // the server sleeps here; every request ring rings it
};

// One client channel: a request ring (client writes, server reads) and a reply
// ring (server writes, client reads).
struct alignas(kLine) ClientEntry {
  std::atomic<std::int32_t> pid;  // 0 = free; claimed by CAS, freed by the server
  std::atomic<ClientState> state;
  std::atomic<std::uint64_t> start_time;
  std::atomic<std::uint32_t> generation;  // bumped at every reset: stale replies are refused
};

inline constexpr std::uint32_t kMaxClients = 64;

}  // namespace plr::shm::detail
