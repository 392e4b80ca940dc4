// report.json of a run, and its only writer: the latest figures each node
// published on `pipeline/report` (plr.msg.NodeReport), their keys at the top
// level, and, once the run ended, the kernel's own `run` (how it ended, its
// wall time, host restarts, messages per topic). Rewritten atomically at every
// change, so a run killed at any moment leaves the figures so far.
#pragma once

#include "bus.hpp"

#include <plr/expected.hpp>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <map>
#include <mutex>
#include <string>
#include <string_view>
#include <vector>

namespace plr::kernel {

// How a run ended, as report.json's `run.ended` says it.
enum class Ending {
  Finished,
  Failed,
  Interrupted,
  Terminated,
  Duration,
  Stopped,
  HostLost,
  NotStarted
};

const char* to_string(Ending e);

struct RunEnd {
  Ending ending = Ending::Finished;
  std::string reason;
  int exit_code = 0;
};

class RunReport {
 public:
  // The report is `dir`/report.json; a file there from an earlier run is
  // replaced at the first write, never merged.
  RunReport(std::filesystem::path dir, std::string pipeline, std::string run_id);

  const std::filesystem::path& file() const { return file_; }

  // `node`'s figures, replacing those it published before: a JSON object.
  // Where nodes give the same key, the node whose name sorts last wins;
  // `run` is the kernel's. Refused (the report unchanged): anything else.
  Status add_figures(const std::string& node, std::string_view figures);

  // How the run ended, with the messages each topic carried on the main
  // host's bus (what a recording of it should hold).
  void end(const RunEnd& end, double wall_s, int host_restarts,
           const std::vector<TopicStatsSnapshot>& topics = {});

  nlohmann::json json() const;

 private:
  nlohmann::json merged() const;  // under m_
  bool write() const;             // under m_; false (logged) when it failed

  std::filesystem::path dir_, file_;
  std::string pipeline_, run_id_;
  mutable std::mutex m_;
  std::map<std::string, nlohmann::json> figures_;  // by node
  nlohmann::json run_;                             // null until the run ended
};

}  // namespace plr::kernel
