#include "pause_for_tests.hpp"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <mutex>

namespace plr::jobs {

namespace {

constexpr const char* kVariable = "PLR_JOBS_TEST_PAUSE";

struct Pause {
  unsigned long after = 0;  // 0: no pause
  int fd = -1;
};

Pause read_pause() {
  const char* value = std::getenv(kVariable);
  if (value == nullptr) return {};
  char* end = nullptr;
  const unsigned long after = std::strtoul(value, &end, 10);
  if (after > 0 && *end == ':') {
    char* fd_end = nullptr;
    const long fd = std::strtol(end + 1, &fd_end, 10);
    if (fd >= 0 && fd_end != end + 1 && *fd_end == '\0') return {after, static_cast<int>(fd)};
  }
  std::fprintf(stderr, "plr jobs: %s='%s': not <results>:<fd>, ignored\n", kVariable, value);
  return {};
}

}  // namespace

void pause_for_tests() {
  static const Pause pause = read_pause();
  if (pause.after == 0) return;
  // Counted over the process's runs: a generation is many batches.
  static std::mutex mutex;
  static unsigned long stored = 0;
  std::lock_guard lock(mutex);
  if (++stored < pause.after) return;
  static const char kLine[] = "paused\n";
  (void)!::write(pause.fd, kLine, sizeof kLine - 1);
  // The lock held: no other run of this process stores anything either.
  for (;;) ::pause();
}

}  // namespace plr::jobs
