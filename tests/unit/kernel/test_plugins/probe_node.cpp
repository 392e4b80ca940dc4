// Test plug-in: serves `double` asynchronously (answers from its own thread
// after a short random delay, so requests are in flight during a swap; one
// chosen value slowly) and
// reports each life-cycle hook on the `lifecycle` topic; with `crash_after_ms`
// its process dies (SIGKILL) that long after activation, for restart tests.
#include <plr/messages.hpp>
#include <plr/node.hpp>
#include <plr/plugin.hpp>

#include <condition_variable>
#include <csignal>
#include <deque>
#include <mutex>
#include <random>
#include <thread>

namespace {

class ProbeNode : public plr::Node {
 public:
  using Node::Node;

 protected:
  plr::Status on_configure() override {
    params().allow_only(
        {"factor", "max_delay_us", "fail_activate", "slow_value", "slow_ms", "crash_after_ms"});
    crash_after_ms_ = params().get<int>("crash_after_ms", -1);
    factor_ = params().get<std::int64_t>("factor", 2);
    max_delay_us_ = params().get<int>("max_delay_us", 200);
    fail_activate_ = params().get<bool>("fail_activate", false);
    slow_value_ = params().get<std::int64_t>("slow_value", -1);
    slow_ms_ = params().get<int>("slow_ms", 0);
    auto events = ctx().advertise<plr::msg::Statistics>("lifecycle");
    if (!events) return events.error();
    events_ = *events;
    if (auto s = ctx().provide_async<plr::msg::DoubleRequest, plr::msg::DoubleReply>(
            "double",
            [this](const plr::Message<plr::msg::DoubleRequest>& req,
                   plr::Responder<plr::msg::DoubleReply> r) {
              std::lock_guard lock(m_);
              work_.emplace_back(req->value(), std::move(r));
              cv_.notify_one();
            });
        !s)
      return s;
    report("configure");
    return {};
  }

  plr::Status on_activate() override {
    if (fail_activate_) return plr::make_error(PLR_ERR_INVALID, "activation refused by test");
    stop_ = false;
    worker_ = std::thread([this] { serve(); });
    if (crash_after_ms_ >= 0)
      std::thread([ms = crash_after_ms_] {
        std::this_thread::sleep_for(std::chrono::milliseconds(ms));
        std::raise(SIGKILL);
      }).detach();
    report("activate");
    return {};
  }

  plr::Status on_deactivate() override {
    {
      std::lock_guard lock(m_);
      stop_ = true;
    }
    cv_.notify_one();
    worker_.join();
    report("deactivate");
    return {};
  }

  plr::Status on_cleanup() override {
    report("cleanup");
    return {};
  }

 private:
  void report(const char* hook) {
    flatbuffers::FlatBufferBuilder fbb;
    fbb.Finish(plr::msg::CreateStatisticsDirect(fbb, (ctx().name() + ":" + hook).c_str()));
    (void)events_.publish(fbb);
  }

  // Answers everything queued, including what arrives while stopping, so no
  // accepted request is dropped.
  void serve() {
    std::mt19937 rng(std::random_device{}());
    std::uniform_int_distribution<int> delay(0, max_delay_us_);
    std::unique_lock lock(m_);
    for (;;) {
      cv_.wait(lock, [&] { return stop_ || !work_.empty(); });
      if (work_.empty() && stop_) return;
      auto [value, responder] = std::move(work_.front());
      work_.pop_front();
      lock.unlock();
      std::this_thread::sleep_for(std::chrono::microseconds(delay(rng)));
      if (value == slow_value_) std::this_thread::sleep_for(std::chrono::milliseconds(slow_ms_));
      flatbuffers::FlatBufferBuilder fbb;
      fbb.Finish(plr::msg::CreateDoubleReply(fbb, value * factor_));
      (void)responder.reply(fbb);
      lock.lock();
    }
  }

  std::int64_t factor_ = 2;
  int max_delay_us_ = 200;
  bool fail_activate_ = false;
  std::int64_t slow_value_ = -1;  // answered after slow_ms, so a test can act while it is in flight
  int slow_ms_ = 0;
  int crash_after_ms_ = -1;
  plr::Publisher<plr::msg::Statistics> events_;
  std::mutex m_;
  std::condition_variable cv_;
  std::deque<std::pair<std::int64_t, plr::Responder<plr::msg::DoubleReply>>> work_;
  bool stop_ = false;
  std::thread worker_;
};

}  // namespace

PLR_PLUGIN(ProbeNode, "test_probe", "0.1.0", PLR_KIND_OTHER,
           "Test: async `double` service and life-cycle reports")
