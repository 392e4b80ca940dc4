#include "plr/sim/collision.hpp"

#include "plr/sim/octree.hpp"

#include <fcl/fcl.h>
#include <fcl/geometry/octree/octree.h>
#include <octomap/octomap.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <mutex>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>

namespace plr::sim {

namespace {

fcl::Transform3d to_fcl(const Eigen::Isometry3d& t) {
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
  // Their enclosing boxes, set with their AABBs (placed()).
  fcl::OBBd exact_obb, swept_obb;
  // Links a mode does not move keep their pose from check to check: their
  // last collision-free placement is remembered and not checked again.
  // Epochs change whenever the placement does; self pairs remember the
  // epochs at which they were free.
  using Placement = Eigen::Matrix<double, 3, 5>;  // pose (3x4) + box sides
  Placement exact_at = Placement::Constant(std::nan(""));
  Placement swept_at = Placement::Constant(std::nan(""));
  std::uint64_t exact_epoch = 0, swept_epoch = 0;
  bool exact_world_free = false, swept_world_free = false;
  Placement swept_world_free_at = Placement::Constant(std::nan(""));
};

RobotShape::Placement placement(const Eigen::Isometry3d& pose, const Eigen::Vector3d& side) {
  RobotShape::Placement p;
  p.leftCols<4>() = pose.matrix().topRows<3>();
  p.col(4) = side;
  return p;
}

struct WorldBox {
  std::uint32_t id = 0;
  std::shared_ptr<fcl::Boxd> shape;  // resized in place when the box is reused
  std::unique_ptr<fcl::CollisionObjectd> obj;
  fcl::OBBd obb;  // obj's enclosing box (itself), kept with it: a planner meets a box many times
};

// Occupied octree leaves counted in a 3-D prefix-sum table at the octree's
// resolution: how many occupied voxels a block of cells holds is eight
// lookups. A shape whose box meets no occupied cell cannot hit the octree,
// which spares FCL's descent from the root for links in free space and for
// links beside a wall or the floor but not touching it (most checks).
class OccupancyGrid {
 public:
  explicit OccupancyGrid(const octomap::OcTree& tree) {
    double x0, y0, z0, x1, y1, z1;
    tree.getMetricMin(x0, y0, z0);
    tree.getMetricMax(x1, y1, z1);
    origin_ = Eigen::Vector3d(x0, y0, z0);
    const Eigen::Vector3d span(x1 - x0, y1 - y0, z1 - z0);
    // Voxel-sized cells, coarser if the table would get large.
    cell_ = tree.getResolution();
    while ((span / cell_).prod() > 2e7) cell_ *= 2.0;
    voxel_sized_ = cell_ == tree.getResolution();
    for (int i = 0; i < 3; ++i)
      dims_[i] = std::max(1, static_cast<int>(std::ceil(span[i] / cell_ - 1e-9)));
    sum_.assign(static_cast<std::size_t>(dims_[0] + 1) * (dims_[1] + 1) * (dims_[2] + 1), 0);
    for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) {
      if (!tree.isNodeOccupied(*it)) continue;
      const double h = it.getSize() / 2.0;
      const Eigen::Vector3d c(it.getX(), it.getY(), it.getZ());
      Eigen::Vector3i lo, hi;
      if (!range(c - Eigen::Vector3d::Constant(h), c + Eigen::Vector3d::Constant(h), lo, hi))
        continue;
      for (int x = lo[0]; x <= hi[0]; ++x) {
        for (int y = lo[1]; y <= hi[1]; ++y) {
          for (int z = lo[2]; z <= hi[2]; ++z) at(x + 1, y + 1, z + 1) = 1;
        }
      }
    }
    for (int x = 1; x <= dims_[0]; ++x) {
      for (int y = 1; y <= dims_[1]; ++y) {
        for (int z = 1; z <= dims_[2]; ++z) {
          at(x, y, z) += at(x - 1, y, z) + at(x, y - 1, z) + at(x, y, z - 1) - at(x - 1, y - 1, z) -
                         at(x - 1, y, z - 1) - at(x, y - 1, z - 1) + at(x - 1, y - 1, z - 1);
        }
      }
    }
  }

  // One cell per voxel (the table was not coarsened to fit in memory).
  bool voxel_sized() const { return voxel_sized_; }

  // Whether `shape`, an oriented box within `bounds`, meets an occupied
  // cell: the block of cells under `bounds` is halved, longest side first,
  // while a part holds occupied cells and its box meets the shape.
  bool may_hit(const fcl::OBBd& shape, const fcl::AABBd& bounds) const {
    Eigen::Vector3i lo, hi;
    return range(bounds.min_, bounds.max_, lo, hi) && occupied_touching(shape, lo, hi);
  }

 private:
  bool occupied_touching(const fcl::OBBd& shape, Eigen::Vector3i lo, Eigen::Vector3i hi) const {
    if (occupied(lo, hi) == 0) return false;
    // Shrunk to its occupied cells first: a block of floor under a link
    // just above it is then one thin slab, apart from the link.
    for (int a = 0; a < 3; ++a) {
      int l = lo[a], r = hi[a];  // the first occupied slice along a
      while (l < r) {
        Eigen::Vector3i upto = hi;
        upto[a] = l + (r - l) / 2;
        if (occupied(lo, upto) > 0)
          r = upto[a];
        else
          l = upto[a] + 1;
      }
      lo[a] = l;
      for (r = hi[a]; l < r;) {  // the last one
        Eigen::Vector3i from = lo;
        from[a] = l + (r - l + 1) / 2;
        if (occupied(from, hi) > 0)
          l = from[a];
        else
          r = from[a] - 1;
      }
      hi[a] = l;
    }
    const Eigen::Vector3d cells = (hi - lo + Eigen::Vector3i::Ones()).cast<double>() * cell_;
    fcl::OBBd block;
    block.axis.setIdentity();
    block.extent = cells / 2.0;
    block.To = origin_ + lo.cast<double>() * cell_ + block.extent;
    if (!block.overlap(shape)) return false;
    // A solid block (a stretch of wall or floor) met by the shape is a hit.
    if (occupied(lo, hi) == (hi - lo + Eigen::Vector3i::Ones()).prod()) return true;
    int axis = 0;
    const int span = (hi - lo).maxCoeff(&axis);
    Eigen::Vector3i first_hi = hi, second_lo = lo;
    first_hi[axis] = lo[axis] + span / 2;
    second_lo[axis] = first_hi[axis] + 1;
    return occupied_touching(shape, lo, first_hi) || occupied_touching(shape, second_lo, hi);
  }
  // Occupied cells in the block [lo, hi].
  std::int64_t occupied(const Eigen::Vector3i& lo, const Eigen::Vector3i& hi) const {
    const int x0 = lo[0], y0 = lo[1], z0 = lo[2], x1 = hi[0] + 1, y1 = hi[1] + 1, z1 = hi[2] + 1;
    return get(x1, y1, z1) - get(x0, y1, z1) - get(x1, y0, z1) - get(x1, y1, z0) + get(x0, y0, z1) +
           get(x0, y1, z0) + get(x1, y0, z0) - get(x0, y0, z0);
  }

  std::int32_t& at(int x, int y, int z) {
    return sum_[(static_cast<std::size_t>(x) * (dims_[1] + 1) + y) * (dims_[2] + 1) + z];
  }
  std::int64_t get(int x, int y, int z) const {
    return sum_[(static_cast<std::size_t>(x) * (dims_[1] + 1) + y) * (dims_[2] + 1) + z];
  }
  // Cells whose interior overlaps [a, b]; false if none.
  bool range(const Eigen::Vector3d& a, const Eigen::Vector3d& b, Eigen::Vector3i& lo,
             Eigen::Vector3i& hi) const {
    for (int i = 0; i < 3; ++i) {
      const double l = std::floor((a[i] - origin_[i]) / cell_ + 1e-9);
      const double h = std::ceil((b[i] - origin_[i]) / cell_ - 1e-9) - 1.0;
      if (h < 0 || l >= dims_[i] || h < l) return false;
      lo[i] = static_cast<int>(std::max(0.0, l));
      hi[i] = static_cast<int>(std::min<double>(dims_[i] - 1, h));
    }
    return true;
  }

  Eigen::Vector3d origin_;
  double cell_ = 0.05;
  bool voxel_sized_ = true;
  std::array<int, 3> dims_{};
  std::vector<std::int32_t> sum_;  // (dims + 1)^3, zero border
};

// What a trailer is known by: its octree (the shared_ptr's owner and
// pointee, so an octree freed and another allocated at the same address is a
// different one: the cache's weak_ptr keeps the owner block alive), or, for a
// shell the checker builds itself, the trailer's sizes and the resolution.
struct TrailerKey {
  std::weak_ptr<const octomap::OcTree> octree;
  const octomap::OcTree* tree = nullptr;
  std::array<double, 4> shell{};  // width, height, depth, resolution

  bool matches(const std::shared_ptr<const octomap::OcTree>& o, const Trailer& t,
               double resolution) const {
    if (o) return tree == o.get() && !octree.owner_before(o) && !o.owner_before(octree);
    return tree == nullptr &&
           shell == std::array<double, 4>{t.width, t.height, t.depth, resolution};
  }
};

// The part of a checker that is a function of the octree alone, shared by
// every checker on it and only read once built (safe across threads: FCL's
// octree collision keeps its traversal state on the stack).
struct TrailerTables {
  TrailerKey key;
  std::uint64_t serial = 0;  // which build (CollisionChecker::trailer_serial)
  std::shared_ptr<const octomap::OcTree> octree;
  fcl::CollisionObjectd object;
  OccupancyGrid grid;

  explicit TrailerTables(std::shared_ptr<const octomap::OcTree> tree)
      : octree(tree), object(std::make_shared<fcl::OcTreed>(tree)), grid(*tree) {
    object.computeAABB();
  }
};

std::atomic<std::uint64_t> g_trailer_builds{0};

// Trailer tables by key. Entries live as long as a checker holds them, and
// the last one built lives on without one: callers that make a checker per
// query on the same trailer (one at a time) find it still there.
class TrailerCache {
 public:
  std::shared_ptr<const TrailerTables> get(const std::shared_ptr<const octomap::OcTree>& octree,
                                           const Trailer& trailer, double resolution) {
    if (auto hit = find(octree, trailer, resolution)) return hit;
    // Built outside the lock (tens of ms) so lookups of other trailers do not
    // wait; two threads missing the same key at once both build, one keeps.
    std::shared_ptr<const octomap::OcTree> tree =
        octree ? octree
               : std::shared_ptr<const octomap::OcTree>(build_trailer_octree(
                     trailer, {.resolution = resolution, .wall_thickness = resolution}));
    auto built = std::make_shared<TrailerTables>(tree);
    built->key =
        octree
            ? TrailerKey{octree, octree.get(), {}}
            : TrailerKey{{}, nullptr, {trailer.width, trailer.height, trailer.depth, resolution}};
    built->serial = g_trailer_builds.fetch_add(1, std::memory_order_relaxed) + 1;
    std::lock_guard lock(mutex_);
    if (auto hit = find_locked(octree, trailer, resolution)) return hit;
    std::erase_if(entries_, [](const auto& e) { return e.expired(); });
    entries_.push_back(built);
    last_ = built;
    return built;
  }

 private:
  std::shared_ptr<const TrailerTables> find(const std::shared_ptr<const octomap::OcTree>& octree,
                                            const Trailer& trailer, double resolution) {
    std::lock_guard lock(mutex_);
    return find_locked(octree, trailer, resolution);
  }
  std::shared_ptr<const TrailerTables> find_locked(
      const std::shared_ptr<const octomap::OcTree>& octree, const Trailer& trailer,
      double resolution) const {
    for (const auto& e : entries_) {
      auto t = e.lock();
      if (t && t->key.matches(octree, trailer, resolution)) return t;
    }
    return nullptr;
  }

  std::mutex mutex_;
  std::vector<std::weak_ptr<const TrailerTables>> entries_;
  std::shared_ptr<const TrailerTables> last_;
};

TrailerCache& trailer_cache() {
  static TrailerCache cache;
  return cache;
}

// The box enclosing an object's shape as an FCL OBB: exact for a box,
// conservative for a cylinder or a sphere, its AABB for anything else.
fcl::OBBd enclosing_box(const fcl::CollisionObjectd& o) {
  fcl::OBBd box;
  const fcl::CollisionGeometryd& g = *o.collisionGeometry();
  switch (o.getNodeType()) {
    case fcl::GEOM_BOX:
      box.extent = static_cast<const fcl::Boxd&>(g).side / 2.0;
      break;
    case fcl::GEOM_CYLINDER: {
      const auto& c = static_cast<const fcl::Cylinderd&>(g);
      box.extent = Eigen::Vector3d(c.radius, c.radius, c.lz / 2.0);
      break;
    }
    case fcl::GEOM_SPHERE:
      box.extent.setConstant(static_cast<const fcl::Sphered&>(g).radius);
      break;
    default:
      box.axis.setIdentity();
      box.To = o.getAABB().center();
      box.extent = (o.getAABB().max_ - o.getAABB().min_) / 2.0;
      return box;
  }
  box.axis = o.getRotation();
  box.To = o.getTranslation();
  return box;
}

// A pair whose world-aligned boxes overlap, with their enclosing boxes.
bool collide_enclosed(const fcl::CollisionObjectd* a, const fcl::OBBd& a_box,
                      const fcl::CollisionObjectd* b, const fcl::OBBd& b_box) {
  // FCL's 15-axis box test settles most near pairs before the narrow phase,
  // and every pair of boxes (it is exact for them, up to 1e-6 m of slack).
  if (!a_box.overlap(b_box)) return false;
  if (a->getNodeType() == fcl::GEOM_BOX && b->getNodeType() == fcl::GEOM_BOX) return true;
  fcl::CollisionRequestd req;
  fcl::CollisionResultd res;
  fcl::collide(a, b, req, res);
  return res.isCollision();
}

bool collide(const fcl::CollisionObjectd* a, const fcl::CollisionObjectd* b) {
  if (!a->getAABB().overlap(b->getAABB())) return false;
  return collide_enclosed(a, enclosing_box(*a), b, enclosing_box(*b));
}

// An object moved or resized: its AABB and enclosing box follow.
void placed(fcl::CollisionObjectd& o, fcl::OBBd& box) {
  o.computeAABB();
  box = enclosing_box(o);
}

// collide() with both enclosing boxes at hand.
bool collide(const fcl::CollisionObjectd* a, const fcl::OBBd& a_box, const fcl::CollisionObjectd* b,
             const fcl::OBBd& b_box) {
  return a->getAABB().overlap(b->getAABB()) && collide_enclosed(a, a_box, b, b_box);
}

}  // namespace

struct CollisionChecker::Impl {
  const RobotModel* robot = nullptr;
  CollisionOptions options;
  std::shared_ptr<const TrailerTables> trailer;
  Trailer inner;                // the trailer's exact inner volume
  std::vector<WorldBox> boxes;  // sorted by AABB min x
  std::vector<double> box_min_x;
  double box_max_len_x = 0.0;
  std::unordered_set<std::uint32_t> ignored;
  std::vector<RobotShape> shapes;
  int robot_shape_count = 0;                    // shapes beyond this are held boxes
  std::vector<std::vector<bool>> allowed;       // [link][link]
  std::vector<std::pair<int, int>> self_pairs;  // shape index pairs checked
  // Per self pair: the shapes' epochs when last found free.
  mutable std::vector<std::pair<std::uint64_t, std::uint64_t>> pair_free_exact, pair_free_swept;
  mutable std::uint64_t next_epoch = 1;
  mutable std::vector<Eigen::Isometry3d> poses;
  mutable std::vector<double> d_self;  // per shape, from motion_bounds()
  mutable CollisionStats stats;

  void add_shape(int link, const Eigen::Isometry3d& origin,
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

  // Forget the shapes' cached "free of the world" results (the world changed;
  // self pairs do not depend on it).
  void forget_world_free() {
    for (auto& sh : shapes) sh.exact_world_free = sh.swept_world_free = false;
  }

  // Forget every cached "free" result (the world or the shapes changed).
  void invalidate() {
    for (auto& sh : shapes) {
      sh.exact_world_free = sh.swept_world_free = false;
      sh.exact_at = sh.swept_at = RobotShape::Placement::Constant(std::nan(""));
    }
    pair_free_exact.assign(self_pairs.size(), {0, 0});
    pair_free_swept.assign(self_pairs.size(), {0, 0});
  }

  void rebuild_pairs() {
    self_pairs.clear();
    for (std::size_t i = 0; i < shapes.size(); ++i) {
      for (std::size_t j = i + 1; j < shapes.size(); ++j) {
        const int a = shapes[i].link, b = shapes[j].link;
        if (a != b && !allowed[a][b])
          self_pairs.emplace_back(static_cast<int>(i), static_cast<int>(j));
      }
    }
    invalidate();
  }

  void place(const JointVector& q) const {
    robot->forward_kinematics(q, poses);
    for (auto& s : const_cast<std::vector<RobotShape>&>(shapes)) {
      const Eigen::Isometry3d pose = poses[s.link] * s.origin;
      const RobotShape::Placement at = placement(pose, Eigen::Vector3d::Zero());
      if (at == s.exact_at) continue;
      s.exact_at = at;
      s.exact_epoch = next_epoch++;
      s.exact_world_free = false;
      s.exact->setTransform(to_fcl(pose));
      placed(*s.exact, s.exact_obb);
    }
  }

  // Whether an enclosing box lies in the trailer's exact inner volume, or
  // above the floor behind its open rear: then it cannot touch the shell,
  // whose leaves round a wall off the octree's grid outwards, into the
  // trailer (a 2.35 m container's side walls by 2.5 cm each, its 2.39 m
  // ceiling by 4 cm), where boxes packed against the wall stand. Bounded by
  // the box's own corners: FCL's AABB of a rotated object is the cube around
  // its bounding sphere, which pokes a held box tilted by a degree through
  // the wall it stands against.
  bool inside_trailer(const fcl::OBBd& box) const {
    const Eigen::Vector3d half = box.axis.cwiseAbs() * box.extent;
    const Eigen::Vector3d lo = box.To - half, hi = box.To + half;
    if (lo.z() < 0.0) return false;
    if (hi.x() <= 0.0) return true;
    const double w = 0.5 * inner.width;
    return hi.x() <= inner.depth && lo.y() >= -w && hi.y() <= w && hi.z() <= inner.height;
  }

  // `box`: o's enclosing box.
  bool hits_octree(const fcl::CollisionObjectd* o, const fcl::OBBd& box) const {
    if (inside_trailer(box) || !trailer->grid.may_hit(box, o->getAABB())) return false;
    // With voxel-sized cells that was the exact test for a box; other
    // shapes, only enclosed by their box, go on to FCL's octree test.
    return (o->getNodeType() == fcl::GEOM_BOX && trailer->grid.voxel_sized()) ||
           collide(o, &trailer->object);
  }

  // World box hit by `o` (not ignored), or -1.
  long hit_box(const fcl::CollisionObjectd* o, const fcl::OBBd& box) const {
    const fcl::AABBd& a = o->getAABB();
    auto i = std::lower_bound(box_min_x.begin(), box_min_x.end(), a.min_.x() - box_max_len_x) -
             box_min_x.begin();
    for (; i < static_cast<long>(boxes.size()) &&
           box_min_x[static_cast<std::size_t>(i)] <= a.max_.x();
         ++i) {
      const WorldBox& b = boxes[static_cast<std::size_t>(i)];
      if (collide(o, box, b.obj.get(), b.obb) && ignored.count(b.id) == 0) return i;
    }
    return -1;
  }

  // The first collision of the exact shapes as placed by place(), as text
  // ("plate - box 12"), or empty.
  std::string first_hit() const {
    for (const auto& s : shapes) {
      if (hits_octree(s.exact.get(), s.exact_obb)) return s.label + " - trailer";
      const long b = hit_box(s.exact.get(), s.exact_obb);
      if (b >= 0)
        return s.label + " - box " + std::to_string(boxes[static_cast<std::size_t>(b)].id);
    }
    for (const auto& [i, j] : self_pairs) {
      if (collide(shapes[i].exact.get(), shapes[i].exact_obb, shapes[j].exact.get(),
                  shapes[j].exact_obb)) {
        return shapes[i].label + " - " + shapes[j].label;
      }
    }
    return {};
  }

  // Exact shapes as placed by place().
  bool any_hit() const {
    for (auto& s : const_cast<std::vector<RobotShape>&>(shapes)) {
      if (s.exact_world_free) continue;
      if (hits_world(s.exact.get(), s.exact_obb)) return true;
      s.exact_world_free = true;
    }
    for (std::size_t k = 0; k < self_pairs.size(); ++k) {
      const RobotShape& a = shapes[self_pairs[k].first];
      const RobotShape& b = shapes[self_pairs[k].second];
      const std::pair<std::uint64_t, std::uint64_t> epochs{a.exact_epoch, b.exact_epoch};
      if (pair_free_exact[k] == epochs) continue;
      if (collide(a.exact.get(), a.exact_obb, b.exact.get(), b.exact_obb)) return true;
      pair_free_exact[k] = epochs;
    }
    return false;
  }

  bool state_valid(const JointVector& q) const {
    ++stats.state_checks;
    if (!robot->within_limits(q, options.limit_tolerance)) return false;
    place(q);
    return !any_hit();
  }

  // Sweep of the motion a->b (a, b valid) with midpoint m: every shape
  // inflated by its travel bound over half the segment. base_x moves every
  // link alike, so it does not count for self-collision: robot pairs are
  // checked with the boxes inflated by the other joints' part only.
  // Bounds, per shape, how far any of its points moves relative to the base
  // over half a segment around `mid` (FK at mid must be in `poses`).
  // Walking the chain from the shape up: joint j moves a point by at most
  // |dq_j| times its distance from j's axis, and that distance can itself
  // grow by what the joints below j move it: D += |dq_j| (r_j + D).
  // Returns the largest bound plus the base's travel.
  double motion_bounds(const JointVector& half_step) const {
    double worst = 0.0;
    d_self.resize(shapes.size());
    const auto& links = robot->links();
    for (std::size_t i = 0; i < shapes.size(); ++i) {
      const RobotShape& s = shapes[i];
      const Eigen::Vector3d c = poses[s.link] * s.origin.translation();
      const double extent = s.half.norm();
      double d = 0.0;
      for (int k = s.link; k >= 0; k = links[k].parent_link) {
        const Link& lk = links[k];
        if (lk.joint <= kBaseX) continue;
        const double dq = std::abs(lk.mimic_multiplier * half_step[lk.joint]);
        if (dq == 0.0) continue;
        if (lk.joint_type == JointType::kPrismatic) {
          d += dq;
        } else {
          const Eigen::Vector3d axis = poses[k].linear() * lk.axis;
          const Eigen::Vector3d v = c - poses[k].translation();
          const double r = (v - v.dot(axis) * axis).norm() + extent;
          d += dq * (r + d);
        }
      }
      d_self[i] = d;
      worst = std::max(worst, d);
    }
    return worst + std::abs(half_step[kBaseX]);
  }

  bool hits_world(const fcl::CollisionObjectd* o, const fcl::OBBd& box) const {
    return hits_octree(o, box) || hit_box(o, box) >= 0;
  }

  // Stretching a shape's box along its own axes covers a base translation
  // exactly only when world x is one of them. For a tilted shape (the scoop,
  // pitched a little, just above the floor) the box in world axes covering
  // the inflated shape, stretched along x, is the tighter bound below and
  // beside it: try that before splitting the segment.
  bool aligned_sweep_free(RobotShape& s, const Eigen::Isometry3d& pose, double d,
                          const JointVector& half_step) const {
    const Eigen::Vector3d half =
        pose.linear().cwiseAbs() * s.half + Eigen::Vector3d(std::abs(half_step[kBaseX]) + d, d, d);
    s.swept_box->side = 2.0 * half;
    s.swept_box->computeLocalAABB();
    s.swept->setTransform(to_fcl(Eigen::Isometry3d(Eigen::Translation3d(pose.translation()))));
    placed(*s.swept, s.swept_obb);
    return !hits_world(s.swept.get(), s.swept_obb);
  }

  bool sweep_free(const JointVector& half_step) const {
    ++stats.sweep_checks;
    for (std::size_t i = 0; i < shapes.size(); ++i) {
      RobotShape& s = const_cast<RobotShape&>(shapes[i]);
      const double d = d_self[i];
      const Eigen::Isometry3d pose = poses[s.link] * s.origin;
      // The base translates along world x: stretch the box along that
      // direction, in the shape's frame (exact when x is one of its axes).
      const Eigen::Vector3d base_shift =
          (pose.linear().transpose() * Eigen::Vector3d::UnitX()).cwiseAbs() *
          std::abs(half_step[kBaseX]);
      const Eigen::Vector3d world_side = 2.0 * (s.half + Eigen::Vector3d::Constant(d) + base_shift);
      const Eigen::Vector3d self_side = 2.0 * (s.half + Eigen::Vector3d::Constant(d));
      const RobotShape::Placement world_at = placement(pose, world_side);
      if (!(s.swept_world_free && world_at == s.swept_world_free_at)) {
        s.swept_box->side = world_side;
        s.swept_box->computeLocalAABB();
        s.swept->setTransform(to_fcl(pose));
        placed(*s.swept, s.swept_obb);
        s.swept_at =
            RobotShape::Placement::Constant(std::nan(""));  // object now differs from swept_at
        if (hits_world(s.swept.get(), s.swept_obb) &&
            !(half_step[kBaseX] != 0.0 && aligned_sweep_free(s, pose, d, half_step))) {
          return false;
        }
        s.swept_world_free = true;
        s.swept_world_free_at = world_at;
        s.swept_at = RobotShape::Placement::Constant(std::nan(""));
      }
      const RobotShape::Placement self_at = placement(pose, self_side);
      if (self_at != s.swept_at) {
        s.swept_at = self_at;
        s.swept_epoch = next_epoch++;
        s.swept_box->side = self_side;
        s.swept_box->computeLocalAABB();
        s.swept->setTransform(to_fcl(pose));
        placed(*s.swept, s.swept_obb);
      }
    }
    for (std::size_t k = 0; k < self_pairs.size(); ++k) {
      const RobotShape& a = shapes[self_pairs[k].first];
      const RobotShape& b = shapes[self_pairs[k].second];
      const std::pair<std::uint64_t, std::uint64_t> epochs{a.swept_epoch, b.swept_epoch};
      if (pair_free_swept[k] == epochs) continue;
      if (collide(a.swept.get(), a.swept_obb, b.swept.get(), b.swept_obb)) return false;
      pair_free_swept[k] = epochs;
    }
    return true;
  }
};

CollisionChecker::CollisionChecker(const RobotModel& robot, const World& world,
                                   std::shared_ptr<const octomap::OcTree> octree,
                                   const CollisionOptions& options)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.robot = &robot;
  m.options = options;
  m.trailer = trailer_cache().get(octree, world.trailer, options.octree_resolution);
  m.inner = world.trailer;
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
      m.add_shape(static_cast<int>(l), cs.origin, std::move(geom), half, links[l].name);
    }
  }
  m.robot_shape_count = static_cast<int>(m.shapes.size());
  m.allowed.assign(links.size(), std::vector<bool>(links.size(), false));
  for (std::size_t l = 0; l < links.size(); ++l) {
    if (links[l].parent_link >= 0) {
      m.allowed[l][links[l].parent_link] = m.allowed[links[l].parent_link][l] = true;
    }
  }
  for (const auto& [a, b] : robot.allowed_collisions()) m.allowed[a][b] = m.allowed[b][a] = true;
  m.rebuild_pairs();
  set_boxes(world.boxes);
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

void CollisionChecker::set_boxes(const std::vector<Box>& boxes) {
  Impl& m = *impl_;
  // Objects are reused by id (each at most once, so repeated ids get their
  // own); a reused box takes the new size and pose, which leaves it as a
  // fresh one would be.
  std::unordered_map<std::uint32_t, std::size_t> old;
  old.reserve(m.boxes.size());
  for (std::size_t i = 0; i < m.boxes.size(); ++i) old.emplace(m.boxes[i].id, i);
  std::vector<WorldBox> next;
  next.reserve(boxes.size());
  for (const Box& b : boxes) {
    WorldBox wb;
    if (const auto it = old.find(b.id); it != old.end() && m.boxes[it->second].obj) {
      wb = std::move(m.boxes[it->second]);
      wb.shape->side = b.size;
      wb.shape->computeLocalAABB();
      wb.obj->setTransform(to_fcl(b.pose));
    } else {
      wb.id = b.id;
      wb.shape = std::make_shared<fcl::Boxd>(b.size);
      wb.obj = std::make_unique<fcl::CollisionObjectd>(wb.shape, to_fcl(b.pose));
    }
    wb.obj->computeAABB();
    wb.obb = enclosing_box(*wb.obj);
    next.push_back(std::move(wb));
  }
  // Sorted from the list as given, as in a fresh checker: boxes with equal
  // min x end up in the same order, so describe_collision() names the same.
  std::sort(next.begin(), next.end(), [](const WorldBox& a, const WorldBox& b) {
    return a.obj->getAABB().min_.x() < b.obj->getAABB().min_.x();
  });
  m.boxes = std::move(next);
  m.box_min_x.clear();
  m.box_max_len_x = 0.0;
  for (const WorldBox& b : m.boxes) {
    const fcl::AABBd& a = b.obj->getAABB();
    m.box_min_x.push_back(a.min_.x());
    m.box_max_len_x = std::max(m.box_max_len_x, a.max_.x() - a.min_.x());
  }
  m.forget_world_free();
}

void CollisionChecker::set_world(const World& world,
                                 std::shared_ptr<const octomap::OcTree> octree) {
  Impl& m = *impl_;
  if (!m.trailer->key.matches(octree, world.trailer, m.options.octree_resolution))
    m.trailer = trailer_cache().get(octree, world.trailer, m.options.octree_resolution);
  m.inner = world.trailer;
  set_boxes(world.boxes);
}

std::uint64_t CollisionChecker::trailer_serial() const {
  return impl_->trailer->serial;
}

std::uint64_t CollisionChecker::trailer_builds() {
  return g_trailer_builds.load(std::memory_order_relaxed);
}

void CollisionChecker::allow_collision(const std::string& a, const std::string& b) {
  const int ia = impl_->robot->link_index(a), ib = impl_->robot->link_index(b);
  if (ia < 0 || ib < 0)
    throw std::invalid_argument("allow_collision: unknown link '" + (ia < 0 ? a : b) + "'");
  impl_->allowed[ia][ib] = impl_->allowed[ib][ia] = true;
  impl_->rebuild_pairs();
}

void CollisionChecker::ignore_box(std::uint32_t id) {
  impl_->ignored.insert(id);
  impl_->invalidate();
}
void CollisionChecker::clear_ignored_boxes() {
  impl_->ignored.clear();
  impl_->invalidate();
}

void CollisionChecker::attach_box(const Box& box, const JointVector& q) {
  Impl& m = *impl_;
  const int plate = m.robot->plate_link();
  const Eigen::Isometry3d in_plate = m.robot->plate_pose(q).inverse() * box.pose;
  constexpr double kSlack = 0.003;  // m per side
  const Eigen::Vector3d size = (box.size.array() - 2 * kSlack).max(kSlack).matrix();
  m.add_shape(plate, in_plate, std::make_shared<fcl::Boxd>(size), size / 2.0,
              "held box " + std::to_string(box.id));
  m.ignored.insert(box.id);
  m.rebuild_pairs();
}

void CollisionChecker::detach_all() {
  impl_->shapes.resize(impl_->robot_shape_count);
  impl_->rebuild_pairs();
}

bool CollisionChecker::is_valid(const JointVector& q) const {
  return impl_->state_valid(q);
}

bool CollisionChecker::is_motion_valid(const JointVector& a, const JointVector& b,
                                       bool check_endpoints) const {
  const Impl& m = *impl_;
  if (check_endpoints && (!m.state_valid(a) || !m.state_valid(b))) return false;
  const double res = m.options.motion_resolution;
  struct Segment {
    JointVector a, b;
  };
  std::vector<Segment> todo{{a, b}};
  while (!todo.empty()) {
    const Segment s = todo.back();
    todo.pop_back();
    const JointVector half = (s.b - s.a) / 2.0;
    const JointVector mid = s.a + half;
    m.robot->forward_kinematics(mid, m.poses);
    if (m.motion_bounds(half) <= res / 2.0) {
      // Down to resolution: the checked states are at most `res` apart.
      if (!m.state_valid(mid)) return false;
      continue;
    }
    if (m.sweep_free(half)) continue;
    if (!m.state_valid(mid)) return false;
    todo.push_back({mid, s.b});
    todo.push_back({s.a, mid});
  }
  return true;
}

std::string CollisionChecker::describe_collision(const JointVector& q) const {
  const Impl& m = *impl_;
  for (int i = 0; i < kNumJoints; ++i) {
    const JointLimits& l = m.robot->limits(i);
    if (!(q[i] >= l.lower - m.options.limit_tolerance &&
          q[i] <= l.upper + m.options.limit_tolerance)) {
      return std::string(kJointNames[i]) + " beyond limits";
    }
  }
  m.place(q);
  return m.first_hit();
}

std::string CollisionChecker::base_collision(const JointVector& q) const {
  const Impl& m = *impl_;
  ++m.stats.state_checks;
  m.place(q);
  const auto& links = m.robot->links();
  for (int i = 0; i < m.robot_shape_count; ++i) {
    const RobotShape& s = m.shapes[static_cast<std::size_t>(i)];
    bool on_arm = false;
    for (int k = s.link; k >= 0 && !on_arm; k = links[k].parent_link)
      on_arm = links[k].joint >= kArm1 && links[k].joint <= kArm4;
    if (on_arm) continue;
    if (m.hits_octree(s.exact.get(), s.exact_obb)) return s.label + " - trailer";
    if (const long b = m.hit_box(s.exact.get(), s.exact_obb); b >= 0)
      return s.label + " - box " + std::to_string(m.boxes[static_cast<std::size_t>(b)].id);
  }
  return {};
}

const CollisionStats& CollisionChecker::stats() const {
  return impl_->stats;
}
void CollisionChecker::reset_stats() {
  impl_->stats = {};
}

}  // namespace plr::sim
