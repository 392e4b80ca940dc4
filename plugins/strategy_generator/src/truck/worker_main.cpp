// plr_sim_worker: a simulation worker of the strategy generator. Reads
// frames (sim_work.hpp) on stdin — a setup, then jobs — and answers each job
// with its result on stdout. Log lines go to stderr; stdout carries nothing
// but frames.
#include <unistd.h>

#include <CLI/CLI.hpp>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <vector>

#include <plr/frame.hpp>

#include "plr/actions/job_runner.hpp"

namespace {

bool read_all(int fd, std::uint8_t* data, std::size_t size) {
  std::size_t done = 0;
  while (done < size) {
    const ssize_t n = ::read(fd, data + done, size - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    done += static_cast<std::size_t>(n);
  }
  return true;
}

// The next frame; nullopt at the end of input.
std::optional<plr::Expected<plr::actions::Frame>> next_frame() {
  std::uint8_t head[4];
  if (!read_all(0, head, 4)) return std::nullopt;
  const std::size_t size = std::size_t{head[0]} | std::size_t{head[1]} << 8 |
                           std::size_t{head[2]} << 16 | std::size_t{head[3]} << 24;
  if (size > plr::actions::kMaxFrameBytes) {
    return plr::make_error(PLR_ERR_INVALID, "stdin: frame of " + std::to_string(size) + " bytes");
  }
  std::vector<std::uint8_t> body(size);
  if (!read_all(0, body.data(), size)) return std::nullopt;
  return plr::actions::decode_frame(body.data(), size, "stdin");
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "A simulation worker of the strategy generator: reads frames on stdin (a setup, then "
      "jobs) and answers each job with its result on stdout; started by the generator"};
  CLI11_PARSE(app, argc, argv);
  // Frames go to a private copy of stdout; whatever a library prints goes to stderr.
  const int out = ::dup(1);
  ::dup2(2, 1);
  auto setup = next_frame();
  if (!setup || !*setup || (*setup)->kind != plr::actions::Frame::Kind::kSetup) {
    std::fprintf(stderr, "plr_sim_worker: expected a setup frame first\n");
    return 2;
  }
  auto runner = plr::actions::JobRunner::create((*setup)->observation_json);
  if (!runner) {
    std::fprintf(stderr, "plr_sim_worker: %s\n", runner.error().message.c_str());
    return 1;
  }
  while (auto frame = next_frame()) {
    if (!*frame || (*frame)->kind != plr::actions::Frame::Kind::kJob) {
      std::fprintf(stderr, "plr_sim_worker: %s\n",
                   *frame ? "expected a job" : frame->error().message.c_str());
      return 2;
    }
    const auto result = (*runner)->run((*frame)->request);
    if (!plr::write_all(out, plr::actions::frame_result((*frame)->id, result))) return 0;
  }
  return 0;
}
