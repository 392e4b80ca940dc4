#include "run_report.hpp"

#include <plr/atomic_file.hpp>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

namespace plr::kernel {

const char* to_string(Ending e) {
  switch (e) {
    case Ending::Finished:
      return "finished";
    case Ending::Failed:
      return "failed";
    case Ending::Interrupted:
      return "interrupted";
    case Ending::Terminated:
      return "terminated";
    case Ending::Duration:
      return "duration";
    case Ending::Stopped:
      return "stopped";
    case Ending::HostLost:
      return "host_lost";
    case Ending::NotStarted:
      return "not_started";
  }
  return "?";
}

RunReport::RunReport(std::filesystem::path dir, std::string pipeline, std::string run_id)
    : dir_(std::move(dir)),
      file_(dir_ / "report.json"),
      pipeline_(std::move(pipeline)),
      run_id_(std::move(run_id)) {}

Status RunReport::add_figures(const std::string& node, std::string_view figures) {
  auto parsed = nlohmann::json::parse(figures, nullptr, false);
  if (!parsed.is_object())
    return make_error(PLR_ERR_INVALID,
                      fmt::format("pipeline/report of node '{}': not a JSON object", node));
  std::lock_guard lock(m_);
  figures_[node] = std::move(parsed);
  write();
  return {};
}

void RunReport::end(const RunEnd& end, double wall_s, int host_restarts,
                    const std::vector<TopicStatsSnapshot>& topics) {
  std::lock_guard lock(m_);
  run_ = {{"pipeline", pipeline_},          {"run_id", run_id_},
          {"ended", to_string(end.ending)}, {"reason", end.reason},
          {"exit_code", end.exit_code},     {"wall_s", wall_s},
          {"host_restarts", host_restarts}};
  for (const auto& t : topics) run_["topic_messages"][t.name] = t.messages;
  if (write()) spdlog::info("report: {} (run {})", file_.string(), to_string(end.ending));
}

nlohmann::json RunReport::json() const {
  std::lock_guard lock(m_);
  return merged();
}

nlohmann::json RunReport::merged() const {
  nlohmann::json report = nlohmann::json::object();
  for (const auto& [node, figures] : figures_) report.update(figures);
  if (!run_.is_null())
    report["run"] = run_;
  else
    report.erase("run");
  return report;
}

bool RunReport::write() const {
  std::error_code ec;
  std::filesystem::create_directories(dir_, ec);
  auto s = write_file_atomically(file_.string(), merged().dump(2) + "\n");
  if (!s) spdlog::error("report: {}", s.error().message);
  return s.has_value();
}

}  // namespace plr::kernel
