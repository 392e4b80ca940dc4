#include "plr/jobs/worker.hpp"

#include <fcntl.h>

#include <unistd.h>

#include <plr/frame.hpp>

#include <cstdio>

#include "plr/jobs/messages.hpp"

namespace plr::jobs {

int serve_jobs(const Kinds& kinds, const std::filesystem::path& log_dir) {
  // Frames go to a private copy of stdout; whatever a library prints goes to stderr.
  const int out = ::dup(STDOUT_FILENO);
  ::dup2(STDERR_FILENO, STDOUT_FILENO);
  FrameReader reader(kMaxBytes + 4096, "stdin");
  while (true) {
    auto payload = reader.read(STDIN_FILENO);
    if (!payload) {
      std::fprintf(stderr, "%s\n", payload.error().message.c_str());
      return 2;
    }
    if (!*payload) return 0;
    auto message = decode_message((*payload)->data(), (*payload)->size(), "stdin");
    if (!message || message->type != Message::Type::kRequest) {
      std::fprintf(
          stderr, "%s\n",
          message ? "stdin: a reply where a request belongs" : message.error().message.c_str());
      return 2;
    }
    if (!log_dir.empty()) {
      const auto log = log_dir / (message->job.key + ".log");
      const int fd = ::open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
      if (fd >= 0) {
        ::dup2(fd, STDERR_FILENO);
        ::dup2(fd, STDOUT_FILENO);
        ::close(fd);
      }
    }
    const Bytes reply = encode_reply(message->id, kinds.run(message->job));
    std::fflush(nullptr);
    if (!plr::write_all(out, plr::frame(reply.data(), reply.size()))) return 0;
  }
}

}  // namespace plr::jobs
