#include "plr/jobs/process_runner.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <plr/frame.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <deque>
#include <map>

#include "plr/jobs/messages.hpp"
#include "plr/jobs/worker.hpp"

extern char** environ;

namespace plr::jobs {

namespace {

using Clock = std::chrono::steady_clock;

std::string status_text(int status) {
  if (WIFSIGNALED(status)) return fmt::format("job process died (signal {})", WTERMSIG(status));
  return fmt::format("job process exited with status {} without a result",
                     WIFEXITED(status) ? WEXITSTATUS(status) : -1);
}

}  // namespace

struct ProcessRunner::Worker {
  pid_t pid = -1;
  int to = -1, from = -1;  // our ends of its stdin and stdout
  FrameReader reader{kMaxBytes + 4096, "worker"};
  long job = -1;  // index of the job it works on; -1: idle
  std::uint64_t id = 0;
  bool broken = false;  // could not be started: stays down
  Clock::time_point start;
};

ProcessRunner::ProcessRunner(ProcessOptions options) : options_(std::move(options)) {}

plr::Expected<std::unique_ptr<ProcessRunner>> ProcessRunner::create(ProcessOptions options) {
  if ((options.command.empty() == !options.kinds) || options.workers < 1 || options.workers > 256)
    return plr::make_error(PLR_ERR_INVALID,
                           "workers: a program or kinds to fork for, and 1..256 of them");
  if (!options.kinds && ::access(options.command[0].c_str(), X_OK) != 0)
    return plr::make_error(PLR_ERR_INVALID, fmt::format("worker program '{}': {}",
                                                        options.command[0], std::strerror(errno)));
  // A worker that dies while we write to it must not take us with it.
  ::signal(SIGPIPE, SIG_IGN);
  std::unique_ptr<ProcessRunner> runner(new ProcessRunner(std::move(options)));
  for (unsigned i = 0; i < runner->options_.workers; ++i) {
    runner->workers_.push_back(std::make_unique<Worker>());
    if (!runner->options_.kinds)
      if (auto s = runner->start(*runner->workers_.back()); !s) return s.error();
  }
  return runner;
}

ProcessRunner::~ProcessRunner() {
  // Closing its stdin ends a worker; bury() waits for it.
  for (auto& w : workers_) bury(*w);
}

std::vector<pid_t> ProcessRunner::pids() const {
  std::vector<pid_t> out;
  for (const auto& w : workers_) out.push_back(w->pid);
  return out;
}

plr::Status ProcessRunner::start(Worker& w) {
  int to[2], from[2];
  if (::pipe2(to, O_CLOEXEC) != 0) return plr::make_error(PLR_ERR_INTERNAL, "pipe failed");
  if (::pipe2(from, O_CLOEXEC) != 0) {
    ::close(to[0]);
    ::close(to[1]);
    return plr::make_error(PLR_ERR_INTERNAL, "pipe failed");
  }
  pid_t pid = -1;
  int rc = 0;
  if (options_.kinds) {
    const pid_t parent = ::getpid();
    std::fflush(nullptr);
    pid = ::fork();
    if (pid == 0) {
      // A worker outlives no killed run; Ctrl-C reaches the whole process
      // group, and the parent decides.
      if (::prctl(PR_SET_PDEATHSIG, SIGKILL) != 0 || ::getppid() != parent) std::_Exit(1);
      ::signal(SIGINT, SIG_IGN);
      ::signal(SIGTERM, SIG_DFL);
      ::dup2(to[0], STDIN_FILENO);
      ::dup2(from[1], STDOUT_FILENO);
      // The other workers' pipes: their ends must close when the parent's do.
      for (const auto& other : workers_)
        for (const int fd : {other->to, other->from})
          if (fd >= 0) ::close(fd);
      for (const int fd : {to[0], to[1], from[0], from[1]}) ::close(fd);
      std::_Exit(serve_jobs(*options_.kinds, options_.log_dir));
    }
    if (pid < 0) rc = errno;
  } else {
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_adddup2(&fa, to[0], STDIN_FILENO);
    posix_spawn_file_actions_adddup2(&fa, from[1], STDOUT_FILENO);
    std::vector<char*> argv;
    for (const std::string& a : options_.command) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    rc = ::posix_spawn(&pid, argv[0], &fa, nullptr, argv.data(), environ);
    posix_spawn_file_actions_destroy(&fa);
  }
  ::close(to[0]);
  ::close(from[1]);
  if (rc != 0 || pid < 0) {
    ::close(to[1]);
    ::close(from[0]);
    w.broken = true;
    return plr::make_error(PLR_ERR_INTERNAL, fmt::format("starting worker '{}': {}",
                                                         options_.kinds ? std::string("(forked)")
                                                                        : options_.command[0],
                                                         std::strerror(rc)));
  }
  w.pid = pid;
  w.to = to[1];
  w.from = from[0];
  w.reader = FrameReader(kMaxBytes + 4096, fmt::format("worker {}", pid));
  w.job = -1;
  return {};
}

void ProcessRunner::bury(Worker& w, int* status) {
  if (w.to >= 0) ::close(w.to);
  if (w.from >= 0) ::close(w.from);
  w.to = w.from = -1;
  int s = 0;
  if (w.pid > 0)
    while (::waitpid(w.pid, &s, 0) < 0 && errno == EINTR) {
    }
  if (status) *status = s;
  w.pid = -1;
  w.job = -1;
}

void ProcessRunner::run(const std::vector<Job>& jobs, const std::vector<std::size_t>& todo,
                        const Done& done, const std::function<bool()>& stop) {
  std::deque<std::size_t> queue(todo.begin(), todo.end());
  std::map<std::size_t, std::uint32_t> attempts;
  std::size_t left = todo.size();

  auto fail = [&](std::size_t i, std::string why, double wall_s) {
    Result r;
    r.key = jobs[i].key;
    r.error = std::move(why);
    if (!options_.log_dir.empty())
      r.error += fmt::format(" (log: {})", (options_.log_dir / (jobs[i].key + ".log")).string());
    r.wall_s = wall_s;
    r.attempts = attempts[i];
    --left;
    done(i, std::move(r));
  };
  // Ends `w` (killed unless `exited`), starts it again and hands its job out
  // anew, unless it has had max_attempts.
  auto lost = [&](Worker& w, std::string why, bool exited = false) {
    const long job = w.job;
    const double s = std::chrono::duration<double>(Clock::now() - w.start).count();
    if (w.pid > 0 && !exited) ::kill(w.pid, SIGKILL);
    int status = 0;
    bury(w, &status);
    if (exited) why = status_text(status);
    ++restarts_;
    if (!options_.kinds) (void)start(w);  // a program that cannot start stays down
    if (job < 0) return;
    const auto i = static_cast<std::size_t>(job);
    if (attempts[i] >= options_.max_attempts) {
      fail(i, fmt::format("{} (attempt {})", why, attempts[i]), s);
    } else {
      ++retries_;
      queue.push_front(i);
    }
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
      if (w.job >= 0 || queue.empty()) continue;
      if (w.pid <= 0 && (w.broken || !start(w))) continue;
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
        std::all_of(workers_.begin(), workers_.end(), [](const auto& w) { return w->broken; })) {
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
        lost(w, std::strerror(errno), n == 0);
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
      if (options_.process_per_job) bury(w);
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
