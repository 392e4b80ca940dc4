// Topics across processes: one publisher per topic segment, up to 62
// subscribers, messages read in place (zero copy).
//
// Threading: a Publisher is used by one thread at a time (loan/publish); a
// Subscriber's take() by one thread at a time. A Loan may be filled and a
// Sample read or released on any thread. counters() may be called from any
// thread. Loans and Samples must be gone before their Publisher/Subscriber.
// Nothing here throws or allocates after create().
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "plr/shm/types.hpp"

namespace plr::shm {

namespace detail {
class Producer;
struct SlotHeader;
struct Notifier;
}  // namespace detail

// A writable slot owned by the publisher until publish() (or the Loan's
// destruction, which gives it back unpublished). Build anywhere inside
// buffer(), e.g. a FlatBuffer at its end, then publish(offset, size).
class Loan {
 public:
  Loan(Loan&& o) noexcept;
  Loan& operator=(Loan&& o) noexcept;
  Loan(const Loan&) = delete;
  Loan& operator=(const Loan&) = delete;
  ~Loan();

  std::span<std::byte> buffer() const noexcept { return buf_; }
  std::byte* data() const noexcept { return buf_.data(); }
  std::size_t capacity() const noexcept { return buf_.size(); }

 private:
  friend class Publisher;
  friend class ServiceClient;
  friend class ServiceServer;
  Loan(detail::Producer* p, std::uint32_t slot, std::span<std::byte> buf) noexcept
      : producer_(p), slot_(slot), buf_(buf) {}
  void reset() noexcept;

  detail::Producer* producer_ = nullptr;
  std::uint32_t slot_ = 0;
  std::span<std::byte> buf_;
};

// A received message, read in place. The slot returns to the publisher when
// every subscriber that took it has dropped its Sample.
class Sample {
 public:
  Sample(Sample&& o) noexcept;
  Sample& operator=(Sample&& o) noexcept;
  Sample(const Sample&) = delete;
  Sample& operator=(const Sample&) = delete;
  ~Sample();

  // Exactly info().size bytes; still untrusted (run the FlatBuffers verifier).
  std::span<const std::byte> data() const noexcept { return data_; }
  const MessageInfo& info() const noexcept { return info_; }

 private:
  friend class Subscriber;
  friend class Publisher;
  friend class ServiceServer;
  friend class ServiceClient;
  Sample(detail::SlotHeader* slot, detail::Notifier* space, std::uint64_t bit,
         std::span<const std::byte> data, const MessageInfo& info) noexcept
      : slot_(slot), space_(space), bit_(bit), data_(data), info_(info) {}
  void release() noexcept;

  detail::SlotHeader* slot_ = nullptr;
  detail::Notifier* space_ = nullptr;
  std::uint64_t bit_ = 0;
  std::span<const std::byte> data_;
  MessageInfo info_;
};

class Publisher {
 public:
  Publisher(Publisher&&) noexcept;
  Publisher& operator=(Publisher&&) noexcept;
  // Marks the segment closed (subscribers get kClosed), wakes them, unlinks it.
  ~Publisher();

  // keep-last: never waits; kSlotsExhausted only if readers hold every slot.
  // reliable: waits up to timeout for every reader to move on (kTimeout =
  // back-pressure); dead readers are reclaimed while waiting.
  Result<Loan> loan(std::size_t max_size, Timeout timeout = kNoWait) noexcept;
  // Publishes buffer()[offset, offset + size). Returns the sequence number.
  // On error the slot goes back unpublished.
  Result<std::uint64_t> publish(Loan&& loan, MessageType type, std::size_t offset,
                                std::size_t size) noexcept;
  // Publishes like publish() and keeps the slot for readers in this process:
  // the returned Sample reads the same bytes in place, and the slot is reused
  // only once it is dropped too (and every subscriber is done).
  Result<Sample> publish_shared(Loan&& loan, MessageType type, std::size_t offset,
                                std::size_t size) noexcept;
  // loan + one memcpy + publish, for messages already built elsewhere.
  Result<std::uint64_t> publish_copy(MessageType type, std::span<const std::byte> bytes,
                                     Timeout timeout = kNoWait) noexcept;

  // Frees table entries and held slots of subscribers whose process died.
  // Also runs by itself when a loan finds no slot; call it from a housekeeping
  // tick too if you like.
  std::size_t reclaim_dead_subscribers() noexcept;
  std::size_t subscriber_count() const noexcept;
  Counters counters() const noexcept;  // published only
  const TopicConfig& config() const noexcept;
  const std::string& segment_name() const noexcept;

  struct Impl;

 private:
  friend class PublisherBuilder;
  explicit Publisher(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

class PublisherBuilder {
 public:
  PublisherBuilder& run_id(std::string_view v) {
    run_id_ = v;
    return *this;
  }
  PublisherBuilder& topic(std::string_view v) {
    topic_ = v;
    return *this;
  }
  PublisherBuilder& config(const TopicConfig& c) {
    config_ = c;
    return *this;
  }
  // Creates /dev/shm/plr.<uid>.<run>.t<hash> (0600). kAlreadyExists if a live
  // process publishes this topic; a dead one's segment is replaced.
  Result<Publisher> create() const;

 private:
  std::string run_id_, topic_;
  TopicConfig config_;
};

class Subscriber {
 public:
  Subscriber(Subscriber&&) noexcept;
  Subscriber& operator=(Subscriber&&) noexcept;
  ~Subscriber();  // leaves the subscriber table

  // Next message, waiting up to timeout (futex or busy-poll per the topic's
  // wait mode). Errors: kNoData (timeout 0), kTimeout, kClosed (publisher
  // exited cleanly and everything was read), kPeerDead (publisher died).
  // Corrupt messages are skipped and counted, never returned.
  Result<Sample> take(Timeout timeout = kNoWait) noexcept;
  // kPeerDead / kClosed if the publisher is gone (a pidfd poll, ~1 µs).
  Result<void> publisher_alive() const noexcept;
  Counters counters() const noexcept;          // received, dropped_slow, dropped_invalid
  const TopicConfig& config() const noexcept;  // as validated from the segment

  struct Impl;

 private:
  friend class SubscriberBuilder;
  explicit Subscriber(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

class SubscriberBuilder {
 public:
  SubscriberBuilder& run_id(std::string_view v) {
    run_id_ = v;
    return *this;
  }
  SubscriberBuilder& topic(std::string_view v) {
    topic_ = v;
    return *this;
  }
  // kNotFound until the publisher has created the topic: retry later.
  // Receives messages published after it joined.
  Result<Subscriber> create() const;

 private:
  std::string run_id_, topic_;
};

// Bytes of /dev/shm the segment of a topic with this config takes (whole pages).
std::size_t segment_bytes(const TopicConfig& config) noexcept;

}  // namespace plr::shm
