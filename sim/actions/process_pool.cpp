#include "plr/actions/process_pool.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>

#include <chrono>
#include <cstdio>
#include <map>

#include "plr/atomic_file.hpp"

namespace plr::actions {

namespace {

using Clock = std::chrono::steady_clock;

std::string save(const std::filesystem::path& file, const nlohmann::json& j) {
  if (auto ok = plr::write_file_atomically(file.string(), j.dump(1) + "\n"); !ok)
    return ok.error().message;
  return {};
}

}  // namespace

std::vector<PoolRun> missing_runs(const std::vector<PoolRun>& runs) {
  std::vector<PoolRun> out;
  for (const PoolRun& r : runs)
    if (!std::filesystem::exists(r.result)) out.push_back(r);
  return out;
}

std::string run_in_processes(
    const std::vector<PoolRun>& runs, const PoolOptions& options,
    const std::function<nlohmann::json(std::size_t)>& work,
    const std::function<nlohmann::json(std::size_t, const std::string&, double)>& failed,
    const std::function<void(std::size_t)>& done) {
  struct Running {
    std::size_t run;
    Clock::time_point start;
    bool killed = false;
  };
  std::map<pid_t, Running> running;
  std::string error;
  auto stop_all = [&] {
    for (auto& [pid, r] : running) ::kill(pid, SIGKILL);
    for (auto& [pid, r] : running) ::waitpid(pid, nullptr, 0);
    running.clear();
  };
  const pid_t parent = ::getpid();
  std::size_t next = 0;
  const unsigned workers = std::max(1u, options.workers);
  while (next < runs.size() || !running.empty()) {
    while (next < runs.size() && running.size() < workers) {
      const std::size_t i = next++;
      std::fflush(nullptr);
      const pid_t pid = ::fork();
      if (pid < 0) {
        stop_all();
        return "fork failed";
      }
      if (pid == 0) {
        // A run outlives no killed job: it would only hold a core.
        if (::prctl(PR_SET_PDEATHSIG, SIGKILL) != 0 || ::getppid() != parent) std::_Exit(1);
        if (options.quiet) {
          // The run's own log lines (the planner's, the simulation's) stay
          // out of the job's display.
          const int null = ::open("/dev/null", O_WRONLY);
          if (null >= 0) ::dup2(null, STDOUT_FILENO);
        }
        const std::string why = save(runs[i].result, work(i));
        if (!why.empty()) std::fprintf(stderr, "%s\n", why.c_str());
        std::_Exit(why.empty() ? 0 : 1);
      }
      running.emplace(pid, Running{i, Clock::now()});
    }
    int status = 0;
    const pid_t ended = ::waitpid(-1, &status, WNOHANG);
    if (ended > 0) {
      const auto it = running.find(ended);
      if (it == running.end()) continue;
      const Running r = it->second;
      running.erase(it);
      const double s = std::chrono::duration<double>(Clock::now() - r.start).count();
      if (!(WIFEXITED(status) && WEXITSTATUS(status) == 0) &&
          !std::filesystem::exists(runs[r.run].result)) {
        const std::string why = WIFSIGNALED(status)
                                    ? fmt::format("run process died (signal {})", WTERMSIG(status))
                                    : std::string("run process failed");
        error = save(runs[r.run].result, failed(r.run, why, s));
        if (!error.empty()) {
          stop_all();
          return error;
        }
      }
      if (done) done(r.run);
      continue;
    }
    for (auto& [pid, r] : running) {
      const double s = std::chrono::duration<double>(Clock::now() - r.start).count();
      if (!r.killed && s > options.timeout_s) {
        ::kill(pid, SIGKILL);
        ::waitpid(pid, nullptr, 0);
        error = save(runs[r.run].result,
                     failed(r.run, fmt::format("killed after {:.0f} s wall", s), s));
        if (!error.empty()) {
          running.erase(pid);
          stop_all();
          return error;
        }
        r.killed = true;
      }
    }
    // A killed child was reaped above; its entry goes with the next pass.
    for (auto it = running.begin(); it != running.end();) {
      if (it->second.killed) {
        if (done) done(it->second.run);
        it = running.erase(it);
      } else {
        ++it;
      }
    }
    ::usleep(50'000);
  }
  return {};
}

}  // namespace plr::actions
