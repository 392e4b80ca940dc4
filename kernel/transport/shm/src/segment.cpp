#include "segment.hpp"

#include <dirent.h>
#include <fcntl.h>
#include <sys/mman.h>
#include <sys/stat.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstddef>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <new>
#include <utility>

#include "plr/shm/segments.hpp"

namespace plr::shm {

const char* to_string(Error e) noexcept {
  switch (e) {
    case Error::kInvalidArgument:
      return "invalid argument";
    case Error::kAlreadyExists:
      return "segment already owned by a live process";
    case Error::kNotFound:
      return "segment not found";
    case Error::kPermission:
      return "segment not private to this user (0600)";
    case Error::kOsError:
      return "operating system error";
    case Error::kIncompatible:
      return "incompatible or corrupt segment header";
    case Error::kTooLarge:
      return "message larger than the slot size";
    case Error::kNoData:
      return "no message";
    case Error::kTimeout:
      return "timed out";
    case Error::kSlotsExhausted:
      return "readers hold every slot";
    case Error::kTooManySubscribers:
      return "subscriber table full";
    case Error::kTooManyClients:
      return "service client table full";
    case Error::kPeerDead:
      return "peer process died";
    case Error::kClosed:
      return "peer closed";
    case Error::kUnknownClient:
      return "client no longer connected";
    case Error::kNoSpace:
      return "no room in /dev/shm (see its size with df /dev/shm)";
  }
  return "unknown error";
}

namespace {

constexpr const char* kShmDir = "/dev/shm/";
// A segment whose creator has not stamped it after this long was abandoned.
constexpr time_t kHalfCreatedGraceSeconds = 5;

std::uint64_t fnv1a(std::string_view s) {
  std::uint64_t h = 0xcbf29ce484222325ULL;
  for (unsigned char c : s) h = (h ^ c) * 0x100000001b3ULL;
  return h;
}

std::string user_prefix() {
  return "plr." + std::to_string(::geteuid()) + ".";
}

std::string make_name(std::string_view run_id, char kind, std::string_view endpoint) {
  char hash[17];
  std::snprintf(hash, sizeof hash, "%016llx", static_cast<unsigned long long>(fnv1a(endpoint)));
  std::string n = "/" + user_prefix();
  n.append(run_id);
  n += '.';
  n += kind;
  n += hash;
  return n;
}

std::uint64_t load_magic(const detail::SegmentHeader& h) {
  return std::atomic_ref<const std::uint64_t>(h.magic).load(std::memory_order_acquire);
}

enum class Owner { kLive, kDead, kUnknown };

// Classifies an existing segment by its stamp, without trusting its size.
Owner segment_owner(const std::string& shm_name) {
  const int fd = ::shm_open(shm_name.c_str(), O_RDONLY | O_CLOEXEC, 0);
  if (fd < 0) return Owner::kUnknown;
  struct stat st {};
  Owner result = Owner::kUnknown;
  if (::fstat(fd, &st) == 0 && st.st_uid == ::geteuid()) {
    const bool old = std::time(nullptr) - st.st_mtime > kHalfCreatedGraceSeconds;
    if (static_cast<std::size_t>(st.st_size) < sizeof(detail::SegmentHeader)) {
      result = old ? Owner::kDead : Owner::kLive;
    } else if (void* p =
                   ::mmap(nullptr, sizeof(detail::SegmentHeader), PROT_READ, MAP_SHARED, fd, 0);
               p != MAP_FAILED) {
      const auto& h = *static_cast<const detail::SegmentHeader*>(p);
      // Stamped with its owner before it has its name (Segment::create),
      // whether or not the magic is there yet.
      if (load_magic(h) == detail::kMagic || h.owner_pid != 0) {
        result = ProcessStamp{h.owner_pid, h.owner_start}.alive() ? Owner::kLive : Owner::kDead;
      } else {
        result = old ? Owner::kDead : Owner::kLive;
      }
      ::munmap(p, sizeof(detail::SegmentHeader));
    }
  }
  ::close(fd);
  return result;
}

}  // namespace

bool valid_run_id(std::string_view run_id) noexcept {
  if (run_id.empty() || run_id.size() > 48) return false;
  for (char c : run_id) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '_' || c == '-';
    if (!ok) return false;
  }
  return true;
}

bool valid_endpoint_name(std::string_view name) noexcept {
  return !name.empty() && name.size() < detail::kNameBytes &&
         name.find('\0') == std::string_view::npos;
}

std::string topic_segment_name(std::string_view run_id, std::string_view topic) {
  return make_name(run_id, 't', topic);
}

std::string service_segment_name(std::string_view run_id, std::string_view service) {
  return make_name(run_id, 's', service);
}

Result<std::size_t> remove_run_segments(std::string_view run_id) noexcept {
  if (!valid_run_id(run_id)) return Error::kInvalidArgument;
  DIR* dir = ::opendir(kShmDir);
  if (dir == nullptr) return Error::kOsError;
  std::string prefix = user_prefix();
  prefix.append(run_id);
  prefix += '.';
  std::size_t removed = 0;
  while (dirent* e = ::readdir(dir)) {
    if (std::strncmp(e->d_name, prefix.c_str(), prefix.size()) != 0) continue;
    if (::shm_unlink((std::string("/") + e->d_name).c_str()) == 0) ++removed;
  }
  ::closedir(dir);
  return removed;
}

std::size_t reclaim_stale_segments() noexcept {
  DIR* dir = ::opendir(kShmDir);
  if (dir == nullptr) return 0;
  const std::string prefix = user_prefix();
  std::size_t removed = 0;
  while (dirent* e = ::readdir(dir)) {
    if (std::strncmp(e->d_name, prefix.c_str(), prefix.size()) != 0) continue;
    const std::string name = std::string("/") + e->d_name;
    if (segment_owner(name) == Owner::kDead && ::shm_unlink(name.c_str()) == 0) ++removed;
  }
  ::closedir(dir);
  return removed;
}

namespace detail {

Segment::Segment(Segment&& o) noexcept
    : name_(std::move(o.name_)),
      base_(std::exchange(o.base_, nullptr)),
      size_(std::exchange(o.size_, 0)),
      dev_(o.dev_),
      ino_(o.ino_),
      owner_(o.owner_) {}

Segment& Segment::operator=(Segment&& o) noexcept {
  if (this != &o) {
    if (base_ != nullptr) ::munmap(base_, size_);
    name_ = std::move(o.name_);
    base_ = std::exchange(o.base_, nullptr);
    size_ = std::exchange(o.size_, 0);
    dev_ = o.dev_;
    ino_ = o.ino_;
    owner_ = o.owner_;
  }
  return *this;
}

Segment::~Segment() {
  if (base_ != nullptr) ::munmap(base_, size_);
}

Segment Segment::mapped(const std::string& name, void* base, std::size_t size,
                        const struct stat& st) {
  Segment s;
  s.name_ = name;
  s.base_ = static_cast<std::byte*>(base);
  s.size_ = size;
  s.dev_ = st.st_dev;
  s.ino_ = st.st_ino;
  return s;
}

Result<Segment> Segment::create(const std::string& name, std::size_t size, SegmentKind kind,
                                std::string_view endpoint) {
  if (size < sizeof(SegmentHeader) || !valid_endpoint_name(endpoint)) {
    return Error::kInvalidArgument;
  }
  // Made under a name of its own and stamped with its owner, then linked to
  // `name` in one step: `name` never exists without an owner, so a crash at
  // any instant leaves nothing there, or a dead owner's segment that the
  // next creator replaces at once (not one "owned by a live process").
  const std::string temporary = name + ".new" + std::to_string(::getpid());
  ::shm_unlink(temporary.c_str());  // a dead process's, with our pid
  const int fd = ::shm_open(temporary.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) return errno == EACCES ? Error::kPermission : Error::kOsError;
  const auto fail = [&](Error e) {
    ::close(fd);
    ::shm_unlink(temporary.c_str());
    return e;
  };
  const ProcessStamp me = ProcessStamp::self();
  const std::int32_t pid = me.pid;
  const std::uint64_t start = me.start_time;
  struct stat st {};
  // fchmod: the umask may have narrowed 0600, and nothing wider is allowed.
  if (::fchmod(fd, 0600) != 0 || ::ftruncate(fd, static_cast<off_t>(size)) != 0)
    return fail(Error::kOsError);
  // The pages now, not at first touch: a /dev/shm too small (Docker's 64 MB)
  // is an error here, where it was a SIGBUS in the middle of a run.
  if (const int e = ::posix_fallocate(fd, 0, static_cast<off_t>(size)); e != 0)
    return fail(e == ENOSPC ? Error::kNoSpace : Error::kOsError);
  if (::fstat(fd, &st) != 0 ||
      ::pwrite(fd, &pid, sizeof pid, offsetof(SegmentHeader, owner_pid)) != sizeof pid ||
      ::pwrite(fd, &start, sizeof start, offsetof(SegmentHeader, owner_start)) != sizeof start)
    return fail(Error::kOsError);
  const std::string from = kShmDir + temporary.substr(1), to = kShmDir + name.substr(1);
  for (int attempt = 0;; ++attempt) {
    if (::link(from.c_str(), to.c_str()) == 0) break;
    if (errno == EACCES || errno == EPERM) return fail(Error::kPermission);
    if (errno != EEXIST) return fail(Error::kOsError);
    // A crashed previous owner (a restarted host) leaves its segment behind.
    if (attempt == 1 || segment_owner(name) != Owner::kDead) return fail(Error::kAlreadyExists);
    ::shm_unlink(name.c_str());
  }
  ::shm_unlink(temporary.c_str());
  void* p = ::mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_SHARED | MAP_POPULATE, fd, 0);
  ::close(fd);
  if (p == MAP_FAILED) {
    ::shm_unlink(name.c_str());
    return Error::kOsError;
  }
  Segment s = mapped(name, p, size, st);
  s.owner_ = me;
  // Default-initialized, not zeroed: the owner stamp written above stays
  // (the fresh object's other bytes are zero).
  auto* h = new (p) SegmentHeader;
  h->magic = 0;
  h->reserved = 0;
  h->layout_version = kLayoutVersion;
  h->kind = kind;
  h->total_size = size;
  h->owner_pid = s.owner_.pid;
  h->owner_start = s.owner_.start_time;
  std::memcpy(h->name, endpoint.data(), endpoint.size());
  return s;
}

void Segment::publish_header() noexcept {
  std::atomic_ref<std::uint64_t>(header().magic).store(kMagic, std::memory_order_release);
}

Result<Segment> Segment::open(const std::string& name, SegmentKind kind,
                              std::string_view endpoint) {
  if (!valid_endpoint_name(endpoint)) return Error::kInvalidArgument;
  const int fd = ::shm_open(name.c_str(), O_RDWR | O_CLOEXEC, 0);
  if (fd < 0) {
    if (errno == ENOENT) return Error::kNotFound;
    if (errno == EACCES) return Error::kPermission;
    return Error::kOsError;
  }
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    ::close(fd);
    return Error::kOsError;
  }
  if (st.st_uid != ::geteuid() || (st.st_mode & 0777) != 0600) {
    ::close(fd);
    return Error::kPermission;
  }
  const auto size = static_cast<std::size_t>(st.st_size);
  if (size < sizeof(SegmentHeader)) {  // the creator has not sized it yet
    ::close(fd);
    return Error::kNotFound;
  }
  void* p = ::mmap(nullptr, size, PROT_READ | PROT_WRITE, MAP_SHARED | MAP_POPULATE, fd, 0);
  ::close(fd);
  if (p == MAP_FAILED) return Error::kOsError;
  Segment s = mapped(name, p, size, st);
  const SegmentHeader& h = s.header();
  const std::uint64_t magic = load_magic(h);
  if (magic == 0) return Error::kNotFound;  // not stamped yet
  char stored[kNameBytes];
  std::memcpy(stored, h.name, kNameBytes);
  stored[kNameBytes - 1] = '\0';
  if (magic != kMagic || h.layout_version != kLayoutVersion || h.kind != kind ||
      h.total_size != size || std::string_view(stored) != endpoint) {
    return Error::kIncompatible;
  }
  s.owner_ = ProcessStamp{h.owner_pid, h.owner_start};
  return s;
}

void Segment::unlink() noexcept {
  struct stat st {};
  const std::string path = kShmDir + name_.substr(1);
  if (::stat(path.c_str(), &st) == 0 && st.st_dev == dev_ && st.st_ino == ino_) {
    ::shm_unlink(name_.c_str());
  }
}

}  // namespace detail
}  // namespace plr::shm
