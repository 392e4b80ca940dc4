#include "ring.hpp"

#include <limits>
#include <new>

namespace plr::shm::detail {

Clock::time_point deadline_after(Timeout t) noexcept {
  const auto now = Clock::now();
  if (t >= Clock::time_point::max() - now) return Clock::time_point::max();
  return now + std::chrono::duration_cast<Clock::duration>(t);
}

// Callers made their state change with a seq_cst operation first; a sleeper
// registers (seq_cst) before re-checking, so one of the two sees the other.
void notify(Notifier& n) noexcept {
  if (n.sleepers.load(std::memory_order_seq_cst) == 0) return;
  n.word.fetch_add(1, std::memory_order_seq_cst);
  futex_wake_all(n.word);
}

namespace {
std::size_t stride_of(const RingGeometry& g) {
  return sizeof(SlotHeader) + align_up(g.slot_size, kLine);
}
std::size_t desc_bytes(const RingGeometry& g) {
  return align_up(g.slot_count * 8ULL, kLine);
}
}  // namespace

std::size_t Ring::bytes(const RingGeometry& g) noexcept {
  return sizeof(RingHeader) + g.max_subscribers * sizeof(SubscriberEntry) + desc_bytes(g) +
         g.slot_count * stride_of(g);
}

Result<void> Ring::check(const RingGeometry& g) noexcept {
  const bool ok = g.slot_count >= 1 && g.slot_count <= kMaxSlots && g.slot_size >= 1 &&
                  g.slot_size <= kMaxSlotSize && g.max_subscribers >= 1 &&
                  g.max_subscribers <= kMaxSubscribers &&
                  (g.policy == Policy::kKeepLast || g.policy == Policy::kReliable) &&
                  (g.wait_mode == WaitMode::kBlocking || g.wait_mode == WaitMode::kPolling) &&
                  g.spin_us <= kMaxSpinUs && bytes(g) <= (std::size_t{16} << 30);
  if (!ok) return Error::kInvalidArgument;
  return {};
}

Ring Ring::view(std::byte* base, const RingGeometry& g, Notifier* doorbell) noexcept {
  Ring r;
  r.geo = g;
  r.header = reinterpret_cast<RingHeader*>(base);
  r.subs = reinterpret_cast<SubscriberEntry*>(base + sizeof(RingHeader));
  std::byte* d = base + sizeof(RingHeader) + g.max_subscribers * sizeof(SubscriberEntry);
  r.desc = reinterpret_cast<std::atomic<std::uint64_t>*>(d);
  r.slots = d + desc_bytes(g);
  r.stride = stride_of(g);
  r.doorbell = doorbell != nullptr ? doorbell : &r.header->data;
  return r;
}

Ring Ring::init(std::byte* base, const RingGeometry& g, Notifier* doorbell) noexcept {
  auto* h = new (base) RingHeader{};
  h->geo = g;
  Ring r = view(base, g, doorbell);
  for (std::uint32_t i = 0; i < g.max_subscribers; ++i) new (&r.subs[i]) SubscriberEntry{};
  for (std::uint32_t i = 0; i < g.slot_count; ++i) {
    new (&r.desc[i]) std::atomic<std::uint64_t>(kNoDesc);
  }
  for (std::uint32_t i = 0; i < g.slot_count; ++i) {
    auto* s = new (r.slots + i * r.stride) SlotHeader{};
    s->seq.store(kNeverWritten, std::memory_order_relaxed);
  }
  return r;
}

void Ring::reset() noexcept {
  for (std::uint32_t i = 0; i < geo.slot_count; ++i) {
    slot(i).readers.store(0, std::memory_order_relaxed);
    slot(i).seq.store(kNeverWritten, std::memory_order_relaxed);
    desc[i].store(kNoDesc, std::memory_order_relaxed);
  }
  for (std::uint32_t i = 0; i < geo.max_subscribers; ++i) {
    subs[i].active.store(0, std::memory_order_relaxed);
    subs[i].cursor.store(0, std::memory_order_relaxed);
    subs[i].start_time.store(0, std::memory_order_relaxed);
    subs[i].pid.store(0, std::memory_order_relaxed);
  }
  header->head.store(0, std::memory_order_seq_cst);
}

// ---------------------------------------------------------------- producer

void Producer::bind(const Ring& r) noexcept {
  ring_ = r;
  next_seq_ = r.header->head.load(std::memory_order_acquire);
  scan_ = 0;
  min_cache_ = 0;
}

std::uint64_t Producer::min_cursor() const noexcept {
  std::uint64_t m = std::numeric_limits<std::uint64_t>::max();
  for (std::uint32_t i = 0; i < ring_.geo.max_subscribers; ++i) {
    const SubscriberEntry& e = ring_.subs[i];
    if (e.active.load(std::memory_order_seq_cst) == 0) continue;
    m = std::min(m, e.cursor.load(std::memory_order_seq_cst));
  }
  return m;
}

// Scans from the slot after the last one used, so keep-last overwrites the
// oldest message first. Reliable: only a slot whose message every active
// reader has moved past.
bool Producer::find_slot(std::uint32_t& out) noexcept {
  const bool reliable = ring_.geo.policy == Policy::kReliable;
  const std::uint32_t n = ring_.geo.slot_count;
  // Reader cursors only grow (a new reader starts at the head), so an old
  // minimum stays a safe bound: re-read the cursors only when it blocks us.
  for (int pass = 0; pass < 2; ++pass) {
    for (std::uint32_t k = 0; k < n; ++k) {
      const std::uint32_t i = (scan_ + k) % n;
      SlotHeader& s = ring_.slot(i);
      if (reliable) {
        const std::uint64_t seq = s.seq.load(std::memory_order_relaxed);
        if (seq != kNeverWritten && seq >= min_cache_) continue;
      }
      std::uint64_t expected = 0;
      if (s.readers.compare_exchange_strong(expected, kWriterBit, std::memory_order_seq_cst)) {
        scan_ = (i + 1) % n;
        out = i;
        return true;
      }
    }
    if (!reliable) return false;
    const std::uint64_t m = std::min(min_cursor(), next_seq_);
    if (m == min_cache_) return false;
    min_cache_ = m;
  }
  return false;
}

Result<std::uint32_t> Producer::loan(std::size_t max_size, Timeout timeout, CheckFn check,
                                     const void* ctx) noexcept {
  if (max_size > ring_.geo.slot_size) return Error::kTooLarge;
  std::uint32_t slot = 0;
  if (find_slot(slot)) return slot;
  if (ring_.geo.policy == Policy::kKeepLast) {
    if (reclaim_dead_readers() > 0 && find_slot(slot)) return slot;
    return Error::kSlotsExhausted;
  }
  if (timeout == kNoWait) return Error::kTimeout;
  auto r = wait_until(
      ring_.header->space, ring_.geo.wait_mode, deadline_after(timeout),
      [&] { return find_slot(slot); },
      [&]() -> Result<void> {
        reclaim_dead_readers();
        return check != nullptr ? check(ctx) : Result<void>{};
      },
      kSpaceSpins);
  if (!r) return r.error();
  return slot;
}

void Producer::cancel(std::uint32_t slot) noexcept {
  ring_.slot(slot).readers.store(0, std::memory_order_release);
}

Result<std::uint64_t> Producer::publish(std::uint32_t slot, MessageType type,
                                        std::uint64_t correlation, std::size_t offset,
                                        std::size_t size, std::uint64_t keep) noexcept {
  const std::size_t cap = ring_.geo.slot_size;
  if (offset > cap || size > cap - offset) {
    cancel(slot);
    return Error::kInvalidArgument;
  }
  const std::uint64_t seq = next_seq_++;
  SlotHeader& h = ring_.slot(slot);
  h.type_id = type.type_id;
  h.correlation_id = correlation;
  h.schema_version = type.schema_version;
  h.size = static_cast<std::uint32_t>(size);
  h.offset = static_cast<std::uint32_t>(offset);
  h.check = header_check(seq, type.type_id, correlation, type.schema_version, h.size, h.offset);
  h.seq.store(seq, std::memory_order_relaxed);
  h.readers.store(keep, std::memory_order_release);
  ring_.desc[seq % ring_.geo.slot_count].store(pack_desc(seq, slot), std::memory_order_release);
  ring_.header->head.store(seq + 1, std::memory_order_seq_cst);
  notify(*ring_.doorbell);
  published_.store(published_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  return seq;
}

std::size_t Producer::reclaim_dead_readers() noexcept {
  return reclaim_dead(ring_);
}

// Any process may reclaim: the entry is first claimed (pid -> kReclaiming) so
// two reclaimers never both free it, and a new reader cannot take it until
// its slots are clean.
std::size_t reclaim_dead(const Ring& ring) noexcept {
  std::size_t n = 0;
  for (std::uint32_t i = 0; i < ring.geo.max_subscribers; ++i) {
    SubscriberEntry& e = ring.subs[i];
    std::int32_t pid = e.pid.load(std::memory_order_acquire);
    if (pid <= 0) continue;
    // start_time 0: the reader died (or is) between claiming and stamping; pid alone decides.
    const ProcessStamp who{pid, e.start_time.load(std::memory_order_acquire)};
    if (who.alive()) continue;
    if (!e.pid.compare_exchange_strong(pid, kReclaiming, std::memory_order_acq_rel)) continue;
    e.active.store(0, std::memory_order_seq_cst);
    const std::uint64_t bit = 1ULL << i;
    for (std::uint32_t s = 0; s < ring.geo.slot_count; ++s) {
      ring.slot(s).readers.fetch_and(~bit, std::memory_order_seq_cst);
    }
    e.start_time.store(0, std::memory_order_relaxed);
    e.pid.store(0, std::memory_order_release);
    ++n;
  }
  if (n > 0) notify(ring.header->space);
  return n;
}

// ---------------------------------------------------------------- consumer

Result<void> Consumer::attach(const ProcessStamp& me) noexcept {
  for (std::uint32_t i = 0; i < ring_.geo.max_subscribers; ++i) {
    SubscriberEntry& e = ring_.subs[i];
    std::int32_t free = 0;
    if (!e.pid.compare_exchange_strong(free, me.pid, std::memory_order_acq_rel)) continue;
    e.start_time.store(me.start_time, std::memory_order_release);
    e.cursor.store(ring_.header->head.load(std::memory_order_seq_cst), std::memory_order_seq_cst);
    e.active.store(1, std::memory_order_seq_cst);
    // Re-read the head now that the publisher sees us: every message from
    // here on is kept for us (the publisher may have missed us before).
    cursor_ = ring_.header->head.load(std::memory_order_seq_cst);
    e.cursor.store(cursor_, std::memory_order_seq_cst);
    index_ = i;
    bit_ = 1ULL << i;
    return {};
  }
  return Error::kTooManySubscribers;
}

void Consumer::detach() noexcept {
  if (bit_ == 0) return;
  SubscriberEntry& e = ring_.subs[index_];
  e.active.store(0, std::memory_order_seq_cst);
  for (std::uint32_t s = 0; s < ring_.geo.slot_count; ++s) {
    ring_.slot(s).readers.fetch_and(~bit_, std::memory_order_seq_cst);
  }
  e.start_time.store(0, std::memory_order_relaxed);
  e.pid.store(0, std::memory_order_release);
  bit_ = 0;
  notify(ring_.header->space);
}

// The descriptor is checked first: a poller then spins on the line it reads
// next anyway. The head (seq_cst) is what pairs with the publisher's wake-up.
bool Consumer::has_data() const noexcept {
  const std::uint64_t d =
      ring_.desc[cursor_ % ring_.geo.slot_count].load(std::memory_order_acquire);
  return desc_seq(d) == cursor_ || ring_.header->head.load(std::memory_order_seq_cst) > cursor_;
}

void Consumer::advance(std::uint64_t to) noexcept {
  cursor_ = to;
  if (ring_.geo.policy == Policy::kReliable) {
    ring_.subs[index_].cursor.store(to, std::memory_order_seq_cst);
    notify(ring_.header->space);
  } else {
    ring_.subs[index_].cursor.store(to, std::memory_order_release);
  }
}

void release_slot(SlotHeader& slot, std::uint64_t bit, Notifier& space) noexcept {
  slot.readers.fetch_and(~bit, std::memory_order_seq_cst);
  notify(space);
}

// Every value read here may have been written by a faulty process: a bad
// value drops that one message (counted) and moves on, never loops forever.
Result<Taken> Consumer::try_take() noexcept {
  const std::uint32_t n = ring_.geo.slot_count;
  for (;;) {
    // Fast path: the descriptor of the next message is there (it is written
    // before the head). Otherwise the head says whether there is anything.
    std::uint64_t d = ring_.desc[cursor_ % n].load(std::memory_order_acquire);
    std::uint64_t dseq = desc_seq(d);
    std::uint32_t idx = desc_slot(d);
    if (dseq != cursor_ || idx >= n) {
      const std::uint64_t head = ring_.header->head.load(std::memory_order_seq_cst);
      if (cursor_ >= head) return Error::kNoData;
      d = ring_.desc[cursor_ % n].load(std::memory_order_acquire);
      dseq = desc_seq(d);
      idx = desc_slot(d);
    }
    if (dseq != cursor_ || idx >= n) {
      const std::uint64_t head = ring_.header->head.load(std::memory_order_seq_cst);
      if (dseq > cursor_ && dseq < head && idx < n) {
        // Overrun: the publisher lapped this reader; resume at the oldest kept message.
        const std::uint64_t next = std::max(cursor_ + 1, head > n ? head - n : 0);
        bump(dropped_slow_, next - cursor_);
        advance(next);
      } else {
        // A scribbled head could be far ahead: skip to its last lap, not one by one.
        bump(dropped_invalid_);
        advance(std::max(cursor_ + 1, head > n ? head - n : 0));
      }
      continue;
    }
    SlotHeader& h = ring_.slot(idx);
    std::uint64_t v = h.readers.load(std::memory_order_relaxed);
    bool pinned = false;
    while ((v & kWriterBit) == 0) {
      if (h.readers.compare_exchange_weak(v, v | bit_, std::memory_order_seq_cst)) {
        pinned = true;
        break;
      }
    }
    if (!pinned || h.seq.load(std::memory_order_acquire) != cursor_) {
      // Rewritten between reading the descriptor and pinning (keep-last).
      if (pinned) release_slot(h, bit_, ring_.header->space);
      bump(dropped_slow_);
      advance(cursor_ + 1);
      continue;
    }
    Taken t{idx, 0, MessageInfo{h.type_id, h.schema_version, h.size, cursor_, h.correlation_id}};
    t.offset = h.offset;
    const std::uint32_t check = h.check;
    const std::uint32_t cap = ring_.geo.slot_size;
    if (check != header_check(t.info.seq, t.info.type_id, t.info.correlation_id,
                              t.info.schema_version, t.info.size, t.offset) ||
        t.offset > cap || t.info.size > cap - t.offset) {
      release_slot(h, bit_, ring_.header->space);
      bump(dropped_invalid_);
      advance(cursor_ + 1);
      continue;
    }
    bump(received_);
    advance(cursor_ + 1);
    return t;
  }
}

Counters Consumer::counters() const noexcept {
  Counters c;
  c.received = received_.load(std::memory_order_relaxed);
  c.dropped_slow = dropped_slow_.load(std::memory_order_relaxed);
  c.dropped_invalid = dropped_invalid_.load(std::memory_order_relaxed);
  return c;
}

}  // namespace plr::shm::detail
