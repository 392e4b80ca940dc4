#include "plr/jobs/spawn_runner.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <plr/frame.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <deque>
#include <map>

#include "plr/jobs/messages.hpp"

extern char** environ;

namespace plr::jobs {

namespace {
using Clock = std::chrono::steady_clock;
}  // namespace

struct SpawnRunner::Worker {
  pid_t pid = -1;
  int to = -1, from = -1;  // our ends of its stdin and stdout
  FrameReader reader{kMaxBytes + 4096, "worker"};
  long job = -1;  // index of the job it works on; -1: idle
  std::uint64_t id = 0;
  Clock::time_point start;
};

SpawnRunner::SpawnRunner(SpawnOptions options) : options_(std::move(options)) {}

plr::Expected<std::unique_ptr<SpawnRunner>> SpawnRunner::create(SpawnOptions options) {
  if (options.command.empty() || options.workers < 1 || options.workers > 256)
    return plr::make_error(PLR_ERR_INVALID, "workers: a program and 1..256 of them");
  if (::access(options.command[0].c_str(), X_OK) != 0)
    return plr::make_error(PLR_ERR_INVALID, fmt::format("worker program '{}': {}",
                                                        options.command[0], std::strerror(errno)));
  // A worker that dies while we write to it must not take us with it.
  ::signal(SIGPIPE, SIG_IGN);
  std::unique_ptr<SpawnRunner> runner(new SpawnRunner(std::move(options)));
  for (unsigned i = 0; i < runner->options_.workers; ++i) {
    runner->workers_.push_back(std::make_unique<Worker>());
    if (auto s = runner->spawn(*runner->workers_.back()); !s) return s.error();
  }
  return runner;
}

SpawnRunner::~SpawnRunner() {
  // Closing its stdin ends a worker; bury() waits for it.
  for (auto& w : workers_) bury(*w);
}

std::vector<pid_t> SpawnRunner::pids() const {
  std::vector<pid_t> out;
  for (const auto& w : workers_) out.push_back(w->pid);
  return out;
}

plr::Status SpawnRunner::spawn(Worker& w) {
  int to[2], from[2];
  if (::pipe2(to, O_CLOEXEC) != 0) return plr::make_error(PLR_ERR_INTERNAL, "pipe failed");
  if (::pipe2(from, O_CLOEXEC) != 0) {
    ::close(to[0]);
    ::close(to[1]);
    return plr::make_error(PLR_ERR_INTERNAL, "pipe failed");
  }
  posix_spawn_file_actions_t fa;
  posix_spawn_file_actions_init(&fa);
  posix_spawn_file_actions_adddup2(&fa, to[0], STDIN_FILENO);
  posix_spawn_file_actions_adddup2(&fa, from[1], STDOUT_FILENO);
  std::vector<char*> argv;
  for (const std::string& a : options_.command) argv.push_back(const_cast<char*>(a.c_str()));
  argv.push_back(nullptr);
  pid_t pid = -1;
  const int rc = ::posix_spawn(&pid, argv[0], &fa, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&fa);
  ::close(to[0]);
  ::close(from[1]);
  if (rc != 0) {
    ::close(to[1]);
    ::close(from[0]);
    return plr::make_error(PLR_ERR_INTERNAL, fmt::format("starting worker '{}': {}",
                                                         options_.command[0], std::strerror(rc)));
  }
  w.pid = pid;
  w.to = to[1];
  w.from = from[0];
  w.reader = FrameReader(kMaxBytes + 4096, fmt::format("worker {}", pid));
  w.job = -1;
  return {};
}

void SpawnRunner::bury(Worker& w) {
  if (w.to >= 0) ::close(w.to);
  if (w.from >= 0) ::close(w.from);
  w.to = w.from = -1;
  if (w.pid > 0)
    while (::waitpid(w.pid, nullptr, 0) < 0 && errno == EINTR) {
    }
  w.pid = -1;
  w.job = -1;
}

void SpawnRunner::run(const std::vector<Job>& jobs, const std::vector<std::size_t>& todo,
                      const Done& done, const std::function<bool()>& stop) {
  std::deque<std::size_t> queue(todo.begin(), todo.end());
  std::map<std::size_t, std::uint32_t> attempts;
  std::size_t left = todo.size();

  auto fail = [&](std::size_t i, std::string why, double wall_s) {
    Result r;
    r.key = jobs[i].key;
    r.error = std::move(why);
    r.wall_s = wall_s;
    r.attempts = attempts[i];
    --left;
    done(i, std::move(r));
  };
  // Kills `w`, starts it again and hands its job out anew, unless it has
  // had max_attempts.
  auto lost = [&](Worker& w, const std::string& why) {
    const long job = w.job;
    const double s = std::chrono::duration<double>(Clock::now() - w.start).count();
    if (w.pid > 0) ::kill(w.pid, SIGKILL);
    bury(w);
    ++restarts_;
    (void)spawn(w);  // a worker that cannot start stays down; the others go on
    if (job < 0) return;
    const auto i = static_cast<std::size_t>(job);
    if (attempts[i] >= options_.max_attempts)
      fail(i, fmt::format("{} (attempt {})", why, attempts[i]), s);
    else
      queue.push_front(i);
  };

  while (left > 0) {
    if (stop && stop()) {
      // Its job is not reported: the worker is started again without it.
      for (auto& w : workers_)
        if (w->job >= 0) {
          w->job = -1;
          lost(*w, "stopped");
        }
      return;
    }
    for (auto& wp : workers_) {
      Worker& w = *wp;
      if (w.pid <= 0 || w.job >= 0 || queue.empty()) continue;
      const std::size_t i = queue.front();
      queue.pop_front();
      ++attempts[i];
      w.job = static_cast<long>(i);
      w.id = next_id_++;
      w.start = Clock::now();
      const Bytes request = encode_request(w.id, jobs[i]);
      if (!plr::write_all(w.to, plr::frame(request.data(), request.size())))
        lost(w, "worker's stdin closed");
    }
    std::vector<pollfd> fds;
    std::vector<Worker*> polled;
    for (auto& w : workers_)
      if (w->pid > 0 && w->job >= 0) {
        fds.push_back({w->from, POLLIN, 0});
        polled.push_back(w.get());
      }
    if (fds.empty() &&
        std::none_of(workers_.begin(), workers_.end(), [](const auto& w) { return w->pid > 0; })) {
      // Every worker is down and none can start: what is left fails.
      while (!queue.empty()) {
        const std::size_t i = queue.front();
        queue.pop_front();
        fail(i, "no worker could be started", 0.0);
      }
      return;
    }
    // Woken by a worker's bytes or its end; every 50 ms for timeouts and stop.
    if (::poll(fds.data(), fds.size(), 50) < 0 && errno != EINTR) return;
    for (std::size_t k = 0; k < fds.size(); ++k) {
      if (fds[k].revents == 0) continue;
      Worker& w = *polled[k];
      std::uint8_t chunk[1 << 16];
      const ssize_t n = ::read(w.from, chunk, sizeof chunk);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        lost(w, n == 0 ? "worker exited" : std::strerror(errno));
        continue;
      }
      w.reader.feed(chunk, static_cast<std::size_t>(n));
      auto payload = w.reader.next();
      if (!payload) {
        lost(w, payload.error().message);
        continue;
      }
      if (!*payload) continue;
      auto message = decode_message((*payload)->data(), (*payload)->size(), "worker");
      if (!message || message->type != Message::Type::kReply || message->id != w.id) {
        lost(w, message ? "worker answered another request" : message.error().message);
        continue;
      }
      const auto i = static_cast<std::size_t>(w.job);
      Result r = std::move(message->result);
      r.attempts = attempts[i];
      r.wall_s = std::chrono::duration<double>(Clock::now() - w.start).count();
      w.job = -1;
      --left;
      done(i, std::move(r));
    }
    const auto now = Clock::now();
    for (auto& w : workers_) {
      if (w->job < 0) continue;
      const double s = std::chrono::duration<double>(now - w->start).count();
      if (s > options_.timeout_s) lost(*w, fmt::format("killed after {:.0f} s wall", s));
    }
  }
}

}  // namespace plr::jobs
