// A simulation worker reached as a service: serves `sim/simulate`
// (WorkerFrame with a SimJob → WorkerFrame with its SimResult), the same
// frames a local worker process reads on its pipe. Run on another machine
// with the service exported over DDS, it is one of the strategy
// generator's remote workers (docs/generator.md).
//
// Jobs run in arrival order on `threads` threads of the node's own, each
// with its own simulation and planner (the simulation is single-threaded:
// one thread per core the machine gives). The job names its observation
// parameters, so a thread keeps nothing between jobs but its loaded robot
// and planner.
#include <plr/msg/generator_generated.h>
#include <plr/interface.hpp>
#include <plr/messages.hpp>
#include <plr/node.hpp>
#include <plr/plugin.hpp>

#include <condition_variable>
#include <deque>
#include <mutex>
#include <thread>

#include "plr/actions/job_runner.hpp"

namespace {

using namespace plr;
using Frame = msg::WorkerFrame;

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

  // The simulation and planner of one thread, made for one set of
  // observation parameters.
  struct Runner {
    std::unique_ptr<actions::JobRunner> runner;
    std::string json;
  };

  void serve() {
    Runner runner;
    for (;;) {
      std::unique_lock lock(m_);
      cv_.wait(lock, [&] { return stop_ || !jobs_.empty(); });
      if (stop_) return;
      Job job = std::move(jobs_.front());
      jobs_.pop_front();
      lock.unlock();
      run(job, runner);
    }
  }

  void run(Job& job, Runner& r) {
    const auto v = job.frame.view();
    auto frame = actions::decode_frame(v.data, v.size, service_);
    if (!frame) {
      (void)job.reply.fail(PLR_ERR_INVALID, frame.error().message);
      return;
    }
    if (frame->kind != actions::Frame::Kind::kJob) {
      (void)job.reply.fail(PLR_ERR_INVALID, service_ + ": the request is not a job");
      return;
    }
    const std::string json = frame->observation_json.empty() ? "{}" : frame->observation_json;
    if (!r.runner || json != r.json) {
      auto runner = actions::JobRunner::create(json);
      if (!runner) {
        (void)job.reply.fail(PLR_ERR_INVALID, service_ + ": job: " + runner.error().message);
        return;
      }
      r.runner = std::move(*runner);
      r.json = json;
    }
    const auto result = r.runner->run(frame->request);
    if (!result) log().warn("{}: job {}: {}", service_, frame->id, result.error().message);
    flatbuffers::FlatBufferBuilder fbb(result && result->state ? result->state->size() + 256 : 256);
    actions::build_result(fbb, frame->id, result);
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
PLR_INTERFACE(plr::service<plr::msg::WorkerFrame, plr::msg::WorkerFrame>("sim/simulate"))
