#include "node_thread.hpp"

#include <pthread.h>

#include <future>

namespace plr::kernel {

NodeThread::NodeThread(std::string name, std::size_t max_queued)
    : name_(std::move(name)), max_queued_(max_queued), thread_([this] { loop(); }) {
  pthread_setname_np(thread_.native_handle(), name_.substr(0, 15).c_str());
}

NodeThread::~NodeThread() {
  {
    std::lock_guard lock(m_);
    stop_ = true;
  }
  cv_.notify_all();
  thread_.join();
  // A poster may still be about to notify for a task that has already run
  // (or a dispatch() to finish its bookkeeping).
  while (posting_.load(std::memory_order_acquire) != 0) std::this_thread::yield();
}

bool NodeThread::post(std::function<void()> task) {
  // Notified after unlocking, so the woken thread does not block on m_ at
  // once (a second wake-up per task). Once the task has run, a swap may
  // destroy this thread: the destructor waits for `posting_` first.
  posting_.fetch_add(1, std::memory_order_relaxed);
  bool queued = false;
  {
    std::lock_guard lock(m_);
    queued = !stop_ && queue_.size() < max_queued_;
    if (queued) queue_.push_back(std::move(task));
  }
  if (queued) cv_.notify_one();
  posting_.fetch_sub(1, std::memory_order_release);
  return queued;
}

bool NodeThread::dispatch(std::function<void()> task) {
  posting_.fetch_add(1, std::memory_order_relaxed);
  std::unique_lock lock(m_);
  if (stop_ || busy_ || !queue_.empty()) {
    lock.unlock();
    const bool queued = post(std::move(task));
    posting_.fetch_sub(1, std::memory_order_release);
    return queued;
  }
  busy_ = true;
  inline_on_.store(std::this_thread::get_id(), std::memory_order_relaxed);
  lock.unlock();
  task();
  lock.lock();
  inline_on_.store(std::thread::id{}, std::memory_order_relaxed);
  busy_ = false;
  // What was queued meanwhile (or a stop) waited for this task: hand over.
  const bool wake = stop_ || !queue_.empty();
  if (!wake) idle_cv_.notify_all();
  lock.unlock();
  if (wake) cv_.notify_one();
  posting_.fetch_sub(1, std::memory_order_release);
  return true;
}

void NodeThread::run_sync(const std::function<void()>& task) {
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

void NodeThread::drain() {
  if (on_this_thread()) return;
  std::unique_lock lock(m_);
  idle_cv_.wait(lock, [&] { return queue_.empty() && !busy_; });
}

std::size_t NodeThread::queued() const {
  std::lock_guard lock(m_);
  return queue_.size();
}

void NodeThread::loop() {
  std::unique_lock lock(m_);
  for (;;) {
    // busy_ here means a dispatch() is running a task inline: wait for it.
    cv_.wait(lock, [&] { return !busy_ && (stop_ || !queue_.empty()); });
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
