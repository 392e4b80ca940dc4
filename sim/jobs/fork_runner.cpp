#include "plr/jobs/fork_runner.hpp"

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <plr/frame.hpp>

#include <fmt/format.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <deque>
#include <list>
#include <map>
#include <optional>

#include "plr/jobs/messages.hpp"

namespace plr::jobs {

namespace {

using Clock = std::chrono::steady_clock;

struct Child {
  pid_t pid = -1;
  int fd = -1;  // our end of its result pipe
  std::size_t index = 0;
  Clock::time_point start;
  FrameReader reader{kMaxBytes + 4096, "job process"};
  std::optional<Result> reply;
  bool ended = false;  // its pipe closed, or it was killed
  std::string why;     // why it ended without a reply, when we know better than its status
};

// In the child: runs the job and writes its result to `fd`; never returns.
[[noreturn]] void serve(const Kinds& kinds, const Job& job, const ForkOptions& options, int fd,
                        pid_t parent) {
  // A job outlives no killed run: it would only hold a core.
  if (::prctl(PR_SET_PDEATHSIG, SIGKILL) != 0 || ::getppid() != parent) std::_Exit(1);
  // Ctrl-C reaches the whole process group: the parent decides, and ends us.
  ::signal(SIGINT, SIG_IGN);
  ::signal(SIGTERM, SIG_DFL);
  if (options.quiet) {
    const int null = ::open("/dev/null", O_WRONLY | O_CLOEXEC);
    if (null >= 0) ::dup2(null, STDOUT_FILENO);
  }
  if (!options.log_dir.empty()) {
    const auto log = options.log_dir / (job.key + ".log");
    const int fd_log = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
    if (fd_log >= 0) ::dup2(fd_log, STDERR_FILENO);
  }
  const Bytes reply = encode_reply(0, kinds.run(job));
  const Bytes framed = plr::frame(reply.data(), reply.size());
  std::fflush(nullptr);
  std::_Exit(plr::write_all(fd, framed) ? 0 : 1);
}

std::string status_text(int status) {
  if (WIFSIGNALED(status)) return fmt::format("job process died (signal {})", WTERMSIG(status));
  return fmt::format("job process exited with status {} without a result",
                     WIFEXITED(status) ? WEXITSTATUS(status) : -1);
}

}  // namespace

void ForkRunner::run(const std::vector<Job>& jobs, const std::vector<std::size_t>& todo,
                     const Done& done, const std::function<bool()>& stop) {
  std::deque<std::size_t> queue(todo.begin(), todo.end());
  std::map<std::size_t, std::uint32_t> attempts;
  std::list<Child> running;
  const pid_t parent = ::getpid();
  const unsigned workers = std::max(1u, options_.workers);

  auto failed = [&](std::size_t i, std::string why, double wall_s) {
    Result r;
    r.key = jobs[i].key;
    r.error = std::move(why);
    if (!options_.log_dir.empty())
      r.error += fmt::format(" (log: {})", (options_.log_dir / (jobs[i].key + ".log")).string());
    r.wall_s = wall_s;
    r.attempts = attempts[i];
    return r;
  };
  auto reap = [](Child& c) {
    if (c.fd >= 0) ::close(c.fd);
    c.fd = -1;
    int status = 0;
    while (::waitpid(c.pid, &status, 0) < 0 && errno == EINTR) {
    }
    return status;
  };
  auto start = [&](std::size_t i) {
    ++attempts[i];
    int fds[2];
    if (::pipe2(fds, O_CLOEXEC) != 0) {
      done(i, failed(i, fmt::format("pipe: {}", std::strerror(errno)), 0.0));
      return;
    }
    std::fflush(nullptr);
    const pid_t pid = ::fork();
    if (pid == 0) serve(kinds_, jobs[i], options_, fds[1], parent);
    ::close(fds[1]);
    if (pid < 0) {
      ::close(fds[0]);
      done(i, failed(i, fmt::format("fork: {}", std::strerror(errno)), 0.0));
      return;
    }
    Child& c = running.emplace_back();
    c.pid = pid;
    c.fd = fds[0];
    c.index = i;
    c.start = Clock::now();
  };
  auto finish = [&](Child& c) {
    const int status = reap(c);
    const double wall_s = std::chrono::duration<double>(Clock::now() - c.start).count();
    if (c.reply) {
      c.reply->attempts = attempts[c.index];
      c.reply->wall_s = wall_s;
      done(c.index, std::move(*c.reply));
      return;
    }
    if (attempts[c.index] < options_.max_attempts) {
      ++retries_;
      queue.push_front(c.index);
      return;
    }
    done(c.index, failed(c.index, c.why.empty() ? status_text(status) : c.why, wall_s));
  };

  while (!queue.empty() || !running.empty()) {
    if (stop && stop()) {
      for (Child& c : running) ::kill(c.pid, SIGKILL);
      for (Child& c : running) reap(c);
      return;
    }
    while (!queue.empty() && running.size() < workers) {
      const std::size_t i = queue.front();
      queue.pop_front();
      start(i);
    }
    std::vector<pollfd> fds;
    std::vector<Child*> polled;
    for (Child& c : running) {
      fds.push_back({c.fd, POLLIN, 0});
      polled.push_back(&c);
    }
    // Woken by a child's bytes or its end; every 50 ms for timeouts and stop.
    if (::poll(fds.data(), fds.size(), 50) < 0 && errno != EINTR) break;
    for (std::size_t k = 0; k < fds.size(); ++k) {
      if (fds[k].revents == 0) continue;
      Child& c = *polled[k];
      std::uint8_t chunk[1 << 16];
      const ssize_t n = ::read(c.fd, chunk, sizeof chunk);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        c.ended = true;
        continue;
      }
      c.reader.feed(chunk, static_cast<std::size_t>(n));
      auto payload = c.reader.next();
      if (!payload || !*payload) {
        if (!payload) {
          c.why = payload.error().message;
          ::kill(c.pid, SIGKILL);
          c.ended = true;
        }
        continue;
      }
      auto message = decode_message((*payload)->data(), (*payload)->size(), "job process");
      if (!message || message->type != Message::Type::kReply) {
        c.why = message ? "job process sent a request" : message.error().message;
        ::kill(c.pid, SIGKILL);
        c.ended = true;
        continue;
      }
      c.reply = std::move(message->result);
    }
    const auto now = Clock::now();
    for (Child& c : running) {
      const double s = std::chrono::duration<double>(now - c.start).count();
      if (!c.ended && s > options_.timeout_s) {
        ::kill(c.pid, SIGKILL);
        c.why = fmt::format("killed after {:.0f} s wall", s);
        c.ended = true;
      }
    }
    for (auto it = running.begin(); it != running.end();) {
      if (it->ended) {
        finish(*it);
        it = running.erase(it);
      } else {
        ++it;
      }
    }
  }
}

}  // namespace plr::jobs
