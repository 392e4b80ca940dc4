#include "heap_policy.hpp"

#include <malloc.h>

#include <mutex>

namespace plr::kernel {

void bound_heap_retention() {
  static std::once_flag once;
  std::call_once(once, [] {
    // Setting either turns glibc's dynamic thresholds off.
    mallopt(M_MMAP_THRESHOLD, static_cast<int>(kMmapThreshold));
    mallopt(M_TRIM_THRESHOLD, static_cast<int>(kTrimThreshold));
  });
}

void release_free_heap() {
  malloc_trim(0);
}

}  // namespace plr::kernel
