// A buffer loaned from the kernel for one message of one publisher: build the
// FlatBuffer straight into it, then publish it. When another process reads
// the topic the buffer is a shared-memory slot, so nobody copies the message
// (those readers and the ones in this process read the slot in place);
// otherwise it is kernel memory that in-process subscribers share.
//
//   auto loan = publisher.loan(64 * 1024);
//   auto& fbb = loan->builder();
//   fbb.Finish(CreateThing(fbb, ...));
//   loan->publish();
//
// A loan dropped unpublished goes back to the kernel.
#pragma once

#include <plr/plugin_abi.h>
#include <plr/expected.hpp>

#include <flatbuffers/flatbuffers.h>

#include <cstdint>
#include <cstring>
#include <memory>
#include <utility>

namespace plr {

class Loan {
 public:
  Loan(const plr_host_api* api, std::uint64_t publisher, plr_msg* msg, std::uint8_t* data,
       std::size_t capacity)
      : api_(api), publisher_(publisher), msg_(msg), data_(data), capacity_(capacity) {}
  Loan(Loan&& o) noexcept
      : api_(o.api_),
        publisher_(o.publisher_),
        msg_(std::exchange(o.msg_, nullptr)),
        data_(o.data_),
        capacity_(o.capacity_),
        build_(std::move(o.build_)) {}
  Loan& operator=(Loan&&) = delete;
  Loan(const Loan&) = delete;
  Loan& operator=(const Loan&) = delete;
  ~Loan() {
    build_.reset();
    if (msg_ != nullptr) api_->msg_release(msg_);
  }

  std::uint8_t* data() const { return data_; }
  std::size_t capacity() const { return capacity_; }

  // A builder over this buffer. A message that outgrows capacity() moves to
  // the heap as it grows, and publish() then copies it once.
  flatbuffers::FlatBufferBuilder& builder() {
    if (!build_) build_ = std::make_unique<Build>(data_, capacity_);
    return build_->fbb;
  }

  // Publishes the finished builder().
  Status publish() {
    if (!build_ || build_->fbb.GetSize() == 0)
      return make_error(PLR_ERR_INVALID, "publish: nothing built in the loan");
    const auto* p = build_->fbb.GetBufferPointer();
    const std::size_t size = build_->fbb.GetSize();
    if (p >= data_ && p + size <= data_ + capacity_)
      return publish(static_cast<std::size_t>(p - data_), size);
    std::uint8_t* fresh = nullptr;
    plr_msg* msg = api_->loan(api_->ctx, publisher_, size, &fresh);
    if (msg == nullptr) return make_error(PLR_ERR_UNAVAILABLE, "publish: no buffer available");
    std::memcpy(fresh, p, size);
    api_->msg_release(std::exchange(msg_, msg));
    data_ = fresh;
    capacity_ = size;
    return publish(0, size);
  }

  // Publishes data()[offset, offset + size), written by the caller.
  Status publish(std::size_t offset, std::size_t size) {
    if (msg_ == nullptr) return make_error(PLR_ERR_STATE, "publish: loan already published");
    const auto s = api_->publish(api_->ctx, publisher_, std::exchange(msg_, nullptr), offset, size);
    if (s != PLR_OK) return make_error(s, "publish failed");
    return {};
  }

 private:
  // Hands the loaned bytes to the builder once; anything bigger comes from the heap.
  class Allocator final : public flatbuffers::Allocator {
   public:
    Allocator(std::uint8_t* data, std::size_t capacity) : data_(data), capacity_(capacity) {}
    std::uint8_t* allocate(std::size_t size) override {
      if (!lent_ && size <= capacity_) {
        lent_ = true;
        return data_;
      }
      return new std::uint8_t[size];
    }
    void deallocate(std::uint8_t* p, std::size_t) override {
      if (p != data_) delete[] p;
    }

   private:
    std::uint8_t* data_;
    std::size_t capacity_;
    bool lent_ = false;
  };

  struct Build {
    // FlatBuffers builds downwards from the end, which must stay aligned to
    // its largest scalar: use a multiple of 8 bytes.
    Build(std::uint8_t* data, std::size_t capacity)
        : alloc(data, capacity & ~std::size_t{7}), fbb(capacity & ~std::size_t{7}, &alloc) {}
    Allocator alloc;
    flatbuffers::FlatBufferBuilder fbb;
  };

  const plr_host_api* api_;
  std::uint64_t publisher_;
  plr_msg* msg_;
  std::uint8_t* data_;
  std::size_t capacity_;
  std::unique_ptr<Build> build_;
};

}  // namespace plr
