#include "plr/sim/observation.hpp"
#include "plr/sim/unaligned.hpp"

#include <plr/message.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

namespace plr::sim {

namespace {

// Footprints are shrunk by this much before testing overlap, so boxes that
// merely touch a neighbour (or lean on it by a few millimetres) are not
// counted as part of its column.
constexpr double kFootprintMargin = 0.03;

bool footprints_overlap(const Bounds& a, const Bounds& b) {
  const double m = kFootprintMargin;
  return a.x0 + m < b.x1 - m && b.x0 + m < a.x1 - m && a.y0 + m < b.y1 - m && b.y0 + m < a.y1 - m;
}

Height classify_height(double top, double mid, double high) {
  if (top >= high) return Height::kHigh;
  if (top >= mid) return Height::kMid;
  return Height::kLow;
}

}  // namespace

plr::Status ObservationParams::check() const {
  auto positive = [](double v) { return std::isfinite(v) && v > 0; };
  auto bad = [](const char* what) { return plr::make_error(PLR_ERR_INVALID, what); };
  if (!positive(h_pile)) return bad("param 'observation.h_pile': must be > 0");
  if (!positive(wall_depth)) return bad("param 'observation.wall_depth': must be > 0");
  if (!std::isfinite(min_pile_depth) || min_pile_depth < 0)
    return bad("param 'observation.min_pile_depth': must be >= 0");
  if (!positive(pile_mid) || !(pile_high > pile_mid))
    return bad("params 'observation.pile_mid'/'observation.pile_high': need 0 < mid < high");
  if (!positive(wall_mid) || !(wall_high > wall_mid))
    return bad("params 'observation.wall_mid'/'observation.wall_high': need 0 < mid < high");
  if (!(side_band > 0 && side_band < 1))
    return bad("param 'observation.side_band': must be in (0, 1)");
  return {};
}

plr::Expected<ObservationParams> ObservationParams::from_json(const nlohmann::json& values) {
  ObservationParams p;
  if (values.is_null()) return p;
  if (!values.is_object())
    return plr::make_error(PLR_ERR_INVALID, "param 'observation': expected a map of thresholds");
  const std::pair<const char*, double*> fields[] = {{"h_pile", &p.h_pile},
                                                    {"wall_depth", &p.wall_depth},
                                                    {"min_pile_depth", &p.min_pile_depth},
                                                    {"pile_mid", &p.pile_mid},
                                                    {"pile_high", &p.pile_high},
                                                    {"wall_mid", &p.wall_mid},
                                                    {"wall_high", &p.wall_high},
                                                    {"side_band", &p.side_band}};
  for (const auto& [key, value] : values.items()) {
    double* field = nullptr;
    for (const auto& [name, target] : fields)
      if (key == name) field = target;
    if (field == nullptr)
      return plr::make_error(PLR_ERR_INVALID, "param 'observation." + key + "': unknown");
    if (!value.is_number())
      return plr::make_error(
          PLR_ERR_INVALID,
          "param 'observation." + key + "': expected a number, got " + value.dump().substr(0, 40));
    *field = value.get<double>();
  }
  if (auto ok = p.check(); !ok) return ok.error();
  return p;
}

Bounds bounds(const Box& box) {
  const Eigen::Matrix3d r = box.pose.linear().cwiseAbs();
  const Eigen::Vector3d half = r * (box.size / 2);
  const Eigen::Vector3d c = box.pose.translation();
  return {c.x() - half.x(), c.x() + half.x(), c.y() - half.y(),
          c.y() + half.y(), c.z() - half.z(), c.z() + half.z()};
}

bool within(const Bounds& a, const Bounds& b, double gap) {
  return a.x0 < b.x1 + gap && b.x0 < a.x1 + gap && a.y0 < b.y1 + gap && b.y0 < a.y1 + gap &&
         a.z0 < b.z1 + gap && b.z0 < a.z1 + gap;
}

SceneAnalysis analyse(const World& world, const ObservationParams& p) {
  SceneAnalysis a;
  const auto& boxes = world.boxes;
  const std::size_t n = boxes.size();
  if (n == 0) return a;

  std::vector<Bounds> b(n);
  for (std::size_t i = 0; i < n; ++i) b[i] = bounds(boxes[i]);

  // Column tops; O(n^2) is a few hundred thousand cheap tests for a full trailer.
  std::vector<bool> is_wall(n);
  for (std::size_t i = 0; i < n; ++i) {
    double top = b[i].z1;
    for (std::size_t j = 0; j < n; ++j)
      if (j != i && b[j].z1 > top && footprints_overlap(b[i], b[j])) top = b[j].z1;
    is_wall[i] = top >= p.h_pile;
    (is_wall[i] ? a.wall : a.pile).push_back(boxes[i].id);
  }

  std::vector<std::size_t> first_wall, front_pile;
  // Boxes with no wall box in front of them across the trailer (a column of
  // the wall nothing stands before, a box lying before it) are in front
  // whatever their depth: a few boxes left standing in front of part of the
  // wall would otherwise make them the whole first wall, and the rest of the
  // wall and what lies before it unreachable to every pick region. A lower
  // wall across the whole width in front of a higher one still hides it.
  auto exposed = [&](std::size_t i) {
    constexpr double kOverlap = 0.05;
    for (std::size_t j = 0; j < n; ++j) {
      if (j != i && is_wall[j] && b[j].x1 <= b[i].x0 + kOverlap && b[j].y0 + kOverlap < b[i].y1 &&
          b[i].y0 + kOverlap < b[j].y1)
        return false;
    }
    return true;
  };
  if (!a.wall.empty()) {
    a.wall_near_x = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < n; ++i)
      if (is_wall[i]) a.wall_near_x = std::min(a.wall_near_x, b[i].x0);
    for (std::size_t i = 0; i < n; ++i) {
      if (is_wall[i] && (b[i].x0 <= a.wall_near_x + p.wall_depth || exposed(i))) {
        first_wall.push_back(i);
        a.first_wall.push_back(boxes[i].id);
        a.wall_height = std::max(a.wall_height, b[i].z1);
      }
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    const double cx = (b[i].x0 + b[i].x1) / 2;
    // Pile boxes level with the first wall (a column picked down to the
    // floor) are reachable too; those behind it are not.
    if (!is_wall[i] && (a.wall.empty() || cx < a.wall_near_x + p.wall_depth || exposed(i))) {
      front_pile.push_back(i);
      a.front_pile.push_back(boxes[i].id);
    }
  }
  if (!front_pile.empty()) {
    a.pile_near_x = std::numeric_limits<double>::infinity();
    a.pile_far_x = -std::numeric_limits<double>::infinity();
    for (auto i : front_pile) {
      a.pile_near_x = std::min(a.pile_near_x, b[i].x0);
      a.pile_far_x = std::max(a.pile_far_x, b[i].x1);
      a.pile_height = std::max(a.pile_height, b[i].z1);
    }
    a.pile_depth = a.pile_far_x - a.pile_near_x;
  }

  const double band = p.side_band * world.trailer.width / 2;
  // Top box (ties: the nearer, then the more central one), its side; y > 0 is left.
  auto top_of = [&](const std::vector<std::size_t>& members, std::uint32_t& id, Side& side) {
    if (members.empty()) return;
    std::size_t top = members.front();
    for (auto i : members) {
      const double dz = b[i].z1 - b[top].z1, dx = b[i].x0 - b[top].x0;
      const double dy =
          std::abs(boxes[i].pose.translation().y()) - std::abs(boxes[top].pose.translation().y());
      if (dz > 1e-6 || (dz > -1e-6 && (dx < -1e-6 || (dx < 1e-6 && dy < -1e-6)))) top = i;
    }
    id = boxes[top].id;
    const double y = boxes[top].pose.translation().y();
    side = y > band ? Side::kLeft : (y < -band ? Side::kRight : Side::kCenter);
  };
  top_of(front_pile, a.pile_top_box, a.pile_side);
  top_of(first_wall, a.wall_top_box, a.wall_side);
  a.pile_class = classify_height(a.pile_height, p.pile_mid, p.pile_high);
  a.wall_class = classify_height(a.wall_height, p.wall_mid, p.wall_high);

  if (!front_pile.empty() && (first_wall.empty() || a.pile_depth >= p.min_pile_depth)) {
    a.observation = make_observation(Structure::kPile, a.pile_class, a.pile_side);
    a.top_box = a.pile_top_box;
  } else {
    a.observation = make_observation(Structure::kWall, a.wall_class, a.wall_side);
    a.top_box = a.wall_top_box;
  }
  return a;
}

std::optional<Observation> classify(const World& world, const ObservationParams& params) {
  return analyse(world, params).observation;
}

World world_from_message(const plr::msg::WorldState& state) {
  World w;
  if (const auto* t = state.trailer_size()) {
    w.trailer.width = t->x();
    w.trailer.height = t->y();
    w.trailer.depth = t->z();
  }
  if (const auto* boxes = state.boxes()) {
    w.boxes.reserve(boxes->size());
    for (flatbuffers::uoffset_t i = 0; i < boxes->size(); ++i) {
      const plr::msg::BoxState b = element(*boxes, i);
      const auto* m = &b;
      Box box;
      box.id = m->id();
      box.size = {m->size().x(), m->size().y(), m->size().z()};
      const auto& pos = m->pose().position();
      const auto& q = m->pose().orientation();
      Eigen::Quaterniond quat(q.w(), q.x(), q.y(), q.z());
      // An all-zero quaternion (a default-built pose) means "not rotated".
      if (quat.norm() < 1e-9) quat = Eigen::Quaterniond::Identity();
      box.pose = Eigen::Isometry3d::Identity();
      box.pose.linear() = quat.normalized().toRotationMatrix();
      box.pose.translation() = Eigen::Vector3d(pos.x(), pos.y(), pos.z());
      box.mass = m->mass();
      w.boxes.push_back(box);
    }
  }
  return w;
}

plr::Expected<World> world_from_request(const plr::msg::NextStrategyRequest& request) {
  const auto* bytes = request.world();
  if (bytes == nullptr || bytes->size() == 0)
    return plr::make_error(PLR_ERR_INVALID, "strategy/next: request carries no world");
  std::vector<std::uint64_t> aligned;
  const auto* state = plr::read_nested<plr::msg::WorldState>(bytes, aligned);
  if (state == nullptr)
    return plr::make_error(PLR_ERR_INVALID, "strategy/next: world is not a valid WorldState");
  return world_from_message(*state);
}

}  // namespace plr::sim
