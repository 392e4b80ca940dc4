#include "executor.hpp"

#include <pthread.h>

#include <future>

namespace plr::kernel {

Executor::Executor(std::string name, std::size_t max_queued)
    : name_(std::move(name)), max_queued_(max_queued), thread_([this] { loop(); }) {
  pthread_setname_np(thread_.native_handle(), name_.substr(0, 15).c_str());
}

Executor::~Executor() {
  {
    std::lock_guard lock(m_);
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
}

bool Executor::post(std::function<void()> task) {
  // Notified under the lock: once the task has run, a swap may destroy this
  // executor, and the poster must not touch cv_ after that.
  std::lock_guard lock(m_);
  if (stop_ || queue_.size() >= max_queued_) return false;
  queue_.push_back(std::move(task));
  cv_.notify_one();
  return true;
}

void Executor::run_sync(const std::function<void()>& task) {
  if (on_this_thread()) {
    task();
    return;
  }
  std::promise<void> done;
  auto fut = done.get_future();
  {
    // Life-cycle steps must run even when the callback queue is full.
    std::lock_guard lock(m_);
    queue_.push_back([&] {
      task();
      done.set_value();
    });
    cv_.notify_one();
  }
  fut.wait();
}

void Executor::drain() {
  if (on_this_thread()) return;
  std::unique_lock lock(m_);
  idle_cv_.wait(lock, [&] { return queue_.empty() && !busy_; });
}

std::size_t Executor::queued() const {
  std::lock_guard lock(m_);
  return queue_.size();
}

void Executor::loop() {
  std::unique_lock lock(m_);
  for (;;) {
    cv_.wait(lock, [&] { return stop_ || !queue_.empty(); });
    if (queue_.empty()) {
      if (stop_) return;
      continue;
    }
    auto task = std::move(queue_.front());
    queue_.pop_front();
    busy_ = true;
    lock.unlock();
    task();
    lock.lock();
    busy_ = false;
    if (queue_.empty()) idle_cv_.notify_all();
  }
}

}  // namespace plr::kernel
