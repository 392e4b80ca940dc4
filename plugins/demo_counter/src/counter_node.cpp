// Demo: counts up, publishes each value on `count`, asks the `double` service
// for twice the value, and publishes the answer on `doubled`. Stops after
// `limit` values (0 = forever) and announces on `pipeline/done` that it is finished.
#include <plr/interface.hpp>
#include <plr/messages.hpp>
#include <plr/node.hpp>
#include <plr/plugin.hpp>

#include <atomic>
#include <thread>

namespace {

class CounterNode : public plr::Node {
 public:
  using Node::Node;

 protected:
  plr::Status on_configure() override {
    params().allow_only({"period_ms", "limit"});
    period_ = std::chrono::milliseconds(params().get<int>("period_ms", 100));
    limit_ = params().get<std::int64_t>("limit", 0);
    if (period_.count() < 0)
      return plr::make_error(PLR_ERR_INVALID, "param 'period_ms': must be >= 0");
    auto count = ctx().advertise<plr::msg::Count>("count");
    if (!count) return count.error();
    auto doubled = ctx().advertise<plr::msg::Count>("doubled");
    if (!doubled) return doubled.error();
    auto done = ctx().advertise<plr::msg::PipelineDone>("pipeline/done");
    if (!done) return done.error();
    count_ = *count;
    doubled_ = *doubled;
    done_ = *done;
    return {};
  }

  plr::Status on_activate() override {
    stop_ = false;
    worker_ = std::thread([this] { run(); });
    return {};
  }

  plr::Status on_deactivate() override {
    stop_ = true;
    worker_.join();
    return {};
  }

 private:
  void run() {
    for (std::int64_t i = next_; !stop_ && (limit_ == 0 || i < limit_); ++i) {
      flatbuffers::FlatBufferBuilder fbb;
      fbb.Finish(plr::msg::CreateCount(fbb, i));
      (void)count_.publish(fbb);

      flatbuffers::FlatBufferBuilder req;
      req.Finish(plr::msg::CreateDoubleRequest(req, i));
      auto reply = ctx()
                       .call<plr::msg::DoubleRequest, plr::msg::DoubleReply>(
                           "double", req, std::chrono::seconds(2))
                       .get();
      if (reply) {
        flatbuffers::FlatBufferBuilder out;
        out.Finish(plr::msg::CreateCount(out, reply.value()->value()));
        (void)doubled_.publish(out);
        log().info("{} doubled is {}", i, reply.value()->value());
      } else {
        log().warn("double({}) failed: {}", i, reply.error().message);
      }
      next_ = i + 1;
      std::this_thread::sleep_for(period_);
    }
    if (limit_ != 0 && next_ >= limit_) {
      flatbuffers::FlatBufferBuilder fbb;
      fbb.Finish(plr::msg::CreatePipelineDoneDirect(fbb, true,
                                                    fmt::format("counted to {}", limit_).c_str()));
      (void)done_.publish(fbb);
    }
  }

  std::chrono::milliseconds period_{100};
  std::int64_t limit_ = 0;
  std::int64_t next_ = 0;
  plr::Publisher<plr::msg::Count> count_;
  plr::Publisher<plr::msg::Count> doubled_;
  plr::Publisher<plr::msg::PipelineDone> done_;
  std::atomic<bool> stop_{false};
  std::thread worker_;
};

}  // namespace

PLR_PLUGIN(CounterNode, "demo_counter", "1.0.0", PLR_KIND_OTHER,
           "Demo: publishes a count and asks a service to double it")
PLR_INTERFACE(plr::topic<plr::msg::Count>("count"), plr::topic<plr::msg::Count>("doubled"),
              plr::topic<plr::msg::PipelineDone>("pipeline/done"))
