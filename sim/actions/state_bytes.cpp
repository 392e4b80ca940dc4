#include "plr/actions/state_bytes.hpp"

#include <fmt/format.h>

#include <cmath>
#include <utility>
#include <vector>

namespace plr::actions {

namespace {

namespace msg = plr::msg;

// Far beyond any trailer's boxes; a hostile count gets an error instead.
constexpr std::size_t kMaxEntries = 100000;
constexpr std::size_t kMaxText = 4096;

std::string text(const flatbuffers::String* s) {
  return s ? s->str() : std::string();
}

plr::Status check_text(const flatbuffers::String* s, const std::string& where) {
  if (s && s->size() > kMaxText)
    return plr::make_error(PLR_ERR_INVALID,
                           fmt::format("{}: longer than {} bytes", where, kMaxText));
  return {};
}

template <class V>
plr::Status check_count(const V* v, const std::string& where) {
  if (v && v->size() > kMaxEntries)
    return plr::make_error(
        PLR_ERR_INVALID, fmt::format("{}: {} entries, at most {}", where, v->size(), kMaxEntries));
  return {};
}

}  // namespace

flatbuffers::Offset<msg::ActionMemory> build(flatbuffers::FlatBufferBuilder& fbb,
                                             const Memory& memory) {
  std::vector<flatbuffers::Offset<msg::GripRecord>> grips;
  for (const auto& [id, g] : memory.grips) {
    const std::vector<std::uint32_t> neighbours(g.neighbours.begin(), g.neighbours.end());
    grips.push_back(msg::CreateGripRecord(fbb, id, g.failures, g.drops, g.cups, g.given_up,
                                          fbb.CreateString(g.last), fbb.CreateString(g.why),
                                          fbb.CreateVector(neighbours)));
  }
  std::vector<flatbuffers::Offset<msg::UnreachedRecord>> unreached;
  for (const auto& [id, why] : memory.unreached) {
    unreached.push_back(msg::CreateUnreachedRecord(fbb, id, fbb.CreateString(why)));
  }
  const std::vector<std::uint32_t> ungripped(memory.ungripped.begin(), memory.ungripped.end());
  const std::vector<std::uint32_t> shaken(memory.shaken.begin(), memory.shaken.end());
  return msg::CreateActionMemory(fbb, fbb.CreateVector(grips), fbb.CreateVector(ungripped),
                                 fbb.CreateVector(unreached), fbb.CreateVector(shaken));
}

flatbuffers::Offset<msg::TruckState> build(flatbuffers::FlatBufferBuilder& fbb,
                                           const SimState& state) {
  const std::vector<std::uint8_t> physics = UnloaderSimulation::physics_of(*state.saved).to_bytes();
  const sim::JointVector& q = UnloaderSimulation::q_of(*state.saved);
  const std::vector<double> joints(q.data(), q.data() + q.size());
  const auto p = fbb.CreateVector(physics);
  const auto j = fbb.CreateVector(joints);
  const auto m = build(fbb, state.memory);
  return msg::CreateTruckState(fbb, p, j, UnloaderSimulation::unloaded_of(*state.saved), m);
}

plr::Expected<Memory> from_message(const msg::ActionMemory& m, const std::string& origin) {
  Memory out;
  for (const auto& [v, name] : {std::pair{m.ungripped(), "ungripped"}, {m.shaken(), "shaken"}}) {
    if (auto s = check_count(v, origin + ": memory." + name); !s) return s.error();
  }
  if (auto s = check_count(m.grips(), origin + ": memory.grips"); !s) return s.error();
  if (auto s = check_count(m.unreached(), origin + ": memory.unreached"); !s) return s.error();
  if (m.grips()) {
    for (flatbuffers::uoffset_t i = 0; i < m.grips()->size(); ++i) {
      const msg::GripRecord* g = m.grips()->Get(i);
      const std::string where = fmt::format("{}: memory.grips[{}]", origin, i);
      if (auto s = check_text(g->last(), where + ".last"); !s) return s.error();
      if (auto s = check_text(g->why(), where + ".why"); !s) return s.error();
      if (auto s = check_count(g->neighbours(), where + ".neighbours"); !s) return s.error();
      if (g->failures() < 0 || g->drops() < 0 || g->cups() < 0)
        return plr::make_error(PLR_ERR_INVALID, where + ": counts must be >= 0");
      GripHistory h;
      h.failures = g->failures();
      h.drops = g->drops();
      h.cups = g->cups();
      h.given_up = g->given_up();
      h.last = text(g->last());
      h.why = text(g->why());
      if (g->neighbours()) h.neighbours.insert(g->neighbours()->begin(), g->neighbours()->end());
      out.grips.emplace(g->id(), std::move(h));
    }
  }
  if (m.unreached()) {
    for (flatbuffers::uoffset_t i = 0; i < m.unreached()->size(); ++i) {
      const msg::UnreachedRecord* u = m.unreached()->Get(i);
      if (auto s = check_text(u->why(), fmt::format("{}: memory.unreached[{}].why", origin, i)); !s)
        return s.error();
      out.unreached.emplace(u->id(), text(u->why()));
    }
  }
  if (m.ungripped()) out.ungripped.insert(m.ungripped()->begin(), m.ungripped()->end());
  if (m.shaken()) out.shaken.insert(m.shaken()->begin(), m.shaken()->end());
  return out;
}

plr::Expected<SimState> from_message(const msg::TruckState& state, const std::string& origin) {
  if (!state.physics() || state.physics()->size() == 0)
    return plr::make_error(PLR_ERR_INVALID, origin + ": physics: missing");
  auto snapshot = sim::Snapshot::from_bytes(state.physics()->data(), state.physics()->size());
  if (!snapshot) return plr::make_error(PLR_ERR_INVALID, origin + ": " + snapshot.error().message);
  if (!state.q() || state.q()->size() != sim::kNumJoints)
    return plr::make_error(
        PLR_ERR_INVALID, fmt::format("{}: q: must have {} joints, got {}", origin, sim::kNumJoints,
                                     state.q() ? state.q()->size() : 0));
  sim::JointVector q;
  for (int i = 0; i < sim::kNumJoints; ++i) {
    q[i] = state.q()->Get(static_cast<flatbuffers::uoffset_t>(i));
    if (!std::isfinite(q[i]))
      return plr::make_error(PLR_ERR_INVALID, fmt::format("{}: q[{}]: not finite", origin, i));
  }
  SimState out;
  if (state.memory()) {
    auto memory = from_message(*state.memory(), origin);
    if (!memory) return memory.error();
    out.memory = std::move(*memory);
  }
  out.saved = UnloaderSimulation::make_saved(std::move(*snapshot), q, state.unloaded());
  return out;
}

}  // namespace plr::actions
