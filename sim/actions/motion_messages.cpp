#include "plr/actions/motion_messages.hpp"

#include <plr/messages.hpp>
#include <plr/sim/unaligned.hpp>

namespace plr::actions {

namespace {

constexpr std::size_t kMaxCups = 1024;  // a plate's cups, bounded for a message from outside

plr::msg::Suction to_msg(Suction s) {
  switch (s) {
    case Suction::kOn:
      return plr::msg::Suction::On;
    case Suction::kOff:
      return plr::msg::Suction::Off;
    case Suction::kKeep:
      break;
  }
  return plr::msg::Suction::Keep;
}

plr::Expected<Suction> from_msg(plr::msg::Suction s, const char* field) {
  switch (s) {
    case plr::msg::Suction::Keep:
      return Suction::kKeep;
    case plr::msg::Suction::On:
      return Suction::kOn;
    case plr::msg::Suction::Off:
      return Suction::kOff;
  }
  return plr::make_error(PLR_ERR_INVALID, std::string("ExecuteRequest.") + field +
                                              ": unknown value " +
                                              std::to_string(static_cast<int>(s)));
}

}  // namespace

void encode_execute_request(const Motion& motion, flatbuffers::FlatBufferBuilder& out) {
  std::vector<flatbuffers::Offset<plr::msg::TrajectoryPoint>> points;
  for (const auto& p : motion.points) {
    const std::vector<double> pos(p.position.data(), p.position.data() + sim::kNumJoints);
    const std::vector<double> vel(p.velocity.data(), p.velocity.data() + sim::kNumJoints);
    points.push_back(plr::msg::CreateTrajectoryPointDirect(out, p.time_s, &pos, &vel));
  }
  const auto trajectory = plr::msg::CreateTrajectoryDirect(out, &points);
  const auto cups = motion.cups_open.empty()
                        ? flatbuffers::Offset<flatbuffers::Vector<std::uint8_t>>()
                        : out.CreateVector(motion.cups_open);
  out.Finish(plr::msg::CreateExecuteRequest(out, trajectory, to_msg(motion.before),
                                            to_msg(motion.after), motion.conveyor, motion.settle_s,
                                            cups));
}

plr::Expected<Motion> decode_execute_request(const plr::msg::ExecuteRequest& r) {
  auto bad = [](const std::string& why) {
    return plr::make_error(PLR_ERR_INVALID, "ExecuteRequest." + why);
  };
  Motion m;
  if (const auto* traj = r.trajectory(); traj && traj->points()) {
    for (const auto* p : *traj->points()) {
      if (!p->positions() || p->positions()->size() != sim::kNumJoints)
        return bad("trajectory: every point needs 8 positions");
      planning::TimedPoint tp;
      tp.time_s = p->time_s();
      for (int i = 0; i < sim::kNumJoints; ++i) tp.position[i] = sim::element(*p->positions(), i);
      if (p->velocities() && p->velocities()->size() == sim::kNumJoints)
        for (int i = 0; i < sim::kNumJoints; ++i)
          tp.velocity[i] = sim::element(*p->velocities(), i);
      if (!std::isfinite(tp.time_s) || !tp.position.allFinite())
        return bad("trajectory: non-finite value");
      if (!m.points.empty() && tp.time_s < m.points.back().time_s)
        return bad("trajectory: times must not decrease");
      m.points.push_back(tp);
    }
  }
  auto before = from_msg(r.suction_before(), "suction_before");
  if (!before) return before.error();
  auto after = from_msg(r.suction_after(), "suction_after");
  if (!after) return after.error();
  m.before = *before;
  m.after = *after;
  m.conveyor = r.conveyor();
  m.settle_s = r.settle_s();
  if (!(m.settle_s >= 0.0 && m.settle_s <= 60.0)) return bad("settle_s: must be in [0, 60]");
  if (const auto* cups = r.cups_open()) {
    if (cups->size() > kMaxCups) return bad("cups_open: more than 1024 cups");
    m.cups_open.assign(cups->begin(), cups->end());
  }
  return m;
}

void encode_execute_outcome(const Executed& e, std::uint32_t boxes_remaining,
                            flatbuffers::FlatBufferBuilder& out) {
  std::vector<plr::msg::SuctionEvent> suction;
  for (const auto& s : e.suction)
    suction.emplace_back(s.box_id, static_cast<plr::msg::SuctionEventKind>(s.kind), s.time, s.load,
                         s.capacity);
  out.Finish(plr::msg::CreateExecuteOutcomeDirect(
      out, true, "", e.sim_time_s, &e.moved, &e.unloaded, &e.held, e.robot_trailer_contacts,
      boxes_remaining, &e.unloaded_after_s, &suction, e.stalled, e.stall_force, e.stall_after_s,
      e.peak_push_force));
}

plr::Expected<Executed> decode_execute_outcome(const plr::msg::ExecuteOutcome& o) {
  if (!o.ok()) return plr::make_error(PLR_ERR_STATE, o.message() ? o.message()->str() : "refused");
  Executed e;
  auto copy = [](const auto* v, auto& to) {
    if (v == nullptr) return;
    const auto all = sim::elements(*v);
    to.assign(all.begin(), all.end());
  };
  copy(o.unloaded_box_ids(), e.unloaded);
  copy(o.unloaded_after_s(), e.unloaded_after_s);
  copy(o.held_box_ids(), e.held);
  copy(o.moved_box_ids(), e.moved);
  if (e.unloaded_after_s.size() != e.unloaded.size())
    return plr::make_error(PLR_ERR_INVALID,
                           "ExecuteOutcome.unloaded_after_s: one time per unloaded box");
  e.robot_trailer_contacts = o.robot_trailer_contacts();
  e.sim_time_s = o.sim_time_s();
  e.stalled = o.stalled();
  e.stall_force = o.stall_force_n();
  e.stall_after_s = o.stall_after_s();
  e.peak_push_force = o.peak_push_force_n();
  if (const auto* events = o.suction_events()) {
    for (flatbuffers::uoffset_t i = 0; i < events->size(); ++i) {
      const plr::msg::SuctionEvent event = sim::element(*events, i);
      const auto* s = &event;
      const int kind = static_cast<int>(s->kind());
      if (kind < 0 || kind > static_cast<int>(sim::SuctionEvent::Kind::kReleased))
        return plr::make_error(PLR_ERR_INVALID, "ExecuteOutcome.suction_events: unknown kind");
      e.suction.push_back({s->box_id(), s->time_s(), static_cast<sim::SuctionEvent::Kind>(kind),
                           s->load_n(), s->capacity_n()});
    }
  }
  return e;
}

}  // namespace plr::actions
