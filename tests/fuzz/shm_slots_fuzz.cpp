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
  // Everything but the reader's own geometry copy, from the input, repeated.
  const std::size_t from = sizeof(RingGeometry);
  for (std::size_t i = from, j = 2; i < bytes; ++i, j = j + 1 < size ? j + 1 : 2)
    std::memcpy(memory.get() + i, data + j, 1);
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
  return static_cast<int>(sum & 0);
}
