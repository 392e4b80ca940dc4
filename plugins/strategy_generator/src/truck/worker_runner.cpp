#include "truck/worker_runner.hpp"

#include <fmt/format.h>

#include <chrono>
#include <condition_variable>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>

#include "plr/jobs/messages.hpp"

namespace plr::generator {

namespace jobs = plr::jobs;

// One run()'s shared state: the queue every slot takes from, and the
// results the calling thread reports.
struct WorkerRunner::Batch {
  const std::vector<jobs::Job>& jobs;
  std::mutex m;
  std::condition_variable cv;
  std::deque<std::size_t> queue;
  std::map<std::size_t, std::uint32_t> attempts;  // remote calls refused as bad
  std::deque<std::pair<std::size_t, jobs::Result>> finished;
  std::size_t left = 0;  // jobs not finished
  std::atomic<bool> stopping{false};

  // The next job, once one is queued; nullopt when all are done or stopping.
  std::optional<std::size_t> take() {
    std::unique_lock lock(m);
    cv.wait(lock, [&] { return stopping || left == 0 || !queue.empty(); });
    if (stopping || left == 0) return std::nullopt;
    const std::size_t i = queue.front();
    queue.pop_front();
    return i;
  }
  void finish(std::size_t i, jobs::Result r) {
    std::lock_guard lock(m);
    --left;
    finished.emplace_back(i, std::move(r));
    cv.notify_all();
  }
  void give_back(std::size_t i) {
    std::lock_guard lock(m);
    queue.push_front(i);
    cv.notify_all();
  }
};

plr::Expected<std::unique_ptr<WorkerRunner>> WorkerRunner::create(WorkerOptions options) {
  if (options.local.workers > 256 || options.remote_workers > 256 ||
      options.local.workers + options.remote_workers < 1)
    return plr::make_error(PLR_ERR_INVALID,
                           fmt::format("workers: {} local and {} remote; each 0..256, at least one",
                                       options.local.workers, options.remote_workers));
  if (options.remote_workers > 0 && !options.remote_send)
    return plr::make_error(PLR_ERR_INVALID, "remote workers: no way to send them jobs");
  std::unique_ptr<WorkerRunner> runner(new WorkerRunner(std::move(options)));
  jobs::ProcessOptions one = runner->options_.local;
  one.workers = 1;
  for (unsigned i = 0; i < runner->options_.local.workers; ++i) {
    auto local = jobs::ProcessRunner::create(one);
    if (!local) return local.error();
    runner->local_.push_back(std::move(*local));
  }
  return runner;
}

WorkerRunner::~WorkerRunner() = default;

std::vector<pid_t> WorkerRunner::pids() const {
  std::vector<pid_t> out;
  for (const auto& l : local_)
    for (const pid_t p : l->pids()) out.push_back(p);
  return out;
}

std::uint64_t WorkerRunner::restarts() const {
  std::uint64_t n = 0;
  for (const auto& l : local_) n += l->restarts();
  return n;
}

void WorkerRunner::serve_local(jobs::ProcessRunner& local, Batch& batch) {
  while (const auto i = batch.take()) {
    local.run(
        batch.jobs, std::vector<std::size_t>{*i},
        [&](std::size_t j, jobs::Result r) { batch.finish(j, std::move(r)); },
        [&] { return batch.stopping.load(); });
  }
}

void WorkerRunner::serve_remote(Batch& batch) {
  using Clock = std::chrono::steady_clock;
  while (const auto i = batch.take()) {
    const std::uint64_t id = next_id_.fetch_add(1);
    auto call = options_.remote_send(jobs::encode_request(id, batch.jobs[*i]));
    while (!call->done() && !batch.stopping)
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    if (batch.stopping) return;
    auto answer = call->take();
    std::string why;
    // The service refused the job as bad, or answered garbage: counted
    // against the job. Anything else (no provider, its kernel gone, a
    // timeout): the worker's fault, not counted.
    bool counts = true;
    if (answer) {
      auto message = jobs::decode_message(answer->data(), answer->size(), "remote worker");
      if (message && message->type == jobs::Message::Type::kReply && message->id == id &&
          message->result.key == batch.jobs[*i].key) {
        remote_done_.fetch_add(1, std::memory_order_relaxed);
        batch.finish(*i, std::move(message->result));
        continue;
      }
      why = message ? "a remote worker answered another request" : message.error().message;
    } else {
      why = answer.error().message;
      counts = answer.error().code == PLR_ERR_INVALID;
    }
    remote_failures_.fetch_add(1, std::memory_order_relaxed);
    std::uint32_t attempts = 0;
    if (counts) {
      std::lock_guard lock(batch.m);
      attempts = ++batch.attempts[*i];
    }
    if (counts && attempts >= options_.local.max_attempts) {
      jobs::Result r;
      r.key = batch.jobs[*i].key;
      r.error = fmt::format("remote: {} (attempt {})", why, attempts);
      r.attempts = attempts;
      batch.finish(*i, std::move(r));
    } else {
      batch.give_back(*i);
    }
    const auto rest = Clock::now() + std::chrono::duration_cast<Clock::duration>(
                                         std::chrono::duration<double>(options_.remote_retry_s));
    std::unique_lock lock(batch.m);
    batch.cv.wait_until(lock, rest, [&] { return batch.stopping || batch.left == 0; });
  }
}

void WorkerRunner::run(const std::vector<jobs::Job>& jobs, const std::vector<std::size_t>& todo,
                       const Done& done, const std::function<bool()>& stop) {
  Batch batch{jobs, {}, {}, {todo.begin(), todo.end()}, {}, {}, todo.size(), {false}};
  std::vector<std::thread> slots;
  for (auto& l : local_) slots.emplace_back([&, local = l.get()] { serve_local(*local, batch); });
  for (unsigned r = 0; r < options_.remote_workers; ++r)
    slots.emplace_back([&] { serve_remote(batch); });
  std::unique_lock lock(batch.m);
  while (true) {
    batch.cv.wait_for(lock, std::chrono::milliseconds(50),
                      [&] { return !batch.finished.empty() || batch.left == 0; });
    while (!batch.finished.empty()) {
      auto [i, r] = std::move(batch.finished.front());
      batch.finished.pop_front();
      lock.unlock();
      done(i, std::move(r));
      lock.lock();
    }
    if (batch.left == 0) break;
    lock.unlock();
    const bool stopped = stop && stop();
    lock.lock();
    if (stopped) {
      batch.stopping = true;
      batch.cv.notify_all();
      break;
    }
  }
  lock.unlock();
  for (auto& t : slots) t.join();
}

}  // namespace plr::generator
