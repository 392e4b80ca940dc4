// The thread of a bus endpoint (a node instance, or a transport bridge): its
// callbacks and life-cycle hooks run there, one at a time, in order, so a
// plug-in needs no locks of its own for them.
#pragma once

#include <atomic>
#include <condition_variable>
#include <deque>
#include <functional>
#include <mutex>
#include <string>
#include <thread>

namespace plr::kernel {

class NodeThread {
 public:
  explicit NodeThread(std::string name, std::size_t max_queued = 4096);
  ~NodeThread();  // runs what is queued, then stops
  NodeThread(const NodeThread&) = delete;
  NodeThread& operator=(const NodeThread&) = delete;

  // False when the queue is full or the thread is stopping.
  bool post(std::function<void()> task);
  // Runs `task` at once on the calling thread when this one is idle
  // (nothing queued, nothing running), else queues it like post(). Tasks
  // still run one at a time. For short tasks whose hand-off to this thread
  // would cost more than the task (quick services).
  bool dispatch(std::function<void()> task);
  // Runs `task` on this thread and waits for it (inline when called from there).
  void run_sync(const std::function<void()>& task);
  // Waits until everything queued so far has run.
  void drain();
  // True on this thread, and on a thread running a task of it inline.
  bool on_this_thread() const {
    const auto self = std::this_thread::get_id();
    return self == thread_.get_id() || self == inline_on_.load(std::memory_order_relaxed);
  }
  std::size_t queued() const;

 private:
  void loop();

  std::string name_;
  std::size_t max_queued_;
  mutable std::mutex m_;
  std::condition_variable cv_;
  std::condition_variable idle_cv_;
  std::deque<std::function<void()>> queue_;
  bool busy_ = false;
  bool stop_ = false;
  std::atomic<int> posting_{0};               // post() and dispatch() calls not yet returned
  std::atomic<std::thread::id> inline_on_{};  // the thread in dispatch()'s task, if any
  std::thread thread_;
};

}  // namespace plr::kernel
