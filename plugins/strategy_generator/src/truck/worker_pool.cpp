#include "truck/worker_pool.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>

#include <cerrno>
#include <cstring>
#include <deque>

extern char** environ;

namespace plr::generator {

struct WorkerPool::Worker {
  pid_t pid = -1;
  int to = -1, from = -1;        // our ends of its stdin and stdout
  std::vector<std::uint8_t> in;  // bytes read, not yet a whole frame
  long job = -1;                 // index in the batch it works on, -1: idle
  std::uint64_t job_id = 0;
};

namespace {}  // namespace

WorkerPool::WorkerPool(WorkerPoolOptions options) : options_(std::move(options)) {}

plr::Expected<std::unique_ptr<WorkerPool>> WorkerPool::create(const WorkerPoolOptions& options) {
  if (options.workers < 1 || options.workers > 256)
    return plr::make_error(PLR_ERR_INVALID,
                           fmt::format("workers: {} is not in 1..256", options.workers));
  if (::access(options.command.c_str(), X_OK) != 0)
    return plr::make_error(PLR_ERR_INVALID, fmt::format("worker program '{}': {}", options.command,
                                                        std::strerror(errno)));
  // A worker that dies while we write to it must not take us with it.
  ::signal(SIGPIPE, SIG_IGN);
  std::unique_ptr<WorkerPool> pool(new WorkerPool(options));
  for (int i = 0; i < options.workers; ++i) {
    pool->workers_.push_back(std::make_unique<Worker>());
    if (auto s = pool->spawn(*pool->workers_.back()); !s) return s.error();
  }
  return pool;
}

WorkerPool::~WorkerPool() {
  for (auto& w : workers_) {
    if (w->pid > 0) ::kill(w->pid, SIGTERM);
    bury(*w);
  }
}

std::vector<pid_t> WorkerPool::pids() const {
  std::vector<pid_t> out;
  for (const auto& w : workers_) out.push_back(w->pid);
  return out;
}

plr::Status WorkerPool::spawn(Worker& w) {
  int to[2], from[2];
  if (::pipe2(to, O_CLOEXEC) != 0 || ::pipe2(from, O_CLOEXEC) != 0)
    return plr::make_error(PLR_ERR_INTERNAL, fmt::format("pipe: {}", std::strerror(errno)));
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_adddup2(&fa, to[0], 0);
  posix_spawn_file_actions_adddup2(&fa, from[1], 1);
  char* argv[] = {const_cast<char*>(options_.command.c_str()), nullptr};
  pid_t pid = -1;
  const int rc = ::posix_spawn(&pid, options_.command.c_str(), &fa, nullptr, argv, environ);
  posix_spawn_file_actions_destroy(&fa);
  ::close(to[0]);
  ::close(from[1]);
  if (rc != 0) {
    ::close(to[1]);
    ::close(from[0]);
    return plr::make_error(PLR_ERR_INTERNAL, fmt::format("starting worker '{}': {}",
                                                         options_.command, std::strerror(rc)));
  }
  w.pid = pid;
  w.to = to[1];
  w.from = from[0];
  w.in.clear();
  w.job = -1;
  if (!write_all(w.to, frame_setup(options_.observation_json))) {
    bury(w);
    return plr::make_error(PLR_ERR_INTERNAL,
                           fmt::format("worker '{}' exited at start", options_.command));
  }
  return {};
}

void WorkerPool::bury(Worker& w) {
  if (w.to >= 0) ::close(w.to);
  if (w.from >= 0) ::close(w.from);
  w.to = w.from = -1;
  if (w.pid > 0) {
    int status = 0;
    while (::waitpid(w.pid, &status, 0) < 0 && errno == EINTR) {
    }
  }
  w.pid = -1;
  w.in.clear();
}

std::vector<plr::Expected<SimOutcome>> WorkerPool::run(const std::vector<SimRequest>& batch) {
  std::vector<plr::Expected<SimOutcome>> results(batch.size(), SimOutcome{});
  std::vector<int> attempts(batch.size(), 0);
  std::deque<long> todo;
  for (long i = 0; i < static_cast<long>(batch.size()); ++i) todo.push_back(i);
  std::size_t left = batch.size();

  auto lost = [&](Worker& w, const std::string& why) {
    // Its request goes back to the front of the queue; the worker starts again.
    if (w.job >= 0) {
      if (++attempts[static_cast<std::size_t>(w.job)] >= options_.max_attempts) {
        results[static_cast<std::size_t>(w.job)] = plr::make_error(
            PLR_ERR_INTERNAL,
            fmt::format("{}: a worker died on it {} times (last: {})",
                        sim::to_string(batch[static_cast<std::size_t>(w.job)].action),
                        options_.max_attempts, why));
        --left;
      } else {
        todo.push_front(w.job);
      }
      w.job = -1;
      busy_.fetch_sub(1, std::memory_order_relaxed);
    }
    if (w.pid > 0) ::kill(w.pid, SIGKILL);
    bury(w);
    restarts_.fetch_add(1, std::memory_order_relaxed);
    (void)spawn(w);  // a worker that cannot start stays down; the others go on
  };

  while (left > 0) {
    for (auto& wp : workers_) {
      Worker& w = *wp;
      if (w.pid <= 0 || w.job >= 0 || todo.empty()) continue;
      const long j = todo.front();
      todo.pop_front();
      w.job = j;
      w.job_id = next_id_++;
      busy_.fetch_add(1, std::memory_order_relaxed);
      if (!write_all(w.to, frame_job(w.job_id, batch[static_cast<std::size_t>(j)])))
        lost(w, "its pipe closed");
    }
    std::vector<pollfd> fds;
    std::vector<Worker*> polled;
    for (auto& wp : workers_) {
      if (wp->pid > 0 && wp->job >= 0) {
        fds.push_back({wp->from, POLLIN, 0});
        polled.push_back(wp.get());
      }
    }
    if (fds.empty()) {
      // Every worker is down and none can start: what is left fails.
      for (const long j : todo)
        results[static_cast<std::size_t>(j)] =
            plr::make_error(PLR_ERR_UNAVAILABLE, "no simulation worker could be started");
      break;
    }
    if (::poll(fds.data(), fds.size(), 1000) < 0 && errno != EINTR) break;
    for (std::size_t k = 0; k < fds.size(); ++k) {
      if (fds[k].revents == 0) continue;
      Worker& w = *polled[k];
      std::uint8_t buf[1 << 16];
      const ssize_t n = ::read(w.from, buf, sizeof buf);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        lost(w, n == 0 ? "it exited" : std::strerror(errno));
        continue;
      }
      w.in.insert(w.in.end(), buf, buf + n);
      if (w.in.size() < 4) continue;
      const std::size_t size = static_cast<std::size_t>(w.in[0]) | std::size_t{w.in[1]} << 8 |
                               std::size_t{w.in[2]} << 16 | std::size_t{w.in[3]} << 24;
      if (size > kMaxFrameBytes) {
        lost(w, "it sent an oversized frame");
        continue;
      }
      if (w.in.size() < size + 4) continue;
      auto frame = decode_frame(w.in.data() + 4, size, fmt::format("worker {}", w.pid));
      w.in.erase(w.in.begin(), w.in.begin() + static_cast<long>(size + 4));
      if (!frame || frame->kind != Frame::Kind::kResult || frame->id != w.job_id) {
        lost(w, frame ? "it answered another request" : frame.error().message);
        continue;
      }
      results[static_cast<std::size_t>(w.job)] = std::move(frame->result);
      w.job = -1;
      busy_.fetch_sub(1, std::memory_order_relaxed);
      --left;
    }
  }
  return results;
}

}  // namespace plr::generator
