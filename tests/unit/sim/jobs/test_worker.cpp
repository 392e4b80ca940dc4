// A worker program for process_runner_test: serves test kinds over stdin and
// stdout (plr/jobs/worker.hpp).
#include <signal.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>

#include "plr/jobs/worker.hpp"

using plr::jobs::Bytes;

int main() {
  plr::jobs::Kinds kinds;
  kinds.add("test.pid", [](const Bytes&) -> plr::Expected<Bytes> {
    return plr::jobs::to_bytes(std::to_string(::getpid()));
  });
  kinds.add("test.hang", [](const Bytes&) -> plr::Expected<Bytes> {
    while (true) ::pause();
  });
  // Dies on its first attempt only: the attempt leaves the file its input names.
  kinds.add("test.crash_once", [](const Bytes& input) -> plr::Expected<Bytes> {
    const std::filesystem::path mark = plr::jobs::to_text(input);
    if (!std::filesystem::exists(mark)) {
      std::ofstream(mark) << "1";
      ::kill(::getpid(), SIGKILL);
    }
    return plr::jobs::to_bytes("second time");
  });
  kinds.add("test.print", [](const Bytes& input) -> plr::Expected<Bytes> {
    // Printed text must not reach the frames on stdout.
    std::printf("noise on stdout\n");
    return input;
  });
  return plr::jobs::serve_jobs(kinds);
}
