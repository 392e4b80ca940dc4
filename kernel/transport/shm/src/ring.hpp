// The lock-free ring shared by topics and service channels: one producer,
// up to 63 readers, slots read in place. See docs/transports.md.
#pragma once

#include <atomic>
#include <chrono>
#include <cstddef>
#include <cstdint>

#include "layout.hpp"
#include "plr/shm/types.hpp"

namespace plr::shm::detail {

using Clock = std::chrono::steady_clock;

// How often a waiter wakes up to check that its peer is still alive.
inline constexpr Timeout kLivenessSlice = std::chrono::milliseconds(5);

Clock::time_point deadline_after(Timeout t) noexcept;

void notify(Notifier& n) noexcept;

// Waits until ready() is true, the deadline passes (kTimeout) or check() — run
// every kLivenessSlice — returns an error, which is passed on. Returns as soon
// as ready() is true once (it may claim something).
// spin_first: busy checks before the first sleep (0 = sleep at once);
// spin_for: then busy-wait up to this long before the first sleep.
template <class Ready, class Check>
Result<void> wait_until(Notifier& n, WaitMode mode, Clock::time_point deadline, Ready ready,
                        Check check, std::uint32_t spin_first = 0,
                        Clock::duration spin_for = Clock::duration::zero()) noexcept;

// A reliable publisher that finds the ring full usually gets a slot back
// within a microsecond or two: spin that long before paying for a futex sleep.
inline constexpr std::uint32_t kSpaceSpins = 4000;

struct Ring {
  RingGeometry geo{};
  RingHeader* header = nullptr;
  SubscriberEntry* subs = nullptr;
  std::atomic<std::uint64_t>* desc = nullptr;
  std::byte* slots = nullptr;
  std::size_t stride = 0;
  Notifier* doorbell = nullptr;  // readers sleep here: the ring's own, or a service's shared one

  static std::size_t bytes(const RingGeometry& g) noexcept;
  static Result<void> check(const RingGeometry& g) noexcept;
  // Lays out a ring over base (zeroed memory) with trusted geometry.
  static Ring init(std::byte* base, const RingGeometry& g, Notifier* doorbell) noexcept;
  // Maps pointers only; g must come from check()ed local values.
  static Ring view(std::byte* base, const RingGeometry& g, Notifier* doorbell) noexcept;
  // Owner only, with no producer or reader of the ring left (service channel reuse).
  void reset() noexcept;

  SlotHeader& slot(std::uint32_t i) const noexcept {
    return *reinterpret_cast<SlotHeader*>(slots + i * stride);
  }
  std::byte* payload(std::uint32_t i) const noexcept {
    return slots + i * stride + sizeof(SlotHeader);
  }
};

class Producer {
 public:
  Producer() = default;
  explicit Producer(const Ring& r) noexcept { bind(r); }
  // (Re)binds to a ring, continuing from its current head.
  void bind(const Ring& r) noexcept;

  // Returns an error if the peer this producer serves is gone.
  using CheckFn = Result<void> (*)(const void* ctx) noexcept;

  // Owns a free slot (kWriterBit set) or fails; reliable rings wait for space,
  // running check(ctx) every liveness slice.
  Result<std::uint32_t> loan(std::size_t max_size, Timeout timeout, CheckFn check = nullptr,
                             const void* ctx = nullptr) noexcept;
  void cancel(std::uint32_t slot) noexcept;
  // keep: reader bits the slot starts with (kOwnerBit: the publisher's
  // process still reads it in place).
  Result<std::uint64_t> publish(std::uint32_t slot, MessageType type, std::uint64_t correlation,
                                std::size_t offset, std::size_t size,
                                std::uint64_t keep = 0) noexcept;
  // Frees the table entries and held slots of readers whose process is gone.
  std::size_t reclaim_dead_readers() noexcept;
  std::uint64_t published() const noexcept { return published_.load(std::memory_order_relaxed); }
  const Ring& ring() const noexcept { return ring_; }

 private:
  bool find_slot(std::uint32_t& out) noexcept;
  std::uint64_t min_cursor() const noexcept;

  Ring ring_;
  std::uint64_t next_seq_ = 0;
  std::uint32_t scan_ = 0;
  std::uint64_t min_cache_ = 0;  // a lower bound of every reader's cursor (reliable)
  std::atomic<std::uint64_t> published_{0};
};

struct Taken {
  std::uint32_t slot;
  std::uint32_t offset;
  MessageInfo info;
};

class Consumer {
 public:
  Consumer() = default;
  explicit Consumer(const Ring& r) noexcept : ring_(r) {}
  // (Re)binds to a ring; not attached until attach().
  void bind(const Ring& r) noexcept {
    ring_ = r;
    bit_ = 0;
  }

  Result<void> attach(const ProcessStamp& me) noexcept;
  // Releases every slot still held and frees the table entry.
  void detach() noexcept;

  // Pins the next valid message (sets this reader's bit in its slot) or kNoData.
  Result<Taken> try_take() noexcept;
  bool has_data() const noexcept;
  std::uint64_t bit() const noexcept { return bit_; }
  const Ring& ring() const noexcept { return ring_; }
  Counters counters() const noexcept;

 private:
  void bump(std::atomic<std::uint64_t>& c, std::uint64_t n = 1) noexcept {
    c.store(c.load(std::memory_order_relaxed) + n, std::memory_order_relaxed);
  }
  void advance(std::uint64_t to) noexcept;

  Ring ring_;
  std::uint32_t index_ = 0;
  std::uint64_t bit_ = 0;
  std::uint64_t cursor_ = 0;
  std::atomic<std::uint64_t> received_{0}, dropped_slow_{0}, dropped_invalid_{0};
};

// Frees the table entries and held slots of readers whose process is gone.
std::size_t reclaim_dead(const Ring& ring) noexcept;

// Clears bit from a slot's reader word and wakes a publisher waiting for space.
void release_slot(SlotHeader& slot, std::uint64_t bit, Notifier& space) noexcept;

}  // namespace plr::shm::detail

#include "wait_impl.hpp"
