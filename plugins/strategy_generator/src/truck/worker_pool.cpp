#include "truck/worker_pool.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <plr/frame.hpp>

#include <fmt/format.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <deque>
#include <utility>

extern char** environ;

namespace plr::generator {

struct WorkerPool::Worker {
  pid_t pid = -1;
  int to = -1, from = -1;        // our ends of its stdin and stdout
  std::vector<std::uint8_t> in;  // bytes read, not yet a whole frame
  long job = -1;                 // index in the batch it works on, -1: idle
  std::uint64_t job_id = 0;
};

struct WorkerPool::RemoteSlot {
  std::unique_ptr<RemoteJob> call;
  long job = -1;
  std::uint64_t job_id = 0;
  std::chrono::steady_clock::time_point rest_until{};
};

WorkerPool::WorkerPool(WorkerPoolOptions options) : options_(std::move(options)) {}

plr::Expected<std::unique_ptr<WorkerPool>> WorkerPool::create(const WorkerPoolOptions& options) {
  if (options.workers < 0 || options.workers > 256 || options.remote_workers < 0 ||
      options.remote_workers > 256 || options.workers + options.remote_workers < 1)
    return plr::make_error(PLR_ERR_INVALID,
                           fmt::format("workers: {} local and {} remote; each 0..256, at least one",
                                       options.workers, options.remote_workers));
  if (options.remote_workers > 0 && !options.remote_send)
    return plr::make_error(PLR_ERR_INVALID, "remote workers: no way to send them jobs");
  if (options.workers > 0 && ::access(options.command.c_str(), X_OK) != 0)
    return plr::make_error(PLR_ERR_INVALID, fmt::format("worker program '{}': {}", options.command,
                                                        std::strerror(errno)));
  // A worker that dies while we write to it must not take us with it.
  ::signal(SIGPIPE, SIG_IGN);
  std::unique_ptr<WorkerPool> pool(new WorkerPool(options));
  for (int i = 0; i < options.workers; ++i) {
    pool->workers_.push_back(std::make_unique<Worker>());
    if (auto s = pool->spawn(*pool->workers_.back()); !s) return s.error();
  }
  for (int i = 0; i < options.remote_workers; ++i)
    pool->remote_.push_back(std::make_unique<RemoteSlot>());
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
  if (!plr::write_all(w.to, actions::frame_setup(options_.observation_json))) {
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
  using Clock = std::chrono::steady_clock;
  std::vector<plr::Expected<SimOutcome>> results(batch.size(), SimOutcome{});
  std::vector<int> attempts(batch.size(), 0);
  std::deque<long> todo;
  for (long i = 0; i < static_cast<long>(batch.size()); ++i) todo.push_back(i);
  std::size_t left = batch.size();

  // The request of a worker that failed on it goes back to the front of the
  // queue, unless workers failed on it max_attempts times (`counts`: the
  // failure may be the request's; a remote kernel gone is not).
  auto give_back = [&](long job, bool counts, const std::string& why) {
    busy_.fetch_sub(1, std::memory_order_relaxed);
    if (counts && ++attempts[static_cast<std::size_t>(job)] >= options_.max_attempts) {
      results[static_cast<std::size_t>(job)] = plr::make_error(
          PLR_ERR_INTERNAL, fmt::format("{}: a worker died on it {} times (last: {})",
                                        sim::to_string(batch[static_cast<std::size_t>(job)].action),
                                        options_.max_attempts, why));
      --left;
    } else {
      todo.push_front(job);
    }
  };
  auto lost = [&](Worker& w, const std::string& why) {
    if (w.job >= 0) give_back(w.job, true, why);
    w.job = -1;
    if (w.pid > 0) ::kill(w.pid, SIGKILL);
    bury(w);
    restarts_.fetch_add(1, std::memory_order_relaxed);
    (void)spawn(w);  // a worker that cannot start stays down; the others go on
  };
  auto remote_answer = [&](RemoteSlot& r) {
    auto bytes = r.call->take();
    r.call.reset();
    const long job = std::exchange(r.job, -1);
    if (!bytes) {
      // The service refused the job as bad: the request's fault. Anything
      // else (no provider, its kernel gone, a timeout): the worker's.
      const bool refused = bytes.error().code == PLR_ERR_INVALID;
      remote_failures_.fetch_add(1, std::memory_order_relaxed);
      r.rest_until = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                        std::chrono::duration<double>(options_.remote_retry_s));
      give_back(job, refused, "remote: " + bytes.error().message);
      return;
    }
    auto frame = actions::decode_frame(bytes->data(), bytes->size(), "remote worker");
    if (!frame || frame->kind != actions::Frame::Kind::kResult || frame->id != r.job_id) {
      remote_failures_.fetch_add(1, std::memory_order_relaxed);
      give_back(job, true,
                frame ? "a remote worker answered another request" : frame.error().message);
      return;
    }
    results[static_cast<std::size_t>(job)] = std::move(frame->result);
    busy_.fetch_sub(1, std::memory_order_relaxed);
    remote_done_.fetch_add(1, std::memory_order_relaxed);
    --left;
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
      if (!plr::write_all(w.to, actions::frame_job(w.job_id, batch[static_cast<std::size_t>(j)])))
        lost(w, "its pipe closed");
    }
    const auto now = Clock::now();
    for (auto& rp : remote_) {
      RemoteSlot& r = *rp;
      if (r.job >= 0 || todo.empty() || now < r.rest_until) continue;
      r.job = todo.front();
      todo.pop_front();
      r.job_id = next_id_++;
      busy_.fetch_add(1, std::memory_order_relaxed);
      const SimRequest& request = batch[static_cast<std::size_t>(r.job)];
      flatbuffers::FlatBufferBuilder fbb(request.state->size() + 1024);
      actions::build_job(fbb, r.job_id, request, options_.observation_json);
      r.call = options_.remote_send(fbb);
    }
    std::vector<pollfd> fds;
    std::vector<Worker*> polled;
    for (auto& wp : workers_) {
      if (wp->pid > 0 && wp->job >= 0) {
        fds.push_back({wp->from, POLLIN, 0});
        polled.push_back(wp.get());
      }
    }
    if (fds.empty() && remote_.empty()) {
      // Every worker is down and none can start: what is left fails.
      for (const long j : todo)
        results[static_cast<std::size_t>(j)] =
            plr::make_error(PLR_ERR_UNAVAILABLE, "no simulation worker could be started");
      break;
    }
    // Remote answers are looked for every 10 ms: a simulation takes a second.
    const int wait_ms = remote_.empty() ? 1000 : 10;
    if (::poll(fds.data(), fds.size(), wait_ms) < 0 && errno != EINTR) break;
    for (auto& rp : remote_)
      if (rp->job >= 0 && rp->call && rp->call->done()) remote_answer(*rp);
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
      if (size > actions::kMaxFrameBytes) {
        lost(w, "it sent an oversized frame");
        continue;
      }
      if (w.in.size() < size + 4) continue;
      auto frame = actions::decode_frame(w.in.data() + 4, size, fmt::format("worker {}", w.pid));
      w.in.erase(w.in.begin(), w.in.begin() + static_cast<long>(size + 4));
      if (!frame || frame->kind != actions::Frame::Kind::kResult || frame->id != w.job_id) {
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
