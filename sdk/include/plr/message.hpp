// Typed views of kernel-owned message buffers, and their type identities.
#pragma once

#include <plr/plugin_abi.h>

#include <flatbuffers/flatbuffers.h>

#include <cstdint>
#include <cstring>
#include <string_view>
#include <utility>
#include <vector>

namespace plr {

constexpr std::uint64_t fnv1a(std::string_view s) {
  std::uint64_t h = 1469598103934665603ull;
  for (char c : s) {
    h ^= static_cast<unsigned char>(c);
    h *= 1099511628211ull;
  }
  return h;
}

// Every FlatBuffers table is a message type; its id is the hash of its fully
// qualified schema name (flatc --gen-name-strings). Bump schema_version in a
// specialisation when a type changes incompatibly.
template <class T>
struct MessageTraits {
  static constexpr std::string_view name() { return T::GetFullyQualifiedName(); }
  static constexpr std::uint64_t type_id() { return fnv1a(name()); }
  static constexpr std::uint32_t schema_version = 1;
};

// Verifies untrusted bytes as a T before anyone reads them.
template <class T>
bool verify(const std::uint8_t* data, std::size_t size) {
  if (data == nullptr || size < sizeof(flatbuffers::uoffset_t) ||
      size > FLATBUFFERS_MAX_BUFFER_SIZE)
    return false;
  flatbuffers::Verifier verifier(data, size);
  return verifier.VerifyBuffer<T>(nullptr);
}

// A message nested in a [ubyte] field of another. Its structs of doubles are
// read in place, so its bytes must start on an 8-byte boundary: FlatBuffers
// aligns a byte vector to 4 only, so writers force 8 and readers copy a
// misaligned buffer (from a foreign writer) before reading it.
inline constexpr std::size_t kNestedAlignment = 8;

inline flatbuffers::Offset<flatbuffers::Vector<std::uint8_t>> create_nested(
    flatbuffers::FlatBufferBuilder& fbb, const std::uint8_t* data, std::size_t size) {
  fbb.ForceVectorAlignment(size, sizeof(std::uint8_t), kNestedAlignment);
  return fbb.CreateVector(data, size);
}

// The verified T nested in `bytes`, or nullptr when absent or invalid.
// `storage` keeps an aligned copy when one is needed: it must outlive the result.
template <class T>
const T* read_nested(const flatbuffers::Vector<std::uint8_t>* bytes,
                     std::vector<std::uint64_t>& storage) {
  if (bytes == nullptr) return nullptr;
  const std::uint8_t* data = bytes->data();
  const std::size_t size = bytes->size();
  if (reinterpret_cast<std::uintptr_t>(data) % kNestedAlignment != 0) {
    storage.assign((size + sizeof(std::uint64_t) - 1) / sizeof(std::uint64_t), 0);
    std::memcpy(storage.data(), data, size);
    data = reinterpret_cast<const std::uint8_t*>(storage.data());
  }
  return verify<T>(data, size) ? flatbuffers::GetRoot<T>(data) : nullptr;
}

// A reference to a received message; copies share the kernel's buffer.
template <class T>
class Message {
 public:
  Message() = default;
  Message(const plr_host_api* api, const plr_msg* msg) : api_(api), msg_(msg) {
    if (msg_) api_->msg_retain(msg_);
  }
  Message(const Message& o) : Message(o.api_, o.msg_) {}
  Message(Message&& o) noexcept
      : api_(std::exchange(o.api_, nullptr)), msg_(std::exchange(o.msg_, nullptr)) {}
  Message& operator=(Message o) noexcept {
    std::swap(api_, o.api_);
    std::swap(msg_, o.msg_);
    return *this;
  }
  ~Message() {
    if (msg_) api_->msg_release(msg_);
  }

  explicit operator bool() const { return msg_ != nullptr; }
  const T* get() const { return flatbuffers::GetRoot<T>(view().data); }
  const T* operator->() const { return get(); }
  const T& operator*() const { return *get(); }
  plr_msg_view view() const { return api_->msg_view(msg_); }
  const plr_msg* raw() const { return msg_; }

 private:
  const plr_host_api* api_ = nullptr;
  const plr_msg* msg_ = nullptr;
};

}  // namespace plr
