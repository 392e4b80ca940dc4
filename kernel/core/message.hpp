// The kernel's message buffer behind the SDK's opaque plr_msg: one heap block,
// reference-counted, immutable once published, shared by every in-process reader.
#pragma once

#include <plr/plugin_abi.h>

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>

namespace plr::kernel {
// Memory a transport loaned for one message (a shared-memory slot). When the
// bus publishes the message on the topic it was loaned for, it commits the
// loan: the transport sends those very bytes, without a copy, and keeps them
// readable for in-process readers until the message dies.
struct MsgLoan {
  virtual ~MsgLoan() = default;
  // True when sent; false leaves the bytes untouched (the transport may copy them).
  virtual bool commit(const plr_msg& msg) = 0;
  const void* topic = nullptr;      // the bus topic it was loaned for
  const void* transport = nullptr;  // becomes the message's origin once committed
  const void* endpoint = nullptr;   // the transport's bus endpoint: not handed the message
};
}  // namespace plr::kernel

struct plr_msg {
  std::atomic<std::uint32_t> refs{1};
  std::unique_ptr<std::uint8_t[]> storage;
  std::size_t capacity = 0;
  std::size_t offset = 0;
  std::size_t size = 0;
  std::uint64_t type_id = 0;
  std::uint32_t schema_version = 0;
  std::int64_t stamp_ns = 0;
  const void* topic = nullptr;  // the bus topic it was published on, for counters
  // Bytes that live elsewhere (a shared-memory slot read in place), kept
  // alive by `keep_alive` for as long as this message lives.
  const std::uint8_t* external = nullptr;
  std::shared_ptr<void> keep_alive;
  // The transport that brought it from another process, or sent it from a
  // loaned slot; that transport does not send it (again).
  const void* origin = nullptr;
  // Set while the bytes are a transport's loaned memory (`external`).
  std::unique_ptr<plr::kernel::MsgLoan> loan;
};

namespace plr::kernel {

plr_msg* msg_alloc(std::size_t capacity, std::uint8_t** data);
// A buffer holding a copy of bytes that arrived from elsewhere.
plr_msg* msg_copy(const std::uint8_t* data, std::size_t size, std::uint64_t type_id,
                  std::uint32_t schema_version, std::int64_t stamp_ns);
// A writable message over a transport's loaned bytes (zero copy on publish).
plr_msg* msg_loaned(std::uint8_t* data, std::size_t capacity, std::unique_ptr<MsgLoan> loan);
// A message over bytes owned by `keep_alive` (zero copy).
plr_msg* msg_wrap(const std::uint8_t* data, std::size_t size, std::uint64_t type_id,
                  std::uint32_t schema_version, std::shared_ptr<void> keep_alive,
                  const void* origin);
void msg_retain(const plr_msg* msg);
void msg_release(const plr_msg* msg);
plr_msg_view msg_view(const plr_msg* msg);
// Live buffers in this process; tests use it to prove nothing leaked.
std::int64_t live_messages();

// Owns one reference.
struct MsgRef {
  MsgRef() = default;
  explicit MsgRef(plr_msg* m) : msg(m) {}  // adopts
  MsgRef(const MsgRef& o) : msg(o.msg) {
    if (msg) msg_retain(msg);
  }
  MsgRef(MsgRef&& o) noexcept : msg(o.msg) { o.msg = nullptr; }
  MsgRef& operator=(MsgRef o) noexcept {
    std::swap(msg, o.msg);
    return *this;
  }
  ~MsgRef() {
    if (msg) msg_release(msg);
  }
  plr_msg* msg = nullptr;
};

std::int64_t wall_now_ns();

}  // namespace plr::kernel
