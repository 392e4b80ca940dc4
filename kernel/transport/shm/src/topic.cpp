#include "plr/shm/topic.hpp"

#include <cstring>
#include <utility>

#include "plr/shm/segments.hpp"
#include "process.hpp"
#include "ring.hpp"
#include "segment.hpp"

namespace plr::shm {

using detail::Ring;
using detail::RingGeometry;
using detail::Segment;
using detail::SegmentKind;

namespace {
constexpr std::size_t kRingOffset = detail::align_up(sizeof(detail::SegmentHeader), detail::kLine);

TopicConfig to_config(const RingGeometry& g) {
  return TopicConfig{g.slot_count, g.slot_size, g.max_subscribers,
                     g.policy,     g.wait_mode, g.spin_us};
}
}  // namespace

// ------------------------------------------------------------------- Loan

Loan::Loan(Loan&& o) noexcept
    : producer_(std::exchange(o.producer_, nullptr)), slot_(o.slot_), buf_(o.buf_) {}

Loan& Loan::operator=(Loan&& o) noexcept {
  if (this != &o) {
    reset();
    producer_ = std::exchange(o.producer_, nullptr);
    slot_ = o.slot_;
    buf_ = o.buf_;
  }
  return *this;
}

Loan::~Loan() {
  reset();
}

void Loan::reset() noexcept {
  if (producer_ != nullptr) std::exchange(producer_, nullptr)->cancel(slot_);
}

// ----------------------------------------------------------------- Sample

Sample::Sample(Sample&& o) noexcept
    : slot_(std::exchange(o.slot_, nullptr)),
      space_(o.space_),
      bit_(o.bit_),
      data_(o.data_),
      info_(o.info_) {}

Sample& Sample::operator=(Sample&& o) noexcept {
  if (this != &o) {
    release();
    slot_ = std::exchange(o.slot_, nullptr);
    space_ = o.space_;
    bit_ = o.bit_;
    data_ = o.data_;
    info_ = o.info_;
  }
  return *this;
}

Sample::~Sample() {
  release();
}

void Sample::release() noexcept {
  if (slot_ != nullptr) detail::release_slot(*std::exchange(slot_, nullptr), bit_, *space_);
}

// -------------------------------------------------------------- Publisher

struct Publisher::Impl {
  Impl(Segment s, const Ring& r, const TopicConfig& c) noexcept
      : segment(std::move(s)), producer(r), config(c) {}
  Segment segment;
  detail::Producer producer;
  TopicConfig config;
};

Publisher::Publisher(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
Publisher::Publisher(Publisher&&) noexcept = default;
Publisher& Publisher::operator=(Publisher&&) noexcept = default;

Publisher::~Publisher() {
  if (!impl_) return;
  impl_->segment.header().closed.store(1, std::memory_order_seq_cst);
  detail::notify(impl_->producer.ring().header->data);
  impl_->segment.unlink();
}

std::size_t segment_bytes(const TopicConfig& c) noexcept {
  const RingGeometry g{c.slot_count, c.slot_size, c.max_subscribers,
                       c.policy,     c.wait_mode, c.spin_us};
  return detail::align_up(kRingOffset + Ring::bytes(g), detail::kPage);
}

Result<Publisher> PublisherBuilder::create() const {
  if (!valid_run_id(run_id_) || !valid_endpoint_name(topic_)) {
    return Error::kInvalidArgument;
  }
  const RingGeometry g{config_.slot_count, config_.slot_size, config_.max_subscribers,
                       config_.policy,     config_.wait_mode, config_.spin_us};
  if (auto ok = Ring::check(g); !ok) return ok.error();
  auto seg = Segment::create(topic_segment_name(run_id_, topic_), kRingOffset + Ring::bytes(g),
                             SegmentKind::kTopic, topic_);
  if (!seg) return seg.error();
  const Ring ring = Ring::init(seg->data() + kRingOffset, g, nullptr);
  auto impl = std::make_unique<Publisher::Impl>(std::move(*seg), ring, config_);
  impl->segment.publish_header();
  return Publisher(std::move(impl));
}

Result<Loan> Publisher::loan(std::size_t max_size, Timeout timeout) noexcept {
  auto slot = impl_->producer.loan(max_size, timeout);
  if (!slot) return slot.error();
  const Ring& r = impl_->producer.ring();
  return Loan(&impl_->producer, *slot, {r.payload(*slot), r.geo.slot_size});
}

Result<std::uint64_t> Publisher::publish(Loan&& loan, MessageType type, std::size_t offset,
                                         std::size_t size) noexcept {
  if (loan.producer_ != &impl_->producer) return Error::kInvalidArgument;
  loan.producer_ = nullptr;
  return impl_->producer.publish(loan.slot_, type, 0, offset, size);
}

Result<Sample> Publisher::publish_shared(Loan&& loan, MessageType type, std::size_t offset,
                                         std::size_t size) noexcept {
  if (loan.producer_ != &impl_->producer) return Error::kInvalidArgument;
  const std::uint32_t slot = std::exchange(loan.slot_, 0);
  loan.producer_ = nullptr;
  auto seq = impl_->producer.publish(slot, type, 0, offset, size, detail::kOwnerBit);
  if (!seq) return seq.error();
  const Ring& r = impl_->producer.ring();
  const MessageInfo info{type.type_id, type.schema_version, static_cast<std::uint32_t>(size), *seq,
                         0};
  return Sample(&r.slot(slot), &r.header->space, detail::kOwnerBit,
                {r.payload(slot) + offset, size}, info);
}

Result<std::uint64_t> Publisher::publish_copy(MessageType type, std::span<const std::byte> bytes,
                                              Timeout timeout) noexcept {
  auto l = loan(bytes.size(), timeout);
  if (!l) return l.error();
  if (!bytes.empty()) std::memcpy(l->data(), bytes.data(), bytes.size());
  return publish(std::move(*l), type, 0, bytes.size());
}

std::size_t Publisher::reclaim_dead_subscribers() noexcept {
  return impl_->producer.reclaim_dead_readers();
}

std::size_t Publisher::subscriber_count() const noexcept {
  const Ring& r = impl_->producer.ring();
  std::size_t n = 0;
  for (std::uint32_t i = 0; i < r.geo.max_subscribers; ++i) {
    n += r.subs[i].active.load(std::memory_order_acquire) != 0;
  }
  return n;
}

Counters Publisher::counters() const noexcept {
  Counters c;
  c.published = impl_->producer.published();
  return c;
}

const TopicConfig& Publisher::config() const noexcept {
  return impl_->config;
}
const std::string& Publisher::segment_name() const noexcept {
  return impl_->segment.name();
}

// ------------------------------------------------------------- Subscriber

struct Subscriber::Impl {
  Impl(Segment s, const Ring& r) noexcept
      : segment(std::move(s)),
        consumer(r),
        watch(segment.owner(), &segment.header().closed),
        config(to_config(r.geo)) {}
  Segment segment;
  detail::Consumer consumer;
  detail::PeerWatch watch;
  TopicConfig config;

  ~Impl() { consumer.detach(); }
  bool closed() const noexcept {
    return segment.header().closed.load(std::memory_order_acquire) != 0;
  }
};

Subscriber::Subscriber(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
Subscriber::Subscriber(Subscriber&&) noexcept = default;
Subscriber& Subscriber::operator=(Subscriber&&) noexcept = default;
Subscriber::~Subscriber() = default;

Result<Subscriber> SubscriberBuilder::create() const {
  if (!valid_run_id(run_id_) || !valid_endpoint_name(topic_)) {
    return Error::kInvalidArgument;
  }
  auto seg = Segment::open(topic_segment_name(run_id_, topic_), SegmentKind::kTopic, topic_);
  if (!seg) return seg.error();
  // The geometry is read once and checked; later changes by a faulty peer are ignored.
  if (seg->size() < kRingOffset + sizeof(detail::RingHeader)) {
    return Error::kIncompatible;
  }
  RingGeometry g;
  std::memcpy(&g, &reinterpret_cast<const detail::RingHeader*>(seg->data() + kRingOffset)->geo,
              sizeof g);
  if (!Ring::check(g) || seg->size() < kRingOffset + Ring::bytes(g)) {
    return Error::kIncompatible;
  }
  const Ring ring = Ring::view(seg->data() + kRingOffset, g, nullptr);
  auto impl = std::make_unique<Subscriber::Impl>(std::move(*seg), ring);
  auto ok = impl->consumer.attach(ProcessStamp::self());
  // A full table may hold readers that died: free those and try once more.
  if (!ok && detail::reclaim_dead(ring) > 0) ok = impl->consumer.attach(ProcessStamp::self());
  if (!ok) return ok.error();
  return Subscriber(std::move(impl));
}

Result<Sample> Subscriber::take(Timeout timeout) noexcept {
  Impl& im = *impl_;
  const auto deadline = detail::deadline_after(timeout);
  for (;;) {
    auto t = im.consumer.try_take();
    if (t) {
      const Ring& r = im.consumer.ring();
      return Sample(&r.slot(t->slot), &r.header->space, im.consumer.bit(),
                    {r.payload(t->slot) + t->offset, t->info.size}, t->info);
    }
    if (t.error() != Error::kNoData) return t.error();
    if (im.closed()) return Error::kClosed;
    if (timeout == kNoWait) return Error::kNoData;
    auto w = detail::wait_until(
        *im.consumer.ring().doorbell, im.config.wait_mode, deadline,
        [&] { return im.consumer.has_data() || im.closed(); }, [&] { return im.watch.check(); }, 0,
        std::chrono::microseconds(im.config.spin_us));
    if (!w) return w.error();
  }
}

Result<void> Subscriber::publisher_alive() const noexcept {
  return impl_->watch.check();
}
Counters Subscriber::counters() const noexcept {
  return impl_->consumer.counters();
}
const TopicConfig& Subscriber::config() const noexcept {
  return impl_->config;
}

}  // namespace plr::shm
