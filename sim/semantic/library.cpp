#include "plr/sim/library.hpp"

#include <plr/msg/library_generated.h>

#include <fmt/format.h>

#include <cmath>

#include "plr/sim/framed_file.hpp"
#include "plr/sim/observation.hpp"
#include "plr/sim/unaligned.hpp"

namespace plr::sim {

namespace {

namespace msg = plr::msg;

constexpr std::size_t kMaxBoxes = 100000;
constexpr std::size_t kMaxCurve = 1000000;
constexpr std::size_t kMaxText = 1 << 16;
constexpr std::size_t kMaxPath = 10000;
constexpr std::size_t kMaxStart = 100000;

constexpr double kUnit = 1e-6;  // a stored rotation is orthonormal within this

flatbuffers::Offset<msg::WorldState> build_world(flatbuffers::FlatBufferBuilder& fbb,
                                                 const World& w) {
  const msg::Vec3 size(w.trailer.width, w.trailer.height, w.trailer.depth);
  std::vector<msg::BoxState> boxes;
  for (const Box& b : w.boxes) {
    const Eigen::Quaterniond q(b.pose.linear());
    const Eigen::Vector3d p = b.pose.translation();
    boxes.emplace_back(
        b.id, msg::Vec3(b.size.x(), b.size.y(), b.size.z()),
        msg::Pose(msg::Vec3(p.x(), p.y(), p.z()), msg::Quat(q.x(), q.y(), q.z(), q.w())), 0.0);
  }
  return msg::CreateWorldStateDirect(fbb, 0, &size, nullptr, 0.0, &boxes);
}

// Each box's rotation matrix, row by row: the quaternion alone does not give
// it back bit for bit.
flatbuffers::Offset<flatbuffers::Vector<double>> build_rotations(
    flatbuffers::FlatBufferBuilder& fbb, const World& w) {
  std::vector<double> r;
  r.reserve(9 * w.boxes.size());
  for (const Box& b : w.boxes)
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) r.push_back(b.pose.linear()(i, j));
  return fbb.CreateVector(r);
}

bool is_fidelity(const std::string& name) {
  return name == "full" || name == "adaptive" || name == "fast";
}

std::string text(const flatbuffers::String* s) {
  return s ? s->str() : std::string();
}

plr::Expected<LibraryEntry> read_entry(const msg::LibraryEntry& m, const std::string& where) {
  LibraryEntry e;
  for (const auto& [s, name] : {std::pair{m.name(), "name"},
                                {m.family(), "family"},
                                {m.observation_json(), "observation_json"}}) {
    if (s && s->size() > kMaxText)
      return invalid_at(where, fmt::format("{}: longer than {} bytes", name, kMaxText));
  }
  e.name = text(m.name());
  e.family = text(m.family());
  e.world_seed = m.world_seed();
  e.observation_json = text(m.observation_json());
  if (!m.world()) return invalid_at(where, "world: missing");
  if (m.world()->boxes() && m.world()->boxes()->size() > kMaxBoxes)
    return invalid_at(where, fmt::format("world: more than {} boxes", kMaxBoxes));
  e.world = world_from_message(*m.world());
  if (const auto* r = m.world_rotations()) {
    if (r->size() != 9 * e.world.boxes.size())
      return invalid_at(where, fmt::format("world_rotations: {} numbers for {} boxes (9 each)",
                                           r->size(), e.world.boxes.size()));
    for (std::size_t i = 0; i < e.world.boxes.size(); ++i) {
      Eigen::Matrix3d m3;
      for (int k = 0; k < 9; ++k)
        m3(k / 3, k % 3) = r->Get(static_cast<flatbuffers::uoffset_t>(9 * i + k));
      if (!m3.allFinite() || !(m3.transpose() * m3).isIdentity(kUnit) ||
          !(std::abs(m3.determinant() - 1.0) < kUnit))
        return invalid_at(where, fmt::format("world_rotations: box {}: not a rotation", i));
      e.world.boxes[i].pose.linear() = m3;
    }
  }
  for (std::size_t i = 0; i < e.world.boxes.size(); ++i) {
    const Box& b = e.world.boxes[i];
    if (!b.pose.matrix().allFinite() || !b.size.allFinite() || (b.size.array() <= 0).any())
      return invalid_at(where,
                        fmt::format("world: boxes[{}]: size must be > 0 and pose finite", i));
  }
  if (!m.strategy()) return invalid_at(where, "strategy: missing");
  auto strategy = from_message(*m.strategy(), "strategy");
  if (!strategy) return invalid_at(where, strategy.error().message);
  e.strategy = std::move(*strategy);
  e.lower = m.lower();
  e.upper = m.upper();
  if (!std::isfinite(e.lower) || !std::isfinite(e.upper) || e.lower > e.upper + 1e-9)
    return invalid_at(
        where, fmt::format("bounds [{}, {}]: must be finite and lower <= upper", e.lower, e.upper));
  if (const msg::LibraryProvenance* p = m.provenance()) {
    if (p->created() && p->created()->size() > kMaxText)
      return invalid_at(where, "provenance.created: too long");
    e.provenance = {p->seed(),         p->particles(),   p->horizon(),  p->trial_budget(),
                    p->trials(),       p->simulations(), p->nodes(),    p->wall_s(),
                    p->workers(),      p->epsilon1(),    p->epsilon2(), p->seconds_per_box(),
                    text(p->created())};
  }
  if (m.curve()) {
    if (m.curve()->size() > kMaxCurve) return invalid_at(where, "curve: too many points");
    for (flatbuffers::uoffset_t i = 0; i < m.curve()->size(); ++i) {
      const msg::BoundPoint b = element(*m.curve(), i);
      e.curve.push_back({b.wall_s(), b.lower(), b.upper(), b.trials()});
    }
  }
  if (m.parent() && m.parent()->size() > kMaxText) return invalid_at(where, "parent: too long");
  e.parent = text(m.parent());
  if (m.leaf()) {
    if (m.leaf()->size() > kMaxPath) return invalid_at(where, "leaf: too many observations");
    for (const auto o : *m.leaf()) {
      if (static_cast<int>(o) >= kNumObservations)
        return invalid_at(where,
                          fmt::format("leaf: observation {} out of range", static_cast<int>(o)));
      e.leaf.push_back(static_cast<Observation>(o));
    }
  }
  if (m.start()) {
    if (m.start()->size() > kMaxStart) return invalid_at(where, "start: too many particles");
    for (flatbuffers::uoffset_t i = 0; i < m.start()->size(); ++i) {
      const msg::StartParticle p = element(*m.start(), i);
      e.start.push_back({p.particle(), p.state_hash(), p.boxes_left()});
    }
  }
  if (m.fidelity()) {
    e.fidelity = m.fidelity()->str().substr(0, 64);
    if (!is_fidelity(e.fidelity))
      return invalid_at(where, "fidelity: '" + e.fidelity + "' is not full, adaptive or fast");
  }
  if (const msg::FidelityCheck* c = m.check()) {
    e.check = FidelityCheck{c->value(),      c->boxes(),          c->full_value(),
                            c->full_boxes(), c->full_particles(), c->first_particle()};
    for (const double v : {c->value(), c->boxes(), c->full_value(), c->full_boxes()})
      if (!std::isfinite(v)) return invalid_at(where, "check: values must be finite");
  }
  if (e.is_continuation() && (e.leaf.empty() || e.start.empty()))
    return invalid_at(where, "a continuation (parent '" + e.parent.substr(0, 64) +
                                 "') needs its leaf and the belief it starts from");
  return e;
}

}  // namespace

std::vector<std::size_t> continuations(const Library& library, std::size_t entry) {
  std::vector<std::size_t> out;
  const std::string& name = library.entries.at(entry).name;
  for (std::size_t i = 0; i < library.entries.size(); ++i)
    if (library.entries[i].parent == name) out.push_back(i);
  return out;
}

std::vector<std::uint8_t> serialize(const Library& library) {
  flatbuffers::FlatBufferBuilder fbb;
  std::vector<flatbuffers::Offset<msg::LibraryEntry>> entries;
  for (const LibraryEntry& e : library.entries) {
    const auto name = fbb.CreateString(e.name);
    const auto family = fbb.CreateString(e.family);
    const auto world = build_world(fbb, e.world);
    const auto obs = fbb.CreateString(e.observation_json);
    const auto strategy = build(fbb, e.strategy);
    const Provenance& p = e.provenance;
    const auto prov =
        msg::CreateLibraryProvenance(fbb, p.seed, p.particles, p.horizon, p.trial_budget, p.trials,
                                     p.simulations, p.nodes, p.wall_s, p.workers, p.epsilon1,
                                     p.epsilon2, p.seconds_per_box, fbb.CreateString(p.created));
    std::vector<msg::BoundPoint> curve;
    for (const BoundPoint& b : e.curve) curve.emplace_back(b.wall_s, b.lower, b.upper, b.trials);
    const auto curve_offset = fbb.CreateVectorOfStructs(curve);
    // A strategy for a fresh trailer writes none of the continuation's
    // fields: its bytes are those of a library made before they existed.
    flatbuffers::Offset<flatbuffers::String> parent;
    flatbuffers::Offset<flatbuffers::Vector<msg::Observation>> leaf;
    flatbuffers::Offset<flatbuffers::Vector<const msg::StartParticle*>> start;
    if (e.is_continuation()) {
      parent = fbb.CreateString(e.parent);
      std::vector<msg::Observation> path;
      for (const Observation o : e.leaf) path.push_back(static_cast<msg::Observation>(o));
      leaf = fbb.CreateVector(path);
      std::vector<msg::StartParticle> particles;
      for (const StartParticle& p : e.start)
        particles.emplace_back(p.particle, p.state_hash, p.boxes_left);
      start = fbb.CreateVectorOfStructs(particles);
    }
    const auto rotations = build_rotations(fbb, e.world);
    // Absent at full fidelity, as in a library made before the setting.
    flatbuffers::Offset<flatbuffers::String> fidelity;
    if (e.fidelity != kFullFidelity) fidelity = fbb.CreateString(e.fidelity);
    flatbuffers::Offset<msg::FidelityCheck> check;
    if (e.check) {
      const FidelityCheck& c = *e.check;
      check = msg::CreateFidelityCheck(fbb, c.value, c.full_value, c.full_particles,
                                       c.first_particle, c.full_boxes, c.boxes);
    }
    entries.push_back(msg::CreateLibraryEntry(fbb, name, family, e.world_seed, world, obs, strategy,
                                              e.lower, e.upper, prov, curve_offset, parent, leaf,
                                              start, rotations, fidelity, check));
  }
  const auto list = fbb.CreateVector(entries);
  msg::FinishStrategyLibraryBuffer(
      fbb, msg::CreateStrategyLibrary(fbb, kLibraryVersion, list, fbb.CreateString(library.made_by),
                                      fbb.CreateString(library.action_model)));
  return plr::frame(fbb.GetBufferPointer(), fbb.GetSize());
}

plr::Expected<Library> deserialize_library(const std::uint8_t* data, std::size_t size,
                                           const std::string& origin) {
  auto framed = unframe(data, size, kMaxLibraryBytes, "a library", origin);
  if (!framed) return framed.error();
  const std::uint8_t* fb = framed->data;
  const std::size_t body = framed->size;
  if (!msg::StrategyLibraryBufferHasIdentifier(fb))
    return invalid_at(origin, "byte 8: not a strategy library (identifier is not PLRL)");
  flatbuffers::Verifier verifier(fb, body);
  if (!msg::VerifyStrategyLibraryBuffer(verifier))
    return invalid_at(origin,
                      fmt::format("bytes 4..{}: malformed (FlatBuffers verification)", body + 4));
  const msg::StrategyLibrary* m = msg::GetStrategyLibrary(fb);
  if (m->version() != kLibraryVersion)
    return invalid_at(origin, fmt::format("version {} is not supported (this build reads {})",
                                          m->version(), kLibraryVersion));
  Library library;
  if (m->entries()) {
    if (m->entries()->size() > kMaxLibraryEntries)
      return invalid_at(origin, fmt::format("entries: more than {}", kMaxLibraryEntries));
    for (flatbuffers::uoffset_t i = 0; i < m->entries()->size(); ++i) {
      const msg::LibraryEntry* e = m->entries()->Get(i);
      const std::string name = text(e->name()).substr(0, 64);
      auto entry = read_entry(*e, fmt::format("{}: entries[{}] '{}'", origin, i, name));
      if (!entry) return entry.error();
      library.entries.push_back(std::move(*entry));
    }
  }
  library.made_by = text(m->made_by()).substr(0, kMaxMadeBy);
  library.action_model = text(m->action_model()).substr(0, kMaxMadeBy);
  return library;
}

plr::Status save_library(const Library& library, const std::filesystem::path& file) {
  return save_framed(serialize(library), file);
}

plr::Expected<Library> load_library(const std::filesystem::path& file) {
  auto bytes = read_bounded_file(file, kMaxLibraryBytes + 8);
  if (!bytes) return bytes.error();
  return deserialize_library(bytes->data(), bytes->size(), file.string());
}

}  // namespace plr::sim
