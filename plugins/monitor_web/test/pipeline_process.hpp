// Runs `plr run <config> --set ...` in a child process for a test ("{dir}"
// in an argument: its temporary folder), reads
// the monitor's port from its log, and stops it (SIGINT) when done.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <thread>
#include <vector>

namespace plr::monitor_web::testing {

class PipelineProcess {
 public:
  PipelineProcess(const std::string& plr, const std::vector<std::string>& args) {
    std::string pattern =
        (std::filesystem::temp_directory_path() / "plr_monitor_web_XXXXXX").string();
    dir_ = ::mkdtemp(pattern.data());
    log_ = dir_ / "log.txt";
    pid_ = ::fork();
    if (pid_ == 0) {
      const int fd = ::open(log_.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
      ::dup2(fd, 1);
      ::dup2(fd, 2);
      std::vector<char*> argv{const_cast<char*>(plr.c_str()), const_cast<char*>("run")};
      std::vector<std::string> expanded;
      for (auto a : args) {
        if (const auto at = a.find("{dir}"); at != std::string::npos)
          a.replace(at, 5, dir_.string());
        expanded.push_back(std::move(a));
      }
      for (auto& a : expanded) argv.push_back(a.data());
      argv.push_back(nullptr);
      ::execv(plr.c_str(), argv.data());
      ::_exit(127);
    }
  }
  ~PipelineProcess() {
    stop();
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }

  const std::filesystem::path& dir() const { return dir_; }

  std::string log() const {
    std::ifstream in(log_);
    return std::string((std::istreambuf_iterator<char>(in)), {});
  }

  // The port the monitor logged ("dashboard on http://127.0.0.1:PORT/"), 0
  // when it did not within `wait`.
  std::uint16_t monitor_port(std::chrono::seconds wait = std::chrono::seconds(60)) const {
    static const std::regex line(R"(dashboard on http://[^:]+:(\d+)/)");
    const auto until = std::chrono::steady_clock::now() + wait;
    while (std::chrono::steady_clock::now() < until) {
      std::smatch m;
      const auto text = log();
      if (std::regex_search(text, m, line)) return static_cast<std::uint16_t>(std::stoi(m[1]));
      if (exited()) return 0;
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
    }
    return 0;
  }

  bool exited() const {
    if (pid_ <= 0) return true;
    if (::waitpid(pid_, &status_, WNOHANG) != pid_) return false;
    pid_ = -1;
    return true;
  }

  // SIGINT, as Ctrl-C; the exit status, or -1.
  int stop() {
    if (pid_ > 0) {
      ::kill(pid_, SIGINT);
      ::waitpid(pid_, &status_, 0);
      pid_ = -1;
    }
    return WIFEXITED(status_) ? WEXITSTATUS(status_) : -1;
  }

 private:
  std::filesystem::path dir_, log_;
  mutable pid_t pid_ = -1;
  mutable int status_ = 0;
};

}  // namespace plr::monitor_web::testing
