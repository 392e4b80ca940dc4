#include "bus_backend.hpp"

#include <plr/actions/motion_messages.hpp>
#include <plr/planning/plan_messages.hpp>
#include <plr/sim/observation.hpp>
#include <plr/sim/unaligned.hpp>

#include <fmt/format.h>

namespace plr::executor {

BusBackend::BusBackend(Context& ctx, BusOptions options,
                       std::function<bool(std::chrono::nanoseconds)> pause)
    : ctx_(ctx), options_(options), pause_(std::move(pause)) {}

plr::Status BusBackend::check_clock(double sim_time_s, const char* service) {
  // A simulator host restarted between two calls resumes from its
  // checkpoint, with its clock set back: the same as a call it failed.
  if (sim_time_s + 1e-9 < sim_clock_s_) {
    const double seen = sim_clock_s_;
    sim_clock_s_ = -1.0;
    return plr::make_error(
        PLR_ERR_UNAVAILABLE,
        fmt::format("{}: the simulator's clock went back from {:.2f} s to {:.2f} s", service, seen,
                    sim_time_s));
  }
  sim_clock_s_ = sim_time_s;
  return {};
}

plr::Expected<actions::Perceived> BusBackend::observe() {
  flatbuffers::FlatBufferBuilder fbb;
  fbb.Finish(msg::CreateObserveRequest(fbb, false));
  auto r = call_once<msg::ObserveRequest, msg::WorldState>("sim/observe", fbb, 30.0);
  if (!r) {
    if (r.error().code == PLR_ERR_UNAVAILABLE || r.error().code == PLR_ERR_TIMEOUT ||
        r.error().code == PLR_ERR_CANCELLED)
      return plr::make_error(r.error().code, "sim/observe: " + r.error().message);
    return plr::make_error(PLR_ERR_INTERNAL, "sim/observe: " + r.error().message);
  }
  const msg::WorldState& m = *r.value();
  if (auto ok = check_clock(static_cast<double>(m.stamp_ns()) * 1e-9, "sim/observe"); !ok)
    return ok.error();
  actions::Perceived p;
  p.world = sim::world_from_message(m);
  if (m.robot() && m.robot()->positions() && m.robot()->positions()->size() == sim::kNumJoints)
    for (int j = 0; j < sim::kNumJoints; ++j) p.q[j] = sim::element(*m.robot()->positions(), j);
  if (m.held_box_ids()) p.held.assign(m.held_box_ids()->begin(), m.held_box_ids()->end());
  p.unloaded = m.boxes_unloaded();
  p.sim_time_s = static_cast<double>(m.stamp_ns()) * 1e-9;
  last_world_ = std::move(r.value());
  return p;
}

plr::Expected<planning::DecodedPlanResponse> BusBackend::plan(const planning::PlanQuery& query,
                                                              const sim::World& world) {
  flatbuffers::FlatBufferBuilder fbb;
  planning::encode_plan_request(query, world, fbb);
  auto r =
      call_retry<msg::PlanRequest, msg::PlanResponse>("plan", fbb, options_.plan_timeout_s + 10.0);
  if (!r) return plr::make_error(r.error().code, "plan: " + r.error().message);
  return planning::decode_plan_response(*r.value());
}

plr::Expected<actions::Executed> BusBackend::execute(const actions::Motion& motion) {
  flatbuffers::FlatBufferBuilder fbb;
  actions::encode_execute_request(motion, fbb);
  auto r = call_once<msg::ExecuteRequest, msg::ExecuteOutcome>("sim/execute", fbb,
                                                               options_.execute_timeout_s);
  if (!r) {
    // Refused (a trajectory from elsewhere, a world not reset): the action
    // goes on without this motion. Gone: the action ends.
    const bool gone = r.error().code == PLR_ERR_UNAVAILABLE || r.error().code == PLR_ERR_CANCELLED;
    return plr::make_error(gone ? r.error().code : PLR_ERR_STATE,
                           "sim/execute: " + r.error().message);
  }
  if (auto ok = check_clock(r.value()->sim_time_s(), "sim/execute"); !ok) return ok.error();
  return actions::decode_execute_outcome(*r.value());
}

plr::Expected<actions::Perceived> BusBackend::wait_for_simulator() {
  using namespace std::chrono_literals;
  const auto t0 = std::chrono::steady_clock::now();
  for (;;) {
    auto w = observe();
    if (w || !lost(w.error())) return w;
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count() >
        options_.service_wait_s)
      return plr::make_error(PLR_ERR_INTERNAL,
                             fmt::format("simulator unavailable for {:.0f} s: {}",
                                         options_.service_wait_s, w.error().message));
    if (!pause_(200ms)) return plr::make_error(PLR_ERR_CANCELLED, "stopping");
  }
}

plr::Expected<BusBackend::SnapshotAnswer> BusBackend::snapshot_or_restore(const char* service) {
  flatbuffers::FlatBufferBuilder fbb;
  fbb.Finish(msg::CreateSnapshotRequestDirect(fbb, "checkpoint"));
  auto r = call_retry<msg::SnapshotRequest, msg::SnapshotReply>(service, fbb, 60.0);
  if (!r) {
    if (r.error().code == PLR_ERR_CANCELLED || r.error().code == PLR_ERR_UNAVAILABLE)
      return plr::make_error(r.error().code, std::string(service) + ": " + r.error().message);
    return SnapshotAnswer{r.error().message, 0};
  }
  if (!r.value()->ok())
    return SnapshotAnswer{r.value()->message() ? r.value()->message()->str() : "refused", 0};
  return SnapshotAnswer{"", r.value()->checkpoint_bytes()};
}

plr::Status BusBackend::checkpoint() {
  const auto a = snapshot_or_restore("sim/snapshot");
  if (!a) return a.error();
  if (!a->refused.empty()) ctx_.log().warn("sim/snapshot 'checkpoint' failed: {}", a->refused);
  return {};
}

plr::Expected<std::uint64_t> BusBackend::checkpoint_until_written(const std::string& what) {
  using namespace std::chrono_literals;
  for (bool warned = false;;) {
    const auto a = snapshot_or_restore("sim/snapshot");
    if (!a) return a.error();
    if (a->refused.empty()) return a->checkpoint_bytes;
    if (!warned)
      ctx_.log().warn("{}: sim/snapshot 'checkpoint' failed: {}; asking again until it is written",
                      what, a->refused);
    warned = true;
    if (!pause_(200ms)) return plr::make_error(PLR_ERR_CANCELLED, "stopping");
  }
}

bool BusBackend::lost(const plr::Error& error) const {
  return error.code == PLR_ERR_UNAVAILABLE || error.code == PLR_ERR_TIMEOUT;
}

plr::Status BusBackend::restore() {
  forget_clock();  // the restart set it back
  if (auto w = wait_for_simulator(); !w) return w.error();
  // Going on without it would unload a world that is not the trailer's.
  const auto a = snapshot_or_restore("sim/restore");
  if (!a) return a.error();
  if (!a->refused.empty())
    return plr::make_error(PLR_ERR_INTERNAL, "sim/restore 'checkpoint': " + a->refused);
  forget_clock();  // and so did the restore
  return check_trailer();
}

void BusBackend::expect_trailer(const sim::World& made) {
  trailer_boxes_.clear();
  for (const auto& b : made.boxes) trailer_boxes_[b.id] = b.size;
  another_world_ = false;
}

// A checkpoint of another trailer (a file from an earlier run, a disk that
// lost the last one) would be unloaded as this one.
plr::Status BusBackend::check_trailer() {
  if (trailer_boxes_.empty()) return {};
  auto w = observe();
  if (!w) return w.error();
  const std::size_t shows = w->world.boxes.size() + w->unloaded;
  bool same = shows == trailer_boxes_.size();
  for (const auto& b : w->world.boxes) {
    const auto it = trailer_boxes_.find(b.id);
    same = same && it != trailer_boxes_.end() && (it->second - b.size).cwiseAbs().maxCoeff() < 1e-6;
  }
  if (same) return {};
  another_world_ = true;
  return plr::make_error(
      PLR_ERR_STATE,
      fmt::format("the simulator came back with another trailer's world ({} boxes, {} unloaded; "
                  "the trailer has {})",
                  w->world.boxes.size(), w->unloaded, trailer_boxes_.size()));
}

}  // namespace plr::executor
