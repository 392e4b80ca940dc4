#include "plr/jobs/kinds.hpp"

#include <fmt/format.h>

#include <chrono>
#include <exception>

namespace plr::jobs {

void Kinds::add(const std::string& kind, Handler handler) {
  handlers_[kind] = std::move(handler);
}

Result Kinds::run(const Job& job) const {
  const auto t0 = std::chrono::steady_clock::now();
  Result r;
  r.key = job.key;
  r.attempts = 1;
  const auto it = handlers_.find(job.kind);
  if (it == handlers_.end()) {
    r.error = fmt::format("no handler for jobs of kind '{}'", job.kind);
  } else {
    try {
      auto out = it->second(job.input);
      if (!out) {
        r.error = out.error().message;
      } else if (out->size() > kMaxBytes) {
        r.error = fmt::format("output of {} bytes, over the limit of {}", out->size(), kMaxBytes);
      } else {
        r.ok = true;
        r.output = std::move(*out);
      }
    } catch (const std::exception& e) {
      r.error = fmt::format("{}: {}", job.kind, e.what());
    }
  }
  r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace plr::jobs
