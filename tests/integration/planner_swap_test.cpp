// Hot swap of the planner while plan requests flow: the pipeline's "plan"
// service moves between ARA* and RRTConnect and every request is answered
// once, solved, by one of them.
#include "kernel.hpp"
#include "kernel_fixture.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <map>
#include <thread>

namespace plr::kernel {
namespace {

using testing::config_from_yaml;
using testing::make_msg;
using testing::TestEndpoint;

// Base from x = 1 to x = 2.5 in an empty 16 m trailer (M5).
plr_msg* plan_request() {
  flatbuffers::FlatBufferBuilder fbb;
  const msg::Vec3 trailer(2.5, 2.7, 16.0);
  const std::vector<double> start{1.0, 0, -1.0, 2.0, 0.0, 0.5, 0, 0};
  const std::vector<double> goal{2.5, 0, -1.0, 2.0, 0.0, 0.5, 0, 0};
  const auto world = msg::CreateWorldStateDirect(fbb, 0, &trailer);
  fbb.Finish(msg::CreatePlanRequestDirect(fbb, msg::PlanMode::M5, &start, &goal, nullptr, false,
                                          5.0, nullptr, world));
  return make_msg<msg::PlanRequest>(fbb);
}

struct Ledger : testing::CallLedger {
  using CallLedger::CallLedger;
  std::map<std::string, int> solved_by;  // planner name -> requests
};
using CallCtx = testing::CallCtx<Ledger>;

void on_reply(void* user, plr_status status, const plr_msg* reply, const char* error) {
  auto* c = static_cast<CallCtx*>(user);
  Ledger& l = *c->ledger;
  std::lock_guard lock(l.m);
  if (status != PLR_OK) return l.count(c->index, error ? error : "error without text");
  const auto* r = flatbuffers::GetRoot<msg::PlanResponse>(msg_view(reply).data);
  if (r->status() != msg::PlanStatus::Solved)
    return l.count(c->index, r->message() ? r->message()->c_str() : "not solved");
  ++l.solved_by[r->planner() ? r->planner()->str() : "?"];
  l.count(c->index, nullptr);
}

TEST(PlannerSwap, RequestsFromFourThreadsAcrossSwapsAreEachSolvedOnce) {
  Kernel kernel(config_from_yaml("nodes:\n  planner: {plugin: planner_arastar}\n"));
  ASSERT_TRUE(kernel.start());
  TestEndpoint client;
  kernel.bus().set_live(&client, true);

  // Requests go out until the swaps are done (a fast planner answers a
  // fixed number before the first swap); at most kMaxRequests.
  constexpr std::size_t kMaxRequests = 20000;
  constexpr int kSwaps = 12;
  Ledger ledger(kMaxRequests);
  std::vector<CallCtx> ctx(kMaxRequests);
  const std::uint64_t type = MessageTraits<msg::PlanRequest>::type_id();

  // Swaps every 20 ms, kSwaps times.
  std::atomic<int> swaps{0};
  std::thread swapper([&] {
    while (swaps < kSwaps) {
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
      const auto s = kernel.swap("planner", swaps % 2 == 0 ? "planner_ompl" : "planner_arastar");
      EXPECT_TRUE(s) << s.error().message;
      ++swaps;
    }
  });
  std::atomic<std::size_t> sent{0};
  std::vector<std::thread> callers;
  for (std::size_t t = 0; t < 4; ++t)
    callers.emplace_back([&, t] {
      // Closed loop: each caller waits for its answer, as the executor does,
      // so the planner's queue stays short and swaps land between requests.
      for (std::size_t i = t; i < kMaxRequests && swaps < kSwaps; i += 4) {
        ++sent;
        ctx[i] = {&ledger, i};
        const auto s = kernel.bus().call(&client, "plan", type, plan_request(),
                                         std::chrono::seconds(30), &on_reply, &ctx[i], nullptr);
        std::unique_lock lock(ledger.m);
        if (!s) ledger.count(i, ("refused: " + s.error().message).c_str());
        ledger.cv.wait_for(lock, std::chrono::seconds(30), [&] { return ledger.answers[i] > 0; });
      }
    });
  for (auto& c : callers) c.join();
  swapper.join();
  const std::size_t requests = sent;
  {
    std::unique_lock lock(ledger.m);
    const bool all = ledger.cv.wait_for(lock, std::chrono::seconds(60),
                                        [&] { return ledger.completed >= requests; });
    ASSERT_TRUE(all) << ledger.completed << " of " << requests << " answered";
  }
  EXPECT_LT(requests, kMaxRequests) << "the swaps took longer than the requests";
  std::this_thread::sleep_for(std::chrono::milliseconds(50));  // a second answer would land here
  std::lock_guard lock(ledger.m);
  // Each caller stops after its own last send: the sent ids are a prefix
  // per caller, so check every id that went out.
  for (std::size_t i = 0; i < kMaxRequests; ++i)
    if (ctx[i].ledger != nullptr) {
      EXPECT_EQ(ledger.answers[i], 1) << "request " << i;
    }
  EXPECT_TRUE(ledger.errors.empty())
      << ledger.errors.size() << " failed, first: " << ledger.errors.front();
  // The load really spanned the swaps: both planners answered.
  EXPECT_EQ(ledger.solved_by.size(), 2u);
  for (const auto& [planner, n] : ledger.solved_by) EXPECT_GT(n, 4) << planner;
  kernel.bus().remove_endpoint(&client);
  client.executor().drain();
}

}  // namespace
}  // namespace plr::kernel
