#include "plr/sim/collision.hpp"

#include <fcl/fcl.h>
#include <fcl/geometry/octree/octree.h>
#include <octomap/octomap.h>

#include <algorithm>
#include <stdexcept>
#include <unordered_set>

namespace plr::sim {

std::shared_ptr<octomap::OcTree> makeTrailerOctree(const Trailer& trailer, double resolution) {
  auto tree = std::make_shared<octomap::OcTree>(resolution);
  const double r = resolution;
  const double x0 = -5.0, x1 = trailer.depth + r;
  const double hw = trailer.width / 2.0;
  auto mark = [&](double x, double y, double z) {
    tree->updateNode(octomap::point3d(x, y, z), true, true);
  };
  // Voxel centres one voxel outside the free interior.
  for (double x = x0 + r / 2; x < x1; x += r) {
    for (double y = -hw - r / 2; y < hw + r; y += r) {
      mark(x, y, -r / 2);
      if (x >= 0.0) mark(x, y, trailer.height + r / 2);
    }
  }
  for (double x = r / 2; x < x1; x += r) {
    for (double z = r / 2; z < trailer.height + r; z += r) {
      mark(x, -hw - r / 2, z);
      mark(x, hw + r / 2, z);
    }
  }
  for (double y = -hw - r / 2; y < hw + r; y += r) {
    for (double z = r / 2; z < trailer.height + r; z += r) mark(trailer.depth + r / 2, y, z);
  }
  tree->updateInnerOccupancy();
  return tree;
}

namespace {

fcl::Transform3d toFcl(const Eigen::Isometry3d& t) {
  fcl::Transform3d f = fcl::Transform3d::Identity();
  f.linear() = t.linear();
  f.translation() = t.translation();
  return f;
}

// One collision shape of the robot (or a held box) with its inflatable
// enclosing box for sweeps.
struct RobotShape {
  int link = 0;
  Eigen::Isometry3d origin = Eigen::Isometry3d::Identity();
  Eigen::Vector3d half = Eigen::Vector3d::Zero();  // enclosing box half-extents
  std::string label;
  std::unique_ptr<fcl::CollisionObjectd> exact;
  std::shared_ptr<fcl::Boxd> swept_box;
  std::unique_ptr<fcl::CollisionObjectd> swept;
};

struct WorldBox {
  std::uint32_t id = 0;
  std::unique_ptr<fcl::CollisionObjectd> obj;
};

// Coarse cells holding any occupied octree leaf: a shape whose AABB touches
// none of them cannot hit the octree, which spares FCL's descent from the
// root for links in free space (most checks).
class OccupancyGrid {
 public:
  static constexpr double kCell = 0.25;

  explicit OccupancyGrid(const octomap::OcTree& tree) {
    double x0, y0, z0, x1, y1, z1;
    tree.getMetricMin(x0, y0, z0);
    tree.getMetricMax(x1, y1, z1);
    origin_ = Eigen::Vector3d(x0, y0, z0);
    for (int i = 0; i < 3; ++i) {
      const double span = (i == 0 ? x1 - x0 : i == 1 ? y1 - y0 : z1 - z0);
      dims_[i] = std::max(1, static_cast<int>(std::ceil(span / kCell)) + 1);
    }
    bits_.assign(static_cast<std::size_t>(dims_[0]) * dims_[1] * dims_[2], 0);
    for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
      if (!tree.isNodeOccupied(*it)) continue;
      const double h = it.getSize() / 2.0;
      const Eigen::Vector3d c(it.getX(), it.getY(), it.getZ());
      mark(c - Eigen::Vector3d::Constant(h), c + Eigen::Vector3d::Constant(h));
    }
  }

  bool mayHit(const fcl::AABBd& box) const {
    Eigen::Vector3i lo, hi;
    if (!range(box.min_, box.max_, lo, hi)) return false;
    for (int x = lo[0]; x <= hi[0]; ++x) {
      for (int y = lo[1]; y <= hi[1]; ++y) {
        for (int z = lo[2]; z <= hi[2]; ++z) {
          if (bits_[index(x, y, z)]) return true;
        }
      }
    }
    return false;
  }

 private:
  std::size_t index(int x, int y, int z) const {
    return (static_cast<std::size_t>(x) * dims_[1] + y) * dims_[2] + z;
  }
  bool range(const Eigen::Vector3d& a, const Eigen::Vector3d& b, Eigen::Vector3i& lo,
             Eigen::Vector3i& hi) const {
    for (int i = 0; i < 3; ++i) {
      const double l = std::floor((a[i] - origin_[i]) / kCell),
                   h = std::floor((b[i] - origin_[i]) / kCell);
      if (h < 0 || l >= dims_[i]) return false;
      lo[i] = static_cast<int>(std::max(0.0, l));
      hi[i] = static_cast<int>(std::min<double>(dims_[i] - 1, h));
    }
    return true;
  }
  void mark(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
    Eigen::Vector3i lo, hi;
    if (!range(a, b, lo, hi)) return;
    for (int x = lo[0]; x <= hi[0]; ++x) {
      for (int y = lo[1]; y <= hi[1]; ++y) {
        for (int z = lo[2]; z <= hi[2]; ++z) bits_[index(x, y, z)] = 1;
      }
    }
  }

  Eigen::Vector3d origin_;
  std::array<int, 3> dims_{};
  std::vector<std::uint8_t> bits_;
};

bool collide(const fcl::CollisionObjectd* a, const fcl::CollisionObjectd* b) {
  if (!a->getAABB().overlap(b->getAABB())) return false;
  fcl::CollisionRequestd req;
  fcl::CollisionResultd res;
  fcl::collide(a, b, req, res);
  return res.isCollision();
}

}  // namespace

struct CollisionChecker::Impl {
  const RobotModel* robot = nullptr;
  CollisionOptions options;
  std::shared_ptr<const octomap::OcTree> octree;
  std::unique_ptr<fcl::CollisionObjectd> octree_obj;
  std::unique_ptr<OccupancyGrid> grid;
  std::vector<WorldBox> boxes;  // sorted by AABB min x
  std::vector<double> box_min_x;
  double box_max_len_x = 0.0;
  std::unordered_set<std::uint32_t> ignored;
  std::vector<RobotShape> shapes;
  int robot_shape_count = 0;                    // shapes beyond this are held boxes
  std::vector<std::vector<bool>> allowed;       // [link][link]
  std::vector<std::pair<int, int>> self_pairs;  // shape index pairs checked
  // reach[l][j]: bound on how far a point of link l moves per unit of joint j.
  std::vector<std::array<double, kNumJoints>> reach;
  mutable std::vector<Eigen::Isometry3d> poses;
  mutable CollisionStats stats;

  void addShape(int link, const Eigen::Isometry3d& origin,
                std::shared_ptr<fcl::CollisionGeometryd> geom, const Eigen::Vector3d& half,
                std::string label) {
    RobotShape s;
    s.link = link;
    s.origin = origin;
    s.half = half;
    s.label = std::move(label);
    s.exact = std::make_unique<fcl::CollisionObjectd>(std::move(geom));
    s.swept_box = std::make_shared<fcl::Boxd>(2.0 * half);
    s.swept = std::make_unique<fcl::CollisionObjectd>(s.swept_box);
    shapes.push_back(std::move(s));
  }

  void rebuildPairsAndReach() {
    self_pairs.clear();
    for (std::size_t i = 0; i < shapes.size(); ++i) {
      for (std::size_t j = i + 1; j < shapes.size(); ++j) {
        const int a = shapes[i].link, b = shapes[j].link;
        if (a != b && !allowed[a][b])
          self_pairs.emplace_back(static_cast<int>(i), static_cast<int>(j));
      }
    }
    // A point of link l is at most (sum of joint offsets down the chain +
    // its distance from l's frame) away from an ancestor joint's origin, in
    // any configuration; prismatic joints count at full extension.
    const auto& links = robot->links();
    std::vector<double> extent(links.size(), 0.0);
    for (const auto& s : shapes) {
      extent[s.link] = std::max(extent[s.link], s.origin.translation().norm() + s.half.norm());
    }
    reach.assign(links.size(), {});
    for (std::size_t l = 0; l < links.size(); ++l) {
      double dist = extent[l];
      for (int k = static_cast<int>(l); k >= 0; k = links[k].parent_link) {
        const Link& lk = links[k];
        if (lk.joint >= 0) {
          reach[l][lk.joint] = lk.joint_type == JointType::kPrismatic ? 1.0 : dist;
          if (lk.joint_type == JointType::kPrismatic) {
            const JointLimits& lim = robot->limits(lk.joint);
            dist += std::max(std::abs(lim.lower), std::abs(lim.upper));
          }
        }
        dist += lk.origin.translation().norm();
      }
    }
  }

  void place(const Config& q) const {
    robot->forwardKinematics(q, poses);
    for (const auto& s : shapes) {
      s.exact->setTransform(toFcl(poses[s.link] * s.origin));
      s.exact->computeAABB();
    }
  }

  bool hitsOctree(const fcl::CollisionObjectd* o) const {
    return octree_obj && grid->mayHit(o->getAABB()) && collide(o, octree_obj.get());
  }

  // World box hit by `o` (not ignored), or -1.
  long hitBox(const fcl::CollisionObjectd* o) const {
    const fcl::AABBd& a = o->getAABB();
    auto i = std::lower_bound(box_min_x.begin(), box_min_x.end(), a.min_.x() - box_max_len_x) -
             box_min_x.begin();
    for (; i < static_cast<long>(boxes.size()) &&
           box_min_x[static_cast<std::size_t>(i)] <= a.max_.x();
         ++i) {
      const WorldBox& b = boxes[static_cast<std::size_t>(i)];
      if (collide(o, b.obj.get()) && ignored.count(b.id) == 0) return i;
    }
    return -1;
  }

  // Index of the first colliding shape pair as text, or empty.
  std::string firstHit(bool swept) const {
    auto obj = [&](const RobotShape& s) { return swept ? s.swept.get() : s.exact.get(); };
    for (const auto& s : shapes) {
      if (hitsOctree(obj(s))) return s.label + " - trailer";
      const long b = hitBox(obj(s));
      if (b >= 0)
        return s.label + " - box " + std::to_string(boxes[static_cast<std::size_t>(b)].id);
    }
    for (const auto& [i, j] : self_pairs) {
      if (collide(obj(shapes[i]), obj(shapes[j]))) return shapes[i].label + " - " + shapes[j].label;
    }
    return {};
  }

  bool anyHit(bool swept) const {
    auto obj = [&](const RobotShape& s) { return swept ? s.swept.get() : s.exact.get(); };
    for (const auto& s : shapes) {
      if (hitsOctree(obj(s)) || hitBox(obj(s)) >= 0) return true;
    }
    for (const auto& [i, j] : self_pairs) {
      if (collide(obj(shapes[i]), obj(shapes[j]))) return true;
    }
    return false;
  }

  bool stateValid(const Config& q) const {
    ++stats.state_checks;
    if (!robot->withinLimits(q, options.limit_tolerance)) return false;
    place(q);
    return !anyHit(false);
  }

  // Sweep of the motion a->b (a, b valid) with midpoint m: every shape
  // inflated by its travel bound over half the segment. base_x moves every
  // link alike, so it does not count for self-collision: robot pairs are
  // checked with the boxes inflated by the other joints' part only.
  bool sweepFree(const Config& mid, const Config& half_step) const {
    ++stats.sweep_checks;
    robot->forwardKinematics(mid, poses);
    for (auto& s : shapes) {
      double d_self = 0.0;
      for (int j = 1; j < kNumJoints; ++j) d_self += reach[s.link][j] * std::abs(half_step[j]);
      const Eigen::Isometry3d pose = poses[s.link] * s.origin;
      // The base translates along world x: stretch the box along that
      // direction only (exact for a translation), in the shape's frame.
      const Eigen::Vector3d base_shift =
          (pose.linear().transpose() * Eigen::Vector3d::UnitX()).cwiseAbs() *
          std::abs(half_step[kBaseX]);
      s.swept_box->side = 2.0 * (s.half + Eigen::Vector3d::Constant(d_self) + base_shift);
      s.swept_box->computeLocalAABB();
      s.swept->setTransform(toFcl(pose));
      s.swept->computeAABB();
      if (hitsOctree(s.swept.get()) || hitBox(s.swept.get()) >= 0) return false;
      s.swept_box->side = 2.0 * (s.half + Eigen::Vector3d::Constant(d_self));
      s.swept_box->computeLocalAABB();
      s.swept->computeAABB();
    }
    for (const auto& [i, j] : self_pairs) {
      if (collide(shapes[i].swept.get(), shapes[j].swept.get())) return false;
    }
    return true;
  }

  double travel(const Config& step) const {
    double worst = 0.0;
    for (const auto& r : reach) {
      double d = 0.0;
      for (int j = 0; j < kNumJoints; ++j) d += r[j] * std::abs(step[j]);
      worst = std::max(worst, d);
    }
    return worst;
  }
};

CollisionChecker::CollisionChecker(const RobotModel& robot, const World& world,
                                   std::shared_ptr<const octomap::OcTree> octree,
                                   const CollisionOptions& options)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.robot = &robot;
  m.options = options;
  m.octree =
      octree ? std::move(octree) : makeTrailerOctree(world.trailer, options.octree_resolution);
  m.octree_obj = std::make_unique<fcl::CollisionObjectd>(std::make_shared<fcl::OcTreed>(m.octree));
  m.octree_obj->computeAABB();
  m.grid = std::make_unique<OccupancyGrid>(*m.octree);
  for (const Box& b : world.boxes) {
    WorldBox wb;
    wb.id = b.id;
    wb.obj =
        std::make_unique<fcl::CollisionObjectd>(std::make_shared<fcl::Boxd>(b.size), toFcl(b.pose));
    wb.obj->computeAABB();
    m.boxes.push_back(std::move(wb));
  }
  std::sort(m.boxes.begin(), m.boxes.end(), [](const WorldBox& a, const WorldBox& b) {
    return a.obj->getAABB().min_.x() < b.obj->getAABB().min_.x();
  });
  for (const WorldBox& b : m.boxes) {
    const fcl::AABBd& a = b.obj->getAABB();
    m.box_min_x.push_back(a.min_.x());
    m.box_max_len_x = std::max(m.box_max_len_x, a.max_.x() - a.min_.x());
  }
  const auto& links = robot.links();
  for (std::size_t l = 0; l < links.size(); ++l) {
    for (const CollisionShape& cs : links[l].shapes) {
      std::shared_ptr<fcl::CollisionGeometryd> geom;
      Eigen::Vector3d half;
      switch (cs.type) {
        case CollisionShape::Type::kBox:
          geom = std::make_shared<fcl::Boxd>(cs.size);
          half = cs.size / 2.0;
          break;
        case CollisionShape::Type::kCylinder:
          geom = std::make_shared<fcl::Cylinderd>(cs.size.x(), cs.size.y());
          half = Eigen::Vector3d(cs.size.x(), cs.size.x(), cs.size.y() / 2.0);
          break;
        case CollisionShape::Type::kSphere:
          geom = std::make_shared<fcl::Sphered>(cs.size.x());
          half = Eigen::Vector3d::Constant(cs.size.x());
          break;
      }
      m.addShape(static_cast<int>(l), cs.origin, std::move(geom), half, links[l].name);
    }
  }
  m.robot_shape_count = static_cast<int>(m.shapes.size());
  m.allowed.assign(links.size(), std::vector<bool>(links.size(), false));
  for (std::size_t l = 0; l < links.size(); ++l) {
    if (links[l].parent_link >= 0) {
      m.allowed[l][links[l].parent_link] = m.allowed[links[l].parent_link][l] = true;
    }
  }
  for (const auto& [a, b] : robot.allowedCollisions()) m.allowed[a][b] = m.allowed[b][a] = true;
  m.rebuildPairsAndReach();
}

CollisionChecker::~CollisionChecker() = default;
CollisionChecker::CollisionChecker(CollisionChecker&&) noexcept = default;
CollisionChecker& CollisionChecker::operator=(CollisionChecker&&) noexcept = default;

const RobotModel& CollisionChecker::robot() const {
  return *impl_->robot;
}
const CollisionOptions& CollisionChecker::options() const {
  return impl_->options;
}

void CollisionChecker::allowCollision(const std::string& a, const std::string& b) {
  const int ia = impl_->robot->linkIndex(a), ib = impl_->robot->linkIndex(b);
  if (ia < 0 || ib < 0)
    throw std::invalid_argument("allowCollision: unknown link '" + (ia < 0 ? a : b) + "'");
  impl_->allowed[ia][ib] = impl_->allowed[ib][ia] = true;
  impl_->rebuildPairsAndReach();
}

void CollisionChecker::ignoreBox(std::uint32_t id) {
  impl_->ignored.insert(id);
}
void CollisionChecker::clearIgnoredBoxes() {
  impl_->ignored.clear();
}

void CollisionChecker::attachBox(const Box& box, const Config& q) {
  Impl& m = *impl_;
  const int plate = m.robot->plateLink();
  const Eigen::Isometry3d in_plate = m.robot->platePose(q).inverse() * box.pose;
  m.addShape(plate, in_plate, std::make_shared<fcl::Boxd>(box.size), box.size / 2.0,
             "held box " + std::to_string(box.id));
  m.ignored.insert(box.id);
  m.rebuildPairsAndReach();
}

void CollisionChecker::detachAll() {
  impl_->shapes.resize(impl_->robot_shape_count);
  impl_->rebuildPairsAndReach();
}

bool CollisionChecker::isValid(const Config& q) const {
  return impl_->stateValid(q);
}

bool CollisionChecker::isMotionValid(const Config& a, const Config& b, bool check_endpoints) const {
  const Impl& m = *impl_;
  if (check_endpoints && (!m.stateValid(a) || !m.stateValid(b))) return false;
  const double res = m.options.motion_resolution;
  struct Segment {
    Config a, b;
  };
  std::vector<Segment> todo{{a, b}};
  while (!todo.empty()) {
    const Segment s = todo.back();
    todo.pop_back();
    const Config half = (s.b - s.a) / 2.0;
    const Config mid = s.a + half;
    if (m.travel(half) <= res / 2.0) {
      // Down to resolution: the checked states are at most `res` apart.
      if (!m.stateValid(mid)) return false;
      continue;
    }
    if (m.sweepFree(mid, half)) continue;
    if (!m.stateValid(mid)) return false;
    todo.push_back({mid, s.b});
    todo.push_back({s.a, mid});
  }
  return true;
}

std::string CollisionChecker::describeCollision(const Config& q) const {
  const Impl& m = *impl_;
  for (int i = 0; i < kNumJoints; ++i) {
    const JointLimits& l = m.robot->limits(i);
    if (!(q[i] >= l.lower - m.options.limit_tolerance &&
          q[i] <= l.upper + m.options.limit_tolerance)) {
      return std::string(kJointNames[i]) + " beyond limits";
    }
  }
  m.place(q);
  return m.firstHit(false);
}

const CollisionStats& CollisionChecker::stats() const {
  return impl_->stats;
}
void CollisionChecker::resetStats() {
  impl_->stats = {};
}

}  // namespace plr::sim
