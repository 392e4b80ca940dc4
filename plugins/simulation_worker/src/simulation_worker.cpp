// A simulation worker reached as a service: serves `sim/simulate`, a
// JobFrame holding a JobRequest of kind sim.action → a JobFrame holding its
// JobReply: the job engine's messages (plr/jobs/messages.hpp), the same a
// local worker process reads and writes on its pipe, run by the same
// handler (plr/actions/simulation_job.hpp). Run on another machine with the
// service exported over DDS, it is one of the strategy generator's remote
// workers (docs/generator.md).
//
// Jobs run in arrival order on `threads` threads of the node's own, each
// with its own simulation and planner (the simulation is single-threaded:
// one thread per core the machine gives). The job names its observation
// parameters, so a thread keeps nothing between jobs but its loaded robot
// and planner.
#include <plr/msg/jobs_generated.h>
#include <plr/interface.hpp>
#include <plr/messages.hpp>
#include <plr/node.hpp>
#include <plr/plugin.hpp>

#include <condition_variable>
#include <deque>
#include <mutex>
#include <thread>

#include "plr/actions/simulation_job.hpp"
#include "plr/jobs/messages.hpp"

namespace {

using namespace plr;
using Frame = msg::JobFrame;

class SimulationWorker : public Node {
 public:
  using Node::Node;

 protected:
  Status on_configure() override {
    params().allow_only({"service", "threads", "queue"});
    service_ = params().get<std::string>("service", "sim/simulate");
    threads_ = params().get<int>("threads", 1);
    queue_limit_ = params().get<int>("queue", 16);
    if (threads_ < 1 || threads_ > 256)
      return make_error(PLR_ERR_INVALID,
                        fmt::format("param 'threads': {} is not in 1..256", threads_));
    if (queue_limit_ < 1 || queue_limit_ > 1024)
      return make_error(PLR_ERR_INVALID,
                        fmt::format("param 'queue': {} is not in 1..1024", queue_limit_));
    return ctx().provide_async<Frame, Frame>(
        service_, [this](const Message<Frame>& job, Responder<Frame> reply) {
          std::lock_guard lock(m_);
          if (stop_ || jobs_.size() >= static_cast<std::size_t>(queue_limit_)) {
            (void)reply.fail(PLR_ERR_UNAVAILABLE, stop_ ? service_ + ": stopping"
                                                        : fmt::format("{}: {} jobs waiting already",
                                                                      service_, jobs_.size()));
            return;
          }
          jobs_.push_back({job, std::move(reply)});
          cv_.notify_one();
        });
  }

  Status on_activate() override {
    stop_ = false;
    for (int i = 0; i < threads_; ++i) threads_running_.emplace_back([this] { serve(); });
    return {};
  }

  Status on_deactivate() override {
    {
      std::lock_guard lock(m_);
      stop_ = true;
    }
    cv_.notify_all();
    for (auto& t : threads_running_) t.join();
    threads_running_.clear();
    std::lock_guard lock(m_);
    for (auto& j : jobs_) (void)j.reply.fail(PLR_ERR_UNAVAILABLE, service_ + ": stopping");
    jobs_.clear();
    return {};
  }

 private:
  struct Job {
    Message<Frame> frame;
    Responder<Frame> reply;
  };

  void serve() {
    // This thread's handler of sim.action, with its own simulation and planner.
    jobs::Kinds kinds;
    actions::add_sim_action(kinds);
    for (;;) {
      std::unique_lock lock(m_);
      cv_.wait(lock, [&] { return stop_ || !jobs_.empty(); });
      if (stop_) return;
      Job job = std::move(jobs_.front());
      jobs_.pop_front();
      lock.unlock();
      run(job, kinds);
    }
  }

  void run(Job& job, const jobs::Kinds& kinds) {
    const auto v = job.frame.view();
    auto message = jobs::decode_message(v.data, v.size, service_);
    if (!message) {
      (void)job.reply.fail(PLR_ERR_INVALID, message.error().message);
      return;
    }
    if (message->type != jobs::Message::Type::kRequest ||
        message->job.kind != actions::kSimActionKind) {
      (void)job.reply.fail(PLR_ERR_INVALID, service_ + ": the request is not a sim.action job");
      return;
    }
    const jobs::Result result = kinds.run(message->job);
    if (!result.ok) log().warn("{}: job {}: {}", service_, result.key, result.error);
    const jobs::Bytes reply = jobs::encode_reply(message->id, result);
    flatbuffers::FlatBufferBuilder fbb(reply.size() + 64);
    fbb.PushFlatBuffer(reply.data(), reply.size());
    (void)job.reply.reply(fbb);
  }

  std::string service_;
  int threads_ = 1, queue_limit_ = 16;
  std::mutex m_;
  std::condition_variable cv_;
  std::deque<Job> jobs_;
  bool stop_ = false;
  std::vector<std::thread> threads_running_;
};

}  // namespace

PLR_PLUGIN(SimulationWorker, "simulation_worker", "1.0.0", PLR_KIND_SIMULATOR,
           "Simulates the strategy generator's jobs (an abstract action on a trailer state) as "
           "the service sim/simulate")
PLR_INTERFACE(plr::service<plr::msg::JobFrame, plr::msg::JobFrame>("sim/simulate"))
