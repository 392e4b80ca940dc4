// Hot swap of the planner while plan requests flow: the pipeline's "plan"
// service moves between ARA* and RRTConnect and every request is answered
// once, solved, by one of them; and swap after swap leaves no memory behind.
#include "kernel.hpp"
#include "kernel_fixture.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <fstream>
#include <map>
#include <string>
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

// The plate to the top of a wall of 0.4 m boxes 3 m ahead (M2 arm+base),
// improved until a budget of expansions: the ARA* search grows its state
// table to megabytes, as the soak's picks did.
constexpr std::uint64_t kFarExpansions = 4000;
plr_msg* far_request() {
  flatbuffers::FlatBufferBuilder fbb;
  const msg::Vec3 trailer(2.5, 2.7, 16.0);
  std::vector<msg::BoxState> wall;
  for (int r = 0; r < 5; ++r)
    for (int c = 0; c < 5; ++c)
      wall.emplace_back(
          static_cast<std::uint32_t>(wall.size() + 1), msg::Vec3(0.4, 0.4, 0.4),
          msg::Pose(msg::Vec3(5.2, 0.405 * (c - 2), 0.2 + 0.405 * r), msg::Quat(0, 0, 0, 1)), 0.0);
  const std::vector<double> start{2.0, 0, -1.0, 2.0, 0.0, 0.5, 0, 0};
  const msg::Pose goal(msg::Vec3(4.85, 0.4, 1.8), msg::Quat(0, 0, 0, 1));
  const auto world = msg::CreateWorldStateDirect(fbb, 0, &trailer, nullptr, 0.0, &wall);
  fbb.Finish(msg::CreatePlanRequestDirect(fbb, msg::PlanMode::M2, &start, nullptr, &goal, true,
                                          120.0, nullptr, world, nullptr, kFarExpansions));
  return make_msg<msg::PlanRequest>(fbb);
}

// This process's own memory (RssAnon of /proc/self/status), KiB.
long rss_anon_kib() {
  std::ifstream status("/proc/self/status");
  for (std::string key; status >> key;) {
    long kib = 0;
    if (key == "RssAnon:" && status >> kib) return kib;
    status.ignore(1 << 10, '\n');
  }
  return -1;
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

// Swap after swap, a planner swapped out gives back what its searches took.
// ARA* grew its state table by doubling; glibc then raised its mmap and
// trim thresholds to the largest block freed, and the arena of each
// instance's thread kept its freed search (malloc_trim() does not shrink an
// arena's top): in the soak, the main process's memory climbed with each
// swap back to ARA* (here: 33.6, then 55 MiB under RRTConnect).
TEST(PlannerSwap, APlannerSwappedOutGivesItsMemoryBack) {
  Kernel kernel(config_from_yaml("nodes:\n  planner: {plugin: planner_ompl}\n"));
  ASSERT_TRUE(kernel.start());
  TestEndpoint client;
  kernel.bus().set_live(&client, true);
  constexpr std::size_t kRounds = 3;
  Ledger ledger(2 * kRounds + 1);
  std::vector<CallCtx> ctx(2 * kRounds + 1);
  std::size_t calls = 0;
  const auto plan = [&] {
    const std::size_t i = calls++;
    ctx[i] = {&ledger, i};
    const auto s =
        kernel.bus().call(&client, "plan", MessageTraits<msg::PlanRequest>::type_id(),
                          far_request(), std::chrono::seconds(300), &on_reply, &ctx[i], nullptr);
    ASSERT_TRUE(s) << s.error().message;
    std::unique_lock lock(ledger.m);
    ASSERT_TRUE(
        ledger.cv.wait_for(lock, std::chrono::seconds(300), [&] { return ledger.answers[i] > 0; }));
  };
  plan();
  long first = 0;  // under RRTConnect after the first round
  for (std::size_t round = 0; round < kRounds; ++round) {
    ASSERT_TRUE(kernel.swap("planner", "planner_arastar"));
    plan();
    const long searched = rss_anon_kib();
    ASSERT_TRUE(kernel.swap("planner", "planner_ompl"));
    plan();
    const long after = rss_anon_kib();
    if (round == 0) first = after;
    // Less than one search's table (megabytes) more than after the first round.
    EXPECT_LT(after - first, 2 * 1024)
        << "round " << round << ": RssAnon " << first << " KiB under RRTConnect after round 0, "
        << searched << " KiB after ARA*'s search, " << after << " KiB under RRTConnect again";
  }
  std::lock_guard lock(ledger.m);
  EXPECT_TRUE(ledger.errors.empty()) << ledger.errors.front();
  EXPECT_EQ(ledger.solved_by.size(), 2u);
  kernel.bus().remove_endpoint(&client);
  client.executor().drain();
}

}  // namespace
}  // namespace plr::kernel
