// The action model's backend over the bus: `sim/observe` and `sim/execute`
// of the simulator (or a robot driver serving the same services) and the
// `plan` service of whichever planner is loaded. A simulator whose host died
// is waited for and restored from its checkpoint (`sim/snapshot`,
// `sim/restore`): the episode engine's recovery.
#pragma once

#include <plr/actions/backend.hpp>
#include <plr/context.hpp>
#include <plr/episode/recovery.hpp>
#include <plr/messages.hpp>

#include <atomic>
#include <chrono>
#include <functional>
#include <map>
#include <optional>
#include <string>

namespace plr::executor {

struct BusOptions {
  double service_wait_s = 60.0;  // how long a provider may be unavailable (starting, swapped)
  std::chrono::milliseconds retry{50};
  double execute_timeout_s = 300.0;
  double plan_timeout_s = 5.0;  // the planner's own limit; the call waits 10 s more
};

// Errors: PLR_ERR_CANCELLED when the node is stopping; PLR_ERR_UNAVAILABLE
// or PLR_ERR_TIMEOUT when the simulator went away (lost()).
class BusBackend final : public actions::Backend, public episode::Recovery {
 public:
  // `pause` sleeps for a while and returns false when the node is stopping.
  BusBackend(Context& ctx, BusOptions options, std::function<bool(std::chrono::nanoseconds)> pause);

  plr::Expected<actions::Perceived> observe() override;
  plr::Expected<planning::DecodedPlanResponse> plan(const planning::PlanQuery& query,
                                                    const sim::World& world) override;
  plr::Expected<actions::Executed> execute(const actions::Motion& motion) override;

  // Observes once the simulator answers (at start, and after its host
  // restarted), waiting at most `service_wait_s`.
  plr::Expected<actions::Perceived> wait_for_simulator();

  // A checkpoint not taken (refused) is logged: it only costs a longer
  // repeat after a crash.
  plr::Status checkpoint() override;
  // The same, but a refused checkpoint is asked for again until it is
  // written (a disk full or read-only for a while); `what` names it in the
  // log. Returns the checkpoint folder's bytes as the simulator reports
  // them. Errors: the simulator lost, the run stopping (PLR_ERR_CANCELLED).
  plr::Expected<std::uint64_t> checkpoint_until_written(const std::string& what);
  bool lost(const plr::Error& error) const override;
  plr::Status restore() override;

  // The trailer being unloaded, as its reset made it: a restored simulator
  // whose boxes are not this trailer's (their count, ids and sizes) is
  // refused with PLR_ERR_STATE, and another_world() says so until the next
  // expect_trailer().
  void expect_trailer(const sim::World& made);
  bool another_world() const { return another_world_; }

  // The last world observed, as the simulator sent it (strategy/next takes it).
  const std::optional<Message<msg::WorldState>>& last_world() const { return last_world_; }
  // Calls `service`, retrying while its provider is unavailable (not started
  // yet, or being swapped): a swap is atomic in the kernel, and this makes a
  // call survive even a gap, so none is lost.
  template <class Req, class Rep>
  plr::Expected<Message<Rep>> call_retry(const std::string& service,
                                         const flatbuffers::FlatBufferBuilder& fbb,
                                         double timeout_s);
  // A simulator that restarted, was restored or reset sets its clock back:
  // forget the clock seen so far, so the next call does not count as a restart.
  void forget_clock() { sim_clock_s_ = -1.0; }

 private:
  template <class Req, class Rep>
  plr::Expected<Message<Rep>> call_once(const std::string& service,
                                        const flatbuffers::FlatBufferBuilder& fbb,
                                        double timeout_s);
  plr::Status check_clock(double sim_time_s, const char* service);
  struct SnapshotAnswer {
    std::string refused;  // empty when the simulator took or restored the checkpoint
    std::uint64_t checkpoint_bytes = 0;
  };
  // An error when the simulator is gone or the node stopping.
  plr::Expected<SnapshotAnswer> snapshot_or_restore(const char* service);
  plr::Status check_trailer();

  Context& ctx_;
  BusOptions options_;
  std::function<bool(std::chrono::nanoseconds)> pause_;
  std::optional<Message<msg::WorldState>> last_world_;
  double sim_clock_s_ = -1.0;  // the simulator's clock when last heard, s
  std::map<std::uint32_t, Eigen::Vector3d> trailer_boxes_;  // id -> size, as reset
  bool another_world_ = false;
};

template <class Req, class Rep>
plr::Expected<Message<Rep>> BusBackend::call_once(const std::string& service,
                                                  const flatbuffers::FlatBufferBuilder& fbb,
                                                  double timeout_s) {
  using namespace std::chrono_literals;
  auto f = ctx_.call<Req, Rep>(service, fbb,
                               std::chrono::duration_cast<std::chrono::nanoseconds>(
                                   std::chrono::duration<double>(timeout_s)));
  while (!f.wait_for(20ms)) {
    if (!pause_(0ns)) {
      f.cancel();
      (void)f.get();
      return plr::make_error(PLR_ERR_CANCELLED, service + ": stopping");
    }
  }
  return f.get();
}

template <class Req, class Rep>
plr::Expected<Message<Rep>> BusBackend::call_retry(const std::string& service,
                                                   const flatbuffers::FlatBufferBuilder& fbb,
                                                   double timeout_s) {
  const auto t0 = std::chrono::steady_clock::now();
  for (;;) {
    auto r = call_once<Req, Rep>(service, fbb, timeout_s);
    if (r || r.error().code != PLR_ERR_UNAVAILABLE ||
        std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() >
            options_.service_wait_s)
      return r;
    if (!pause_(options_.retry)) return plr::make_error(PLR_ERR_CANCELLED, service + ": stopping");
  }
}

}  // namespace plr::executor
