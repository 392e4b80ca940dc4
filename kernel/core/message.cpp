#include "message.hpp"

#include <chrono>
#include <cstring>

namespace plr::kernel {
namespace {
std::atomic<std::int64_t> g_live{0};
}

plr_msg* msg_alloc(std::size_t capacity, std::uint8_t** data) {
  auto* m = new plr_msg;
  // Aligned for FlatBuffers' largest scalar; a zero-size buffer still gets storage.
  m->storage.reset(new std::uint8_t[capacity == 0 ? 1 : capacity]);
  m->capacity = capacity;
  m->size = capacity;
  g_live.fetch_add(1, std::memory_order_relaxed);
  if (data) *data = m->storage.get();
  return m;
}

plr_msg* msg_copy(const std::uint8_t* data, std::size_t size, std::uint64_t type_id,
                  std::uint32_t schema_version, std::int64_t stamp_ns) {
  std::uint8_t* out = nullptr;
  plr_msg* m = msg_alloc(size, &out);
  if (size) std::memcpy(out, data, size);
  m->type_id = type_id;
  m->schema_version = schema_version;
  m->stamp_ns = stamp_ns;
  return m;
}

plr_msg* msg_wrap(const std::uint8_t* data, std::size_t size, std::uint64_t type_id,
                  std::uint32_t schema_version, std::shared_ptr<void> keep_alive,
                  const void* origin) {
  auto* m = new plr_msg;
  m->external = data;
  m->capacity = size;
  m->size = size;
  m->type_id = type_id;
  m->schema_version = schema_version;
  m->stamp_ns = wall_now_ns();
  m->keep_alive = std::move(keep_alive);
  m->origin = origin;
  g_live.fetch_add(1, std::memory_order_relaxed);
  return m;
}

plr_msg* msg_loaned(std::uint8_t* data, std::size_t capacity, std::unique_ptr<MsgLoan> loan) {
  auto* m = new plr_msg;
  m->external = data;
  m->capacity = capacity;
  m->size = capacity;
  m->loan = std::move(loan);
  g_live.fetch_add(1, std::memory_order_relaxed);
  return m;
}

void msg_retain(const plr_msg* msg) {
  const_cast<plr_msg*>(msg)->refs.fetch_add(1, std::memory_order_relaxed);
}

void msg_release(const plr_msg* msg) {
  auto* m = const_cast<plr_msg*>(msg);
  if (m->refs.fetch_sub(1, std::memory_order_acq_rel) == 1) {
    delete m;
    g_live.fetch_sub(1, std::memory_order_relaxed);
  }
}

plr_msg_view msg_view(const plr_msg* m) {
  const std::uint8_t* base = m->external ? m->external : m->storage.get();
  return {base + m->offset, m->size, m->type_id, m->schema_version, m->stamp_ns};
}

std::int64_t live_messages() {
  return g_live.load();
}

std::int64_t wall_now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

}  // namespace plr::kernel
