// An mmap'ed POSIX shared-memory object (RAII). Not on the data path.
#pragma once

#include <sys/stat.h>
#include <sys/types.h>

#include <cstddef>
#include <string>

#include "layout.hpp"
#include "plr/shm/types.hpp"

namespace plr::shm::detail {

class Segment {
 public:
  Segment() = default;
  Segment(Segment&& o) noexcept;
  Segment& operator=(Segment&& o) noexcept;
  Segment(const Segment&) = delete;
  Segment& operator=(const Segment&) = delete;
  ~Segment();

  // Creates name exclusively (0600), sized and pre-faulted, with the header
  // stamped except for the magic (see publish_header). A leftover segment of a
  // dead owner is replaced; one of a live owner is kAlreadyExists.
  static Result<Segment> create(const std::string& name, std::size_t size, SegmentKind kind,
                                std::string_view endpoint);
  // Opens an existing segment and checks owner uid, mode 0600, magic, layout
  // version, kind, size and endpoint name.
  static Result<Segment> open(const std::string& name, SegmentKind kind, std::string_view endpoint);

  // Makes the segment visible to openers: magic is written last.
  void publish_header() noexcept;
  // Removes the name if it still refers to this segment's object.
  void unlink() noexcept;

  std::byte* data() const noexcept { return base_; }
  std::size_t size() const noexcept { return size_; }
  SegmentHeader& header() const noexcept { return *reinterpret_cast<SegmentHeader*>(base_); }
  ProcessStamp owner() const noexcept { return owner_; }
  const std::string& name() const noexcept { return name_; }

 private:
  // The object `name` mapped at `base` (`st`: its identity, for unlink()).
  static Segment mapped(const std::string& name, void* base, std::size_t size,
                        const struct stat& st);

  std::string name_;
  std::byte* base_ = nullptr;
  std::size_t size_ = 0;
  dev_t dev_ = 0;
  ino_t ino_ = 0;
  ProcessStamp owner_{};  // copied at open: the shared copy is not trusted later
};

}  // namespace plr::shm::detail
