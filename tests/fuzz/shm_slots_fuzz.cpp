// Fuzz target: a reader of the shared-memory ring (kernel/transport/shm)
// whose publisher is hostile: the ring header, descriptors and slot headers
// hold the input's bytes. Every message taken must lie inside its slot, and
// a take must end (kNoData or a message), never read outside the ring.
#include "ring.hpp"

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <memory>

using namespace plr::shm;
using namespace plr::shm::detail;

namespace {
volatile std::uint64_t sink;
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 3) return 0;
  // The geometry is the reader's own (checked local values); the rest is shared.
  const RingGeometry g{1u + data[0] % 8u, 16u + 8u * (data[1] % 8u), 2,
                       Policy::kKeepLast, WaitMode::kBlocking,       0};
  if (!Ring::check(g)) return 0;
  const std::size_t bytes = Ring::bytes(g);
  // Exactly the ring, so AddressSanitizer sees any read past it.
  auto memory = std::make_unique<std::byte[]>(bytes);
  const Ring ring = Ring::init(memory.get(), g, nullptr);
  Consumer reader(ring);
  if (!reader.attach(ProcessStamp::self())) return 0;
  // A publisher that knows the format (the check is no secret): the input's
  // first bytes say which slots it stamps with a correct check, and with
  // which size and offset.
  const std::uint8_t stamped = data[2];
  std::size_t at = 3;
  const auto next = [&]() -> std::uint32_t {
    std::uint32_t v = 0;
    for (int k = 0; k < 4; ++k) v = (v << 8) | (at < size ? data[at++] : 0u);
    return v;
  };
  for (std::uint32_t k = 0; k < g.slot_count; ++k) {
    if (((stamped >> (k % 8)) & 1u) == 0) continue;
    const std::uint32_t idx = next() % (g.slot_count + 1);  // one past the end, too
    const std::uint32_t size32 = next(), offset = next();
    if (idx < g.slot_count) {
      SlotHeader& h = ring.slot(idx);
      h.seq.store(k);
      h.type_id = 7;
      h.size = size32;
      h.offset = offset;
      h.check = header_check(k, 7, 0, 0, size32, offset);
    }
    ring.desc[k].store(pack_desc(k, idx));
    ring.header->head.store(k + 1);
  }
  // Then the rest of the input over the shared part (a zero byte leaves one).
  for (std::size_t i = sizeof(RingGeometry); at < size && i < bytes; ++i, ++at)
    if (data[at] != 0) std::memcpy(memory.get() + i, data + at, 1);
  const Ring view = Ring::view(memory.get(), g, nullptr);
  std::uint64_t sum = 0;
  for (int i = 0; i < 2 * static_cast<int>(g.slot_count) + 2; ++i) {
    (void)reader.has_data();
    auto taken = reader.try_take();
    if (!taken) continue;
    if (taken->slot >= g.slot_count || taken->offset > g.slot_size ||
        taken->info.size > g.slot_size - taken->offset)
      __builtin_trap();  // a message outside its slot
    const std::byte* p = view.payload(taken->slot) + taken->offset;
    for (std::uint32_t k = 0; k < taken->info.size; ++k) sum += static_cast<std::uint8_t>(p[k]);
    release_slot(view.slot(taken->slot), reader.bit(), view.header->space);
  }
  (void)reader.counters();
  sink = sum;  // the bytes are read, not optimised away
  return 0;
}
