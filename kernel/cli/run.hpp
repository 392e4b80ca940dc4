// One run of a pipeline (`plr run`, `record`, `replay`), in steps its caller
// drives: prepare, start, poll until something ends it, finish. `plr run`
// drives them from its signal loop (run_pipeline); tests drive them in
// process.
#pragma once

#include "commands.hpp"
#include "run_report.hpp"

#include <plr/expected.hpp>

#include <filesystem>
#include <memory>
#include <optional>
#include <string>

namespace plr::kernel {

class Run {
 public:
  explicit Run(RunOptions options);
  ~Run();
  Run(const Run&) = delete;
  Run& operator=(const Run&) = delete;

  // Reads the config and makes what the run needs, starting no node: the
  // /dev/shm check and the hosts' supervisor (main host, runs across
  // hosts), the kernel, recorder, replayer and control socket.
  Status prepare();
  // Starts the other hosts, then this host's nodes; a host then tells its
  // supervisor it is ready.
  Status start();
  // How the run ended, once something ended it: a node's `pipeline/done`,
  // a stop request, the replay done, a host lost for good, `--duration`.
  std::optional<RunEnd> poll();
  // SIGHUP: reads the config again and swaps every node whose plug-in changed.
  void reload();
  // What the control socket's `stop` asks.
  void request_stop();
  // Stops the nodes, then the hosts; finishes the recording; removes the
  // run's shared memory; writes report.json (main host). Returns the exit
  // code: the end's, 0 for a host the supervisor stopped.
  int finish(const RunEnd& end);
  // After prepare() or start() failed: says why, stops what started and
  // writes report.json (`not_started`) once the config is known. Returns
  // the error's exit code.
  int not_started(const Error& error);

  bool main_host() const { return main_host_; }
  const std::string& run_id() const { return run_id_; }
  // report.json; empty before prepare() read the config.
  std::filesystem::path report_file() const;

 private:
  struct Parts;
  Status prepare_main_host();
  Status listen();
  double wall_s() const;

  RunOptions options_;
  bool main_host_;
  std::string run_id_;
  std::unique_ptr<Parts> parts_;
};

// The end a stop signal gives a run: interrupted (SIGINT) or terminated,
// with 128 + signal as exit code, as a shell reports a process it ended.
RunEnd ended_by_signal(int signal);

}  // namespace plr::kernel
