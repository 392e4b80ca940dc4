#include "kernel_fixture.hpp"

#include <sys/wait.h>
#include <chrono>
#include <cstdio>

namespace plr::kernel::testing {

PipelineConfig config_from_yaml(const std::string& yaml) {
  auto c = parse_pipeline_config("plugin_paths: [" PLR_TEST_PLUGIN_DIR "]\n" + yaml, "test.yaml");
  if (!c) throw std::runtime_error(c.error().message);
  return *c;
}

plr_msg* make_double_request(std::int64_t value) {
  flatbuffers::FlatBufferBuilder fbb;
  fbb.Finish(msg::CreateDoubleRequest(fbb, value));
  return make_msg<msg::DoubleRequest>(fbb);
}

void EventLog::on_message(void* user, const plr_msg* m) {
  auto* self = static_cast<EventLog*>(user);
  const auto v = msg_view(m);
  const auto* stats = flatbuffers::GetRoot<msg::Statistics>(v.data);
  std::lock_guard lock(self->m_);
  self->events_.push_back(stats->source()->str());
  self->cv_.notify_all();
}

std::vector<std::string> EventLog::wait_for(std::size_t n, int timeout_ms) {
  std::unique_lock lock(m_);
  cv_.wait_for(lock, std::chrono::milliseconds(timeout_ms), [&] { return events_.size() >= n; });
  return events_;
}

int run_command(const std::string& command, std::string* output) {
  FILE* p = ::popen((command + " 2>&1").c_str(), "r");
  if (!p) return -1;
  char buf[4096];
  std::size_t n = 0;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) output->append(buf, n);
  const int status = ::pclose(p);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

}  // namespace plr::kernel::testing
