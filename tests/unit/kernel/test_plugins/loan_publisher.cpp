// Test plug-in: publishes `count` blobs on `blobs`, each built straight into a
// loaned buffer (plr/loan.hpp): a NextStrategyRequest whose `world` is `bytes`
// bytes of value (i & 0xff). `loan_bytes` asks for a smaller loan to force the
// builder to grow out of it. Starts on activation, from its own thread.
#include <plr/messages.hpp>
#include <plr/node.hpp>
#include <plr/plugin.hpp>

#include <atomic>
#include <cstring>
#include <thread>

namespace {

class LoanPublisher : public plr::Node {
 public:
  using Node::Node;

 protected:
  plr::Status on_configure() override {
    params().allow_only({"count", "bytes", "loan_bytes", "period_us"});
    count_ = params().get<int>("count", 100);
    bytes_ = params().get<int>("bytes", 4096);
    loan_bytes_ = params().get<int>("loan_bytes", bytes_ + 256);
    period_us_ = params().get<int>("period_us", 0);
    auto p = ctx().advertise<plr::msg::NextStrategyRequest>("blobs");
    if (!p) return p.error();
    pub_ = *p;
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
    for (int i = 0; i < count_ && !stop_; ++i) {
      auto loan = pub_.loan(static_cast<std::size_t>(loan_bytes_));
      if (!loan) {
        log().error("loan failed: {}", loan.error().message);
        return;
      }
      auto& fbb = loan->builder();
      std::uint8_t* world = nullptr;
      const auto vec = fbb.CreateUninitializedVector(static_cast<std::size_t>(bytes_), &world);
      std::memset(world, i & 0xff, static_cast<std::size_t>(bytes_));
      plr::msg::NextStrategyRequestBuilder b(fbb);
      b.add_world(vec);
      fbb.Finish(b.Finish());
      if (auto s = loan->publish(); !s) {
        log().error("publish failed: {}", s.error().message);
        return;
      }
      if (period_us_ > 0) std::this_thread::sleep_for(std::chrono::microseconds(period_us_));
    }
  }

  int count_ = 100, bytes_ = 4096, loan_bytes_ = 0, period_us_ = 0;
  plr::Publisher<plr::msg::NextStrategyRequest> pub_;
  std::atomic<bool> stop_{false};
  std::thread worker_;
};

}  // namespace

PLR_PLUGIN(LoanPublisher, "test_loan_publisher", "0.1.0", PLR_KIND_OTHER,
           "Test: publishes blobs built in loaned buffers")
