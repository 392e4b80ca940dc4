#include "plr/shm/service.hpp"

#include <cstring>
#include <utility>

#include "plr/shm/segments.hpp"
#include "process.hpp"
#include "ring.hpp"
#include "segment.hpp"

namespace plr::shm {

using detail::ClientEntry;
using detail::ClientState;
using detail::Ring;
using detail::RingGeometry;
using detail::Segment;
using detail::SegmentKind;
using detail::ServiceHeader;

namespace {

constexpr std::size_t kServiceOffset =
    detail::align_up(sizeof(detail::SegmentHeader), detail::kLine);
constexpr std::size_t kClientsOffset = kServiceOffset + sizeof(ServiceHeader);

std::size_t channels_offset(std::uint32_t max_clients) {
  return kClientsOffset + max_clients * sizeof(ClientEntry);
}

std::size_t segment_bytes(std::uint32_t max_clients, const RingGeometry& g) {
  return channels_offset(max_clients) + 2ULL * max_clients * Ring::bytes(g);
}

// Request ring of channel c, then its reply ring.
std::byte* ring_base(std::byte* seg, std::uint32_t max_clients, const RingGeometry& g,
                     std::uint32_t c, bool reply) {
  return seg + channels_offset(max_clients) + (2ULL * c + (reply ? 1 : 0)) * Ring::bytes(g);
}

// Validated geometry of a service segment (header written by another process).
struct Layout {
  std::uint32_t max_clients;
  RingGeometry geo;
};

Result<Layout> read_layout(const Segment& seg) {
  if (seg.size() < kClientsOffset) return Error::kIncompatible;
  Layout l{};
  const auto* sh = reinterpret_cast<const ServiceHeader*>(seg.data() + kServiceOffset);
  std::memcpy(&l.max_clients, &sh->max_clients, sizeof l.max_clients);
  std::memcpy(&l.geo, &sh->geo, sizeof l.geo);
  if (l.max_clients < 1 || l.max_clients > detail::kMaxClients || !Ring::check(l.geo) ||
      l.geo.max_subscribers != 1 || l.geo.policy != Policy::kReliable ||
      seg.size() < segment_bytes(l.max_clients, l.geo)) {
    return Error::kIncompatible;
  }
  return l;
}

// Context of a reply loan's liveness check.
struct ClientWatch {
  const ClientEntry* entry;
  std::uint32_t generation;
  ProcessStamp stamp;

  static Result<void> check(const void* self) noexcept {
    const auto& w = *static_cast<const ClientWatch*>(self);
    if (w.entry->generation.load(std::memory_order_acquire) != w.generation ||
        w.entry->state.load(std::memory_order_acquire) != ClientState::kActive) {
      return Error::kUnknownClient;
    }
    if (!w.stamp.alive()) return Error::kPeerDead;
    return {};
  }
};

}  // namespace

// ----------------------------------------------------------------- server

struct ServiceServer::Impl {
  Segment segment;
  Layout layout{};
  ServiceHeader* sh = nullptr;
  ClientEntry* clients = nullptr;
  std::unique_ptr<detail::Consumer[]> requests;
  std::unique_ptr<detail::Producer[]> replies;
  std::uint32_t next = 0;
  std::uint32_t calls = 0;
  ProcessStamp me = ProcessStamp::self();

  Ring ring(std::uint32_t c, bool reply) const {
    return Ring::view(ring_base(segment.data(), layout.max_clients, layout.geo, c, reply),
                      layout.geo, reply ? nullptr : &sh->doorbell);
  }
  // Server side of a fresh channel: it is the one reader of the request ring.
  void bind_channel(std::uint32_t c) {
    requests[c].bind(ring(c, false));
    // Cannot fail: the ring was just reset and has one free reader entry.
    (void)requests[c].attach(me);
    replies[c].bind(ring(c, true));
  }
  std::size_t reap() noexcept;
};

// Resets channels whose client left or died, so another client can claim them.
std::size_t ServiceServer::Impl::reap() noexcept {
  std::size_t n = 0;
  for (std::uint32_t c = 0; c < layout.max_clients; ++c) {
    ClientEntry& e = clients[c];
    const pid_t pid = e.pid.load(std::memory_order_acquire);
    if (pid == 0) continue;
    const bool leaving = e.state.load(std::memory_order_acquire) == ClientState::kLeaving;
    if (!leaving && ProcessStamp{pid, e.start_time.load(std::memory_order_acquire)}.alive()) {
      continue;
    }
    e.state.store(ClientState::kFree, std::memory_order_release);
    e.generation.fetch_add(1, std::memory_order_acq_rel);
    ring(c, false).reset();
    ring(c, true).reset();
    bind_channel(c);
    e.start_time.store(0, std::memory_order_relaxed);
    e.pid.store(0, std::memory_order_release);
    ++n;
  }
  return n;
}

ServiceServer::ServiceServer(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
ServiceServer::ServiceServer(ServiceServer&&) noexcept = default;
ServiceServer& ServiceServer::operator=(ServiceServer&&) noexcept = default;

ServiceServer::~ServiceServer() {
  if (!impl_) return;
  impl_->segment.header().closed.store(1, std::memory_order_seq_cst);
  for (std::uint32_t c = 0; c < impl_->layout.max_clients; ++c) {
    detail::notify(impl_->ring(c, true).header->data);
    detail::notify(impl_->ring(c, false).header->space);
  }
  impl_->segment.unlink();
}

std::size_t segment_bytes(const ServiceConfig& c) noexcept {
  const RingGeometry g{c.slot_count, c.slot_size, 1, Policy::kReliable, c.wait_mode, 0};
  return detail::align_up(segment_bytes(c.max_clients, g), detail::kPage);
}

Result<ServiceServer> ServiceServerBuilder::create() const {
  if (!valid_run_id(run_id_) || !valid_endpoint_name(service_) || config_.max_clients < 1 ||
      config_.max_clients > detail::kMaxClients) {
    return Error::kInvalidArgument;
  }
  const Layout l{config_.max_clients, RingGeometry{config_.slot_count, config_.slot_size, 1,
                                                   Policy::kReliable, config_.wait_mode, 0}};
  if (auto ok = Ring::check(l.geo); !ok) return ok.error();
  auto seg = Segment::create(service_segment_name(run_id_, service_),
                             segment_bytes(l.max_clients, l.geo), SegmentKind::kService, service_);
  if (!seg) return seg.error();
  auto impl = std::make_unique<ServiceServer::Impl>();
  impl->segment = std::move(*seg);
  impl->layout = l;
  std::byte* base = impl->segment.data();
  impl->sh = new (base + kServiceOffset) ServiceHeader{};
  impl->sh->max_clients = l.max_clients;
  impl->sh->geo = l.geo;
  impl->clients = reinterpret_cast<ClientEntry*>(base + kClientsOffset);
  impl->requests = std::make_unique<detail::Consumer[]>(l.max_clients);
  impl->replies = std::make_unique<detail::Producer[]>(l.max_clients);
  for (std::uint32_t c = 0; c < l.max_clients; ++c) {
    new (&impl->clients[c]) ClientEntry{};
    Ring::init(ring_base(base, l.max_clients, l.geo, c, false), l.geo, &impl->sh->doorbell);
    Ring::init(ring_base(base, l.max_clients, l.geo, c, true), l.geo, nullptr);
    impl->bind_channel(c);
  }
  impl->segment.publish_header();
  return ServiceServer(std::move(impl));
}

Result<Request> ServiceServer::take_request(Timeout timeout) noexcept {
  Impl& im = *impl_;
  const std::uint32_t n = im.layout.max_clients;
  const auto deadline = detail::deadline_after(timeout);
  auto any_data = [&] {
    for (std::uint32_t c = 0; c < n; ++c) {
      if (im.clients[c].state.load(std::memory_order_acquire) == ClientState::kActive &&
          im.requests[c].has_data()) {
        return true;
      }
    }
    return false;
  };
  // A server that is never idle still frees departed clients' channels.
  if (++im.calls % 1024 == 0) im.reap();
  for (;;) {
    for (std::uint32_t k = 0; k < n; ++k) {
      const std::uint32_t c = (im.next + k) % n;
      ClientEntry& e = im.clients[c];
      if (e.state.load(std::memory_order_acquire) != ClientState::kActive) continue;
      auto t = im.requests[c].try_take();
      if (!t) continue;
      im.next = (c + 1) % n;
      const Ring& r = im.requests[c].ring();
      Sample s(&r.slot(t->slot), &r.header->space, im.requests[c].bit(),
               {r.payload(t->slot) + t->offset, t->info.size}, t->info);
      return Request{std::move(s), ReplyTo{c, e.generation.load(std::memory_order_acquire),
                                           t->info.correlation_id}};
    }
    if (timeout == kNoWait) return Error::kNoData;
    auto w = detail::wait_until(im.sh->doorbell, im.layout.geo.wait_mode, deadline, any_data,
                                [&]() -> Result<void> {
                                  im.reap();
                                  return {};
                                });
    if (!w) return w.error();
  }
}

Result<Loan> ServiceServer::loan_reply(const ReplyTo& to, std::size_t max_size,
                                       Timeout timeout) noexcept {
  Impl& im = *impl_;
  if (to.channel >= im.layout.max_clients) return Error::kUnknownClient;
  const ClientEntry& e = im.clients[to.channel];
  const ClientWatch watch{&e, to.generation,
                          ProcessStamp{e.pid.load(std::memory_order_acquire),
                                       e.start_time.load(std::memory_order_acquire)}};
  if (e.generation.load(std::memory_order_acquire) != to.generation ||
      e.state.load(std::memory_order_acquire) != ClientState::kActive) {
    return Error::kUnknownClient;
  }
  detail::Producer& p = im.replies[to.channel];
  auto slot = p.loan(max_size, timeout, &ClientWatch::check, &watch);
  if (!slot) return slot.error();
  return Loan(&p, *slot, {p.ring().payload(*slot), p.ring().geo.slot_size});
}

Result<void> ServiceServer::send_reply(Loan&& loan, const ReplyTo& to, MessageType type,
                                       std::size_t offset, std::size_t size) noexcept {
  Impl& im = *impl_;
  if (to.channel >= im.layout.max_clients || loan.producer_ != &im.replies[to.channel]) {
    return Error::kInvalidArgument;
  }
  loan.producer_ = nullptr;
  if (im.clients[to.channel].generation.load(std::memory_order_acquire) != to.generation) {
    im.replies[to.channel].cancel(loan.slot_);
    return Error::kUnknownClient;
  }
  auto r = im.replies[to.channel].publish(loan.slot_, type, to.correlation_id, offset, size);
  if (!r) return r.error();
  return {};
}

std::size_t ServiceServer::reclaim_dead_clients() noexcept {
  return impl_->reap();
}

std::size_t ServiceServer::client_count() const noexcept {
  std::size_t n = 0;
  for (std::uint32_t c = 0; c < impl_->layout.max_clients; ++c) {
    n += impl_->clients[c].state.load(std::memory_order_acquire) == ClientState::kActive;
  }
  return n;
}

const std::string& ServiceServer::segment_name() const noexcept {
  return impl_->segment.name();
}

// ----------------------------------------------------------------- client

struct ServiceClient::Impl {
  Impl(Segment s, const Layout& l) noexcept
      : segment(std::move(s)),
        layout(l),
        sh(reinterpret_cast<ServiceHeader*>(segment.data() + kServiceOffset)),
        watch(segment.owner(), &segment.header().closed),
        config{l.geo.slot_count, l.geo.slot_size, l.max_clients, l.geo.wait_mode} {}
  ~Impl() {
    if (entry == nullptr) return;
    reply.detach();
    entry->state.store(ClientState::kLeaving, std::memory_order_seq_cst);
    // Wake the server so it frees the channel soon.
    sh->doorbell.word.fetch_add(1, std::memory_order_seq_cst);
    detail::futex_wake_all(sh->doorbell.word);
  }

  Segment segment;
  Layout layout;
  ServiceHeader* sh;
  ClientEntry* entry = nullptr;
  detail::Producer request;
  detail::Consumer reply;
  detail::PeerWatch watch;
  ServiceConfig config;
  std::uint64_t next_correlation = 1;
  std::atomic<std::uint64_t> sent{0};
  std::atomic<std::uint64_t> replied{0};
};

ServiceClient::ServiceClient(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
ServiceClient::ServiceClient(ServiceClient&&) noexcept = default;
ServiceClient& ServiceClient::operator=(ServiceClient&&) noexcept = default;
ServiceClient::~ServiceClient() = default;

Result<ServiceClient> ServiceClientBuilder::create() const {
  if (!valid_run_id(run_id_) || !valid_endpoint_name(service_)) {
    return Error::kInvalidArgument;
  }
  auto seg =
      Segment::open(service_segment_name(run_id_, service_), SegmentKind::kService, service_);
  if (!seg) return seg.error();
  auto l = read_layout(*seg);
  if (!l) return l.error();
  auto impl = std::make_unique<ServiceClient::Impl>(std::move(*seg), *l);
  if (auto alive = impl->watch.check(); !alive) return alive.error();
  std::byte* base = impl->segment.data();
  auto* clients = reinterpret_cast<ClientEntry*>(base + kClientsOffset);
  const ProcessStamp me = ProcessStamp::self();
  for (std::uint32_t c = 0; c < l->max_clients; ++c) {
    ClientEntry& e = clients[c];
    std::int32_t free = 0;
    if (!e.pid.compare_exchange_strong(free, me.pid, std::memory_order_acq_rel)) continue;
    e.start_time.store(me.start_time, std::memory_order_release);
    impl->request.bind(
        Ring::view(ring_base(base, l->max_clients, l->geo, c, false), l->geo, &impl->sh->doorbell));
    impl->reply.bind(Ring::view(ring_base(base, l->max_clients, l->geo, c, true), l->geo, nullptr));
    if (auto ok = impl->reply.attach(me); !ok) {
      e.start_time.store(0, std::memory_order_relaxed);
      e.pid.store(0, std::memory_order_release);
      return Error::kIncompatible;
    }
    impl->entry = &e;
    e.state.store(ClientState::kActive, std::memory_order_seq_cst);
    return ServiceClient(std::move(impl));
  }
  return Error::kTooManyClients;
}

Result<Loan> ServiceClient::loan_request(std::size_t max_size, Timeout timeout) noexcept {
  Impl& im = *impl_;
  if (auto alive = im.watch.check(); !alive) return alive.error();
  auto slot = im.request.loan(max_size, timeout, &detail::PeerWatch::check_fn, &im.watch);
  if (!slot) return slot.error();
  return Loan(&im.request, *slot, {im.request.ring().payload(*slot), im.layout.geo.slot_size});
}

Result<std::uint64_t> ServiceClient::send_request(Loan&& loan, MessageType type, std::size_t offset,
                                                  std::size_t size) noexcept {
  Impl& im = *impl_;
  if (loan.producer_ != &im.request) return Error::kInvalidArgument;
  loan.producer_ = nullptr;
  if (auto alive = im.watch.check(); !alive) {
    im.request.cancel(loan.slot_);
    return alive.error();
  }
  const std::uint64_t id = im.next_correlation++;
  auto r = im.request.publish(loan.slot_, type, id, offset, size);
  if (!r) return r.error();
  im.sent.store(im.sent.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  return id;
}

Result<Sample> ServiceClient::take_reply(Timeout timeout) noexcept {
  Impl& im = *impl_;
  const auto deadline = detail::deadline_after(timeout);
  for (;;) {
    auto t = im.reply.try_take();
    if (t) {
      im.replied.store(im.replied.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
      const Ring& r = im.reply.ring();
      return Sample(&r.slot(t->slot), &r.header->space, im.reply.bit(),
                    {r.payload(t->slot) + t->offset, t->info.size}, t->info);
    }
    // Nothing to read: a dead or closed server fails the call now, not at the timeout.
    if (auto alive = im.watch.check(); !alive) return alive.error();
    if (timeout == kNoWait) return Error::kNoData;
    auto w = detail::wait_until(
        im.reply.ring().header->data, im.layout.geo.wait_mode, deadline,
        [&] {
          return im.reply.has_data() ||
                 im.segment.header().closed.load(std::memory_order_acquire) != 0;
        },
        [&] { return im.watch.check(); });
    if (!w) return w.error();
  }
}

std::uint64_t ServiceClient::pending() const noexcept {
  return impl_->sent.load(std::memory_order_relaxed) -
         impl_->replied.load(std::memory_order_relaxed);
}

Result<void> ServiceClient::server_alive() const noexcept {
  return impl_->watch.check();
}
const ServiceConfig& ServiceClient::config() const noexcept {
  return impl_->config;
}

}  // namespace plr::shm
