// How much freed memory the allocator may keep in a kernel's process.
//
// glibc raises its mmap threshold to the size of each large block freed (up
// to 32 MiB) and its trim threshold to twice that. After ARA* freed its
// state table (a vector doubled up to 20 MiB), `plr run`'s planner arena
// kept 17 MiB of freed memory at its top (mmap threshold 20 MiB, trim
// threshold 42 MiB), which malloc_trim() does not give back for an arena
// other than the main one. A swap starts the new instance's thread while the
// old one still runs, so the planners' threads move between arenas, each
// keeping its own planner's peak (PlannerSwap.APlannerSwappedOutGivesItsMemoryBack:
// 33.6, then 55 MiB under RRTConnect). Fixed thresholds stop that: blocks of
// kMmapThreshold and more are mapped and unmapped, and an arena's free top
// beyond kTrimThreshold goes back to the system as it is freed.
#pragma once

#include <cstddef>

namespace plr::kernel {

inline constexpr std::size_t kMmapThreshold = std::size_t{1} << 20;
inline constexpr std::size_t kTrimThreshold = std::size_t{1} << 20;

// Sets the thresholds, once per process (before threads multiply: call it
// early). Kernel's constructor does.
void bound_heap_retention();

// Gives back the free pages of every arena (after a swap freed an instance).
void release_free_heap();

}  // namespace plr::kernel
