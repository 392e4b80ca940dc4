// Environment families. Walls are built column by column from the front wall
// backwards; piles are built by dropping boxes onto a height map.
#include <fcl/fcl.h>
#include <fmt/format.h>

#include <Eigen/QR>
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <functional>
#include <map>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>

#include "plr/sim/generators.hpp"

namespace plr::sim {
namespace {

constexpr double kGap = 0.01;           // between neighbouring columns, slabs and walls
constexpr double kSupportStep = 0.03;   // m; a pile box rests on what is this close below it
constexpr double kSupportShare = 0.75;  // of its footprint, at least
constexpr double kLandingStep = 0.01;   // m; what a pile box lands on is this close below it
constexpr double kSupportMargin =
    0.15;                       // of its size: landing support this far out from the centre
constexpr double kCell = 0.02;  // m; height map and support cells

struct WallParams {
  std::vector<double> depths;                           // box extent along x, per slab
  std::vector<double> widths;                           // column widths
  std::vector<double> heights;                          // box heights
  double stack_min, stack_max;                          // column height limits
  double mass_median, mass_spread, mass_min, mass_max;  // log-normal, clipped
  int min_slabs;
  std::size_t min_boxes;
};

struct PileParams {
  int count_min, count_max;
  double size_min, size_max;
  double flat_share;  // share of flat boxes (height halved)
  double mass_median, mass_spread, mass_min, mass_max;
  double region;      // m of trailer (from the front wall) the pile covers
  double front_bias;  // > 1 packs boxes towards the front wall
  double max_height;  // m; no box top above this (taller towers of loose boxes topple)
};

WallParams wall_params(EnvFamily family) {
  if (family == EnvFamily::kA1) {
    return {{0.40, 0.45, 0.50},
            {0.40, 0.45, 0.50, 0.55},
            {0.30, 0.35, 0.40},
            2.0,
            2.4,
            6.0,
            0.35,
            2.0,
            15.0,
            6,
            150};
  }
  return {{0.35, 0.55, 0.60},
          {0.30, 0.35, 0.60, 0.70},
          {0.25, 0.30, 0.45, 0.50},
          1.4,
          2.4,
          9.0,
          0.6,
          1.0,
          30.0,
          5,
          100};
}

PileParams pile_params(EnvFamily family) {
  if (family == EnvFamily::kB1) {
    return {70, 90, 0.25, 0.50, 0.0, 6.0, 0.4, 1.5, 15.0, 3.5, 1.5, 1.3};
  }
  return {90, 120, 0.20, 0.60, 0.3, 8.0, 0.7, 1.0, 35.0, 4.5, 1.0, 1.6};
}

double draw_mass(std::mt19937_64& rng, double median, double spread, double lo, double hi) {
  std::lognormal_distribution<double> dist(std::log(median), spread);
  return std::clamp(dist(rng), lo, hi);
}

template <typename T>
const T& pick(std::mt19937_64& rng, const std::vector<T>& values) {
  std::uniform_int_distribution<std::size_t> dist(0, values.size() - 1);
  return values[dist(rng)];
}

World make_wall(EnvFamily family, std::uint64_t seed, const Trailer& trailer) {
  const WallParams p = wall_params(family);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_real_distribution<double> jitter(-0.4 * kGap, 0.4 * kGap);
  World world;
  world.trailer = trailer;
  std::uint32_t next_id = 1;
  double front = trailer.depth - kGap;  // x of the current slab's front face
  for (int slab = 0; slab < p.min_slabs || world.boxes.size() < p.min_boxes; ++slab) {
    const double depth = pick(rng, p.depths);
    if (front - depth < 0.5 * trailer.depth) break;  // keep the rear half free
    // Columns across the width; leftover width becomes even gaps.
    std::vector<double> columns;
    double used = kGap;
    for (;;) {
      const double w = pick(rng, p.widths);
      if (used + w + kGap > trailer.width) {
        const double narrowest = *std::min_element(p.widths.begin(), p.widths.end());
        if (used + narrowest + kGap > trailer.width) break;
        continue;
      }
      columns.push_back(w);
      used += w + kGap;
    }
    const double spare = (trailer.width - used) / static_cast<double>(columns.size() + 1);
    double y = -0.5 * trailer.width + kGap + spare;
    for (const double w : columns) {
      const double limit =
          std::min(p.stack_min + (p.stack_max - p.stack_min) * unit(rng), trailer.height - 0.2);
      double z = 0.0;
      for (;;) {
        const double h = pick(rng, p.heights);
        if (z + h > limit) break;
        Box box;
        box.id = next_id++;
        box.size = {depth, w, h};
        box.pose = Eigen::Isometry3d::Identity();
        box.pose.translation() = Eigen::Vector3d(front - 0.5 * depth + jitter(rng),
                                                 y + 0.5 * w + jitter(rng), z + 0.5 * h);
        box.mass = draw_mass(rng, p.mass_median, p.mass_spread, p.mass_min, p.mass_max);
        world.boxes.push_back(box);
        z += h;
      }
      y += w + kGap + spare;
    }
    front -= depth + kGap;
  }
  return world;
}

// Height map over the trailer floor, cells of kCell metres.
class HeightMap {
 public:
  explicit HeightMap(const Trailer& t)
      : t_(t),
        nx_(static_cast<int>(std::ceil(t.depth / kCell))),
        ny_(static_cast<int>(std::ceil(t.width / kCell))),
        h_(static_cast<std::size_t>(nx_ * ny_), 0.0) {}

  template <typename F>
  void for_cells(const Box& box, F&& f) {
    // Footprint of the (yawed) box, inflated by one cell so that rasterising
    // never misses an edge.
    const Eigen::Matrix3d r = box.pose.linear();
    const Eigen::Vector2d c = box.pose.translation().head<2>();
    const Eigen::Vector2d half = 0.5 * box.size.head<2>() + Eigen::Vector2d::Constant(kCell);
    const Eigen::Vector2d ext = r.topLeftCorner<2, 2>().cwiseAbs() * half;
    const int x0 = std::max(0, static_cast<int>((c.x() - ext.x()) / kCell));
    const int x1 = std::min(nx_ - 1, static_cast<int>((c.x() + ext.x()) / kCell));
    const int y0 = std::max(0, static_cast<int>((c.y() - ext.y() + 0.5 * t_.width) / kCell));
    const int y1 = std::min(ny_ - 1, static_cast<int>((c.y() + ext.y() + 0.5 * t_.width) / kCell));
    for (int i = x0; i <= x1; ++i) {
      for (int j = y0; j <= y1; ++j) {
        const Eigen::Vector2d cell((i + 0.5) * kCell, (j + 0.5) * kCell - 0.5 * t_.width);
        const Eigen::Vector2d local = r.topLeftCorner<2, 2>().transpose() * (cell - c);
        if (std::abs(local.x()) <= half.x() && std::abs(local.y()) <= half.y()) {
          f(h_[static_cast<std::size_t>(i * ny_ + j)], local);
        }
      }
    }
  }

 private:
  Trailer t_;
  int nx_, ny_;
  std::vector<double> h_;
};

// What one box rests on: cells of its bottom face (box frame) and, per cell,
// the box below (index) or the floor (-1).
struct Support {
  std::vector<Eigen::Vector2d> cells;
  std::vector<int> by;
};

Eigen::Matrix2d yaw_of(const Box& box) {
  return box.pose.linear().topLeftCorner<2, 2>();
}

// Which of the four quadrants around a point the offsets added reach: a
// weight is over its support when that support reaches all four.
class Quadrants {
 public:
  void add(const Eigen::Vector2d& d) {
    seen_[static_cast<std::size_t>((d.x() > 0.0) + 2 * (d.y() > 0.0))] = true;
  }
  bool all() const {
    return std::all_of(seen_.begin(), seen_.end(), [](bool q) { return q; });
  }

 private:
  std::array<bool, 4> seen_{};
};

// Cells of `box`'s bottom face that rest on the floor or on the top of a box
// in `others` (indices `candidates`) within kLandingStep below it (plus a few
// mm: piles hover before their drop, settled boxes sink a little).
Support find_support(const Box& box, const std::vector<Box>& others,
                     const std::vector<int>& candidates) {
  constexpr double kSlack = 0.005;
  Support s;
  const Eigen::Vector2d half = 0.5 * box.size.head<2>();
  const double bottom = box.pose.translation().z() - 0.5 * box.size.z();
  const int nx = std::max(2, static_cast<int>(std::lround(box.size.x() / kCell)));
  const int ny = std::max(2, static_cast<int>(std::lround(box.size.y() / kCell)));
  const Eigen::Matrix2d r = yaw_of(box);
  const Eigen::Vector2d c = box.pose.translation().head<2>();
  for (int i = 0; i < nx; ++i) {
    for (int j = 0; j < ny; ++j) {
      const Eigen::Vector2d local((i + 0.5) / nx * box.size.x() - half.x(),
                                  (j + 0.5) / ny * box.size.y() - half.y());
      int by = -2;
      if (bottom < kLandingStep + kSlack) {
        by = -1;
      } else {
        const Eigen::Vector2d p = c + r * local;
        double best = -1.0;
        for (const int k : candidates) {
          const Box& o = others[static_cast<std::size_t>(k)];
          const double top = o.pose.translation().z() + 0.5 * o.size.z();
          if (top < bottom - kLandingStep - kSlack || top > bottom + kSlack || top <= best)
            continue;
          const Eigen::Vector2d q = yaw_of(o).transpose() * (p - o.pose.translation().head<2>());
          if ((q.cwiseAbs().array() <= 0.5 * o.size.head<2>().array()).all()) {
            best = top;
            by = k;
          }
        }
      }
      if (by == -2) continue;
      s.cells.push_back(local);
      s.by.push_back(by);
    }
  }
  return s;
}

// Statics of upright boxes: each box carries its weight plus what rests on
// it, and that load's line of action (its resultant) must pass through the
// box's support with a margin, the same one a single box's centre needs.
// Otherwise the box (and all it carries) tips over: a column whose boxes each
// sit on the one below can still lean over as a whole. A box on several
// supports passes its load to them by the lever rule (the split closest to
// one by contact area that puts the resultant where it is). Boxes are
// processed top down (`order`: descending top height); returns the indices
// of `check` (or of all, if empty) whose resultant falls outside.
std::vector<int> tipping(const std::vector<Box>& boxes, const std::vector<Support>& supports,
                         const std::vector<int>& order, std::vector<bool> check) {
  const std::size_t n = boxes.size();
  const bool all = check.empty();
  check.resize(n, all);
  std::vector<double> load(n);
  std::vector<Eigen::Vector2d> moment(n);  // load-weighted xy of the line of action
  for (std::size_t i = 0; i < n; ++i) {
    load[i] = boxes[i].mass;
    moment[i] = boxes[i].mass * boxes[i].pose.translation().head<2>();
  }
  std::vector<int> failed;
  for (const int bi : order) {
    const auto i = static_cast<std::size_t>(bi);
    const Box& box = boxes[i];
    const Support& s = supports[i];
    const Eigen::Matrix2d r = yaw_of(box);
    const Eigen::Vector2d x = moment[i] / load[i];
    if (check[i]) {
      const Eigen::Vector2d at = r.transpose() * (x - box.pose.translation().head<2>());
      const Eigen::Array2d margin = 2.0 * kSupportMargin * 0.5 * box.size.head<2>().array();
      Quadrants quadrants;
      for (const Eigen::Vector2d& cell : s.cells) {
        const Eigen::Vector2d d = cell - at;
        if ((d.cwiseAbs().array() > margin).all()) quadrants.add(d);
      }
      if (!quadrants.all()) failed.push_back(bi);
    }
    // Contact centroid and area per support.
    std::vector<int> by;
    std::vector<Eigen::Vector2d> centroid;
    std::vector<double> area;
    for (std::size_t c = 0; c < s.cells.size(); ++c) {
      const auto k =
          static_cast<std::size_t>(std::find(by.begin(), by.end(), s.by[c]) - by.begin());
      if (k == by.size()) {
        by.push_back(s.by[c]);
        centroid.emplace_back(Eigen::Vector2d::Zero());
        area.push_back(0.0);
      }
      centroid[k] += box.pose.translation().head<2>() + r * s.cells[c];
      area[k] += 1.0;
    }
    if (by.empty()) continue;
    const double total = static_cast<double>(s.cells.size());
    Eigen::VectorXd w0(static_cast<Eigen::Index>(by.size()));
    Eigen::MatrixXd a(3, static_cast<Eigen::Index>(by.size()));
    for (std::size_t k = 0; k < by.size(); ++k) {
      centroid[k] /= area[k];
      w0[static_cast<Eigen::Index>(k)] = area[k] / total;
      a.col(static_cast<Eigen::Index>(k)) << 1.0, centroid[k];
    }
    // Shares w closest to w0 (weighted by w0) with sum 1 and sum w c = x.
    const Eigen::Vector3d target(1.0, x.x(), x.y());
    const Eigen::MatrixXd aw = a * w0.asDiagonal();
    const Eigen::Vector3d lambda =
        (aw * a.transpose()).completeOrthogonalDecomposition().solve(target - a * w0);
    Eigen::VectorXd w = (w0.array() * (1.0 + (a.transpose() * lambda).array())).max(0.0);
    w /= w.sum();
    Eigen::Vector2d through = Eigen::Vector2d::Zero();
    for (std::size_t k = 0; k < by.size(); ++k)
      through += w[static_cast<Eigen::Index>(k)] * centroid[k];
    const Eigen::Vector2d shift = x - through;  // keeps the moment exact when x is off the hull
    for (std::size_t k = 0; k < by.size(); ++k) {
      if (by[k] < 0) continue;
      const auto j = static_cast<std::size_t>(by[k]);
      const double f = w[static_cast<Eigen::Index>(k)] * load[i];
      load[j] += f;
      moment[j] += f * (centroid[k] + shift);
      check[j] = check[j] || check[i];
    }
  }
  return failed;
}

// Boxes ordered top down.
std::vector<int> top_down(const std::vector<Box>& boxes) {
  std::vector<int> order(boxes.size());
  std::iota(order.begin(), order.end(), 0);
  const auto top = [&](int i) {
    const Box& b = boxes[static_cast<std::size_t>(i)];
    return b.pose.translation().z() + 0.5 * b.size.z();
  };
  std::stable_sort(order.begin(), order.end(), [&](int x, int y) { return top(x) > top(y); });
  return order;
}

World make_pile(EnvFamily family, std::uint64_t seed, const Trailer& trailer) {
  const PileParams p = pile_params(family);
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<int> count_dist(p.count_min, p.count_max);
  World world;
  world.trailer = trailer;
  HeightMap map(trailer);
  std::vector<fcl::Boxd> shapes;
  std::vector<Support> supports;
  shapes.reserve(static_cast<std::size_t>(p.count_max));
  const int count = count_dist(rng);
  fcl::CollisionRequestd request;
  for (int n = 0, tries = 0; n < count && tries < 60 * count; ++tries) {
    Box box;
    box.id = static_cast<std::uint32_t>(world.boxes.size() + 1);
    for (int k = 0; k < 3; ++k) box.size[k] = p.size_min + (p.size_max - p.size_min) * unit(rng);
    if (unit(rng) < p.flat_share) box.size.z() *= 0.5;
    // A dropped box lands on a large face: never stand it on its smallest one.
    auto& narrow = box.size.x() < box.size.y() ? box.size.x() : box.size.y();
    if (box.size.z() > narrow) std::swap(box.size.z(), narrow);
    box.mass = draw_mass(rng, p.mass_median, p.mass_spread, p.mass_min, p.mass_max);
    const double yaw = M_PI * (unit(rng) - 0.5);
    box.pose = Eigen::Isometry3d::Identity();
    box.pose.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    const Eigen::Vector3d ext = box.pose.linear().cwiseAbs() * (0.5 * box.size);
    const double x_hi = trailer.depth - ext.x() - kGap;
    const double x_lo = std::max(trailer.depth - p.region + ext.x(), 0.5 * trailer.depth);
    const double y_lim = 0.5 * trailer.width - ext.y() - kGap;
    if (x_hi <= x_lo || y_lim <= 0.0) continue;
    const double x = x_hi - (x_hi - x_lo) * std::pow(unit(rng), p.front_bias);
    const double y = y_lim * (2.0 * unit(rng) - 1.0);
    box.pose.translation() = Eigen::Vector3d(x, y, 0.0);
    double base = 0.0;
    map.for_cells(box, [&](double& h, const Eigen::Vector2d&) { base = std::max(base, h); });
    // Only keep drops whose centre is supported near the landing height:
    // boxes balanced on one corner would tumble for seconds.
    Box core = box;
    core.size.head<2>() *= 0.3;
    double centre = 0.0;
    map.for_cells(core, [&](double& h, const Eigen::Vector2d&) { centre = std::max(centre, h); });
    if (centre < base - 0.03) continue;
    // ... and whose footprint rests mostly at that height: a box on a ridge
    // or a corner topples, and a toppling box brings its neighbours down.
    // What it lands on (the cells near the top) must also reach into all four
    // quadrants around its centre, so its centre of mass lies inside that
    // support with a margin: a box over a slope or a gap tips after the drop.
    int cells = 0, supported = 0;
    Quadrants quadrants;
    const Eigen::Array2d half = 0.5 * box.size.head<2>().array();
    map.for_cells(box, [&](double& h, const Eigen::Vector2d& local) {
      ++cells;
      supported += h > base - kSupportStep;
      const Eigen::Array2d d = local.cwiseAbs().array();
      if (h > base - kLandingStep && (d > 2.0 * kSupportMargin * half).all() && (d <= half).all())
        quadrants.add(local);
    });
    if (supported < kSupportShare * cells || !quadrants.all()) continue;
    // Hover a little above the support so the drop starts free of contact.
    double z = base + 0.5 * box.size.z() + 0.003;
    const fcl::Boxd shape(box.size);
    for (bool clear = false; !clear;) {
      box.pose.translation().z() = z;
      clear = true;
      for (std::size_t i = 0; i < world.boxes.size() && clear; ++i) {
        fcl::CollisionResultd result;
        clear =
            fcl::collide(&shape, box.pose, &shapes[i], world.boxes[i].pose, request, result) == 0;
      }
      if (!clear) z += 0.01;
    }
    if (z + 0.5 * box.size.z() > std::min(trailer.height - 0.1, p.max_height)) continue;
    // The pile must stand with this box on it: every box below it, carrying
    // its share of the new load, still has its load over its support.
    std::vector<int> near;
    const Eigen::Vector3d e = box.pose.linear().cwiseAbs() * (0.5 * box.size);
    for (std::size_t i = 0; i < world.boxes.size(); ++i) {
      const Box& o = world.boxes[i];
      const Eigen::Vector3d oe = o.pose.linear().cwiseAbs() * (0.5 * o.size);
      const Eigen::Vector3d d = (o.pose.translation() - box.pose.translation()).cwiseAbs();
      if ((d.head<2>().array() < (e + oe).head<2>().array()).all())
        near.push_back(static_cast<int>(i));
    }
    supports.push_back(find_support(box, world.boxes, near));
    world.boxes.push_back(box);
    std::vector<bool> check(world.boxes.size(), false);
    check.back() = true;
    if (!tipping(world.boxes, supports, top_down(world.boxes), check).empty()) {
      world.boxes.pop_back();
      supports.pop_back();
      continue;
    }
    const double top = z + 0.5 * box.size.z();
    map.for_cells(box, [&](double& h, const Eigen::Vector2d&) { h = std::max(h, top); });
    shapes.emplace_back(box.size);
    ++n;
  }
  return world;
}

// Family C. A wall of A1's or A2's boxes, then what happens to its front:
// each of three changes with even odds, at least one of them.
//  - stair-stepped: the front slab's columns lose a random number of top
//    boxes (some columns all of them), as a partly unloaded wall;
//  - fallen: a few of the front slab's top boxes lie on the floor before it,
//    on their largest face, at any yaw;
//  - loose layer: flat boxes on the floor before the wall.
// Floor boxes are placed clear of each other and of the wall; the physics
// settles them (make_environment).
double near_x(const Box& b) {
  return b.pose.translation().x() - (b.pose.linear().cwiseAbs() * (0.5 * b.size)).x();
}

World make_mixed(std::uint64_t seed, const Trailer& given) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  Trailer trailer = given;
  const double kind = unit(rng);
  if (kind < 1.0 / 3.0) {
    trailer.width = 2.35;  // 40 ft ISO container inside
    trailer.height = 2.39;
  } else if (kind < 2.0 / 3.0) {
    trailer.width = 2.35;  // 45 ft high cube
    trailer.height = 2.69;
  }
  const EnvFamily walls = unit(rng) < 0.5 ? EnvFamily::kA1 : EnvFamily::kA2;
  World world = make_wall(walls, rng(), trailer);
  bool stair = unit(rng) < 0.5, fallen = unit(rng) < 0.5, loose = unit(rng) < 0.5;
  if (!stair && !fallen && !loose) (unit(rng) < 0.5 ? fallen : loose) = true;

  double front = trailer.depth;
  for (const Box& b : world.boxes) front = std::min(front, near_x(b));
  // The front slab's columns, each bottom up (make_wall stacks them so).
  std::map<long, std::vector<std::size_t>> columns;
  for (std::size_t i = 0; i < world.boxes.size(); ++i)
    if (near_x(world.boxes[i]) < front + kGap)
      columns[std::lround(world.boxes[i].pose.translation().y() * 100)].push_back(i);
  std::vector<bool> removed(world.boxes.size(), false);
  std::vector<Box> down;  // fallen boxes, to lay on the floor
  for (auto& [y, column] : columns) {
    std::size_t keep = column.size();
    if (stair) {
      keep =
          unit(rng) < 0.2 ? 0 : std::uniform_int_distribution<std::size_t>(1, column.size())(rng);
    }
    for (std::size_t k = keep; k < column.size(); ++k) removed[column[k]] = true;
    if (fallen && keep > 1 && unit(rng) < 0.4) {
      removed[column[keep - 1]] = true;
      down.push_back(world.boxes[column[keep - 1]]);
    }
  }
  std::vector<Box> kept;
  for (std::size_t i = 0; i < world.boxes.size(); ++i)
    if (!removed[i]) kept.push_back(world.boxes[i]);
  world.boxes = std::move(kept);
  if (loose) {
    const int n = std::uniform_int_distribution<int>(4, 12)(rng);
    for (int k = 0; k < n; ++k) {
      Box b;
      b.size = {0.3 + 0.3 * unit(rng), 0.3 + 0.3 * unit(rng), 0.15 + 0.15 * unit(rng)};
      down.push_back(b);
    }
  }
  // On the floor before the wall, on the largest face, clear of the rest.
  fcl::CollisionRequestd request;
  const double region = 1.6;
  for (Box b : down) {
    std::sort(b.size.data(), b.size.data() + 3, std::greater<>());
    const double yaw = M_PI * (unit(rng) - 0.5);
    b.pose = Eigen::Isometry3d::Identity();
    b.pose.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    const Eigen::Vector3d ext = b.pose.linear().cwiseAbs() * (0.5 * b.size);
    const double y_lim = 0.5 * trailer.width - ext.y() - kGap;
    const fcl::Boxd shape(b.size + Eigen::Vector3d::Constant(2 * kGap));
    for (int tries = 0; tries < 50 && y_lim > 0; ++tries) {
      // Never in the rear half: that is the robot's.
      const double x_hi = front - kGap - ext.x();
      const double x_lo = std::max(x_hi - region, 0.5 * trailer.depth + ext.x());
      b.pose.translation() = Eigen::Vector3d(x_hi - (x_hi - x_lo) * unit(rng),
                                             y_lim * (2.0 * unit(rng) - 1.0), 0.5 * b.size.z());
      const bool clear = std::none_of(world.boxes.begin(), world.boxes.end(), [&](const Box& o) {
        fcl::CollisionResultd result;
        const fcl::Boxd other(o.size);
        return fcl::collide(&shape, b.pose, &other, o.pose, request, result) > 0;
      });
      if (clear) {
        world.boxes.push_back(b);
        break;
      }
    }
  }
  // One prior for the whole family (mass_prior(kC)): A2's, the wider one.
  const WallParams prior = wall_params(EnvFamily::kA2);
  std::uint32_t id = 1;
  for (Box& b : world.boxes) {
    b.id = id++;
    b.mass = draw_mass(rng, prior.mass_median, prior.mass_spread, prior.mass_min, prior.mass_max);
  }
  return world;
}

// Family D and make_carton_wall: the columns of the lower layers, then the
// loose layers carton by carton, each kept only where it overlaps nothing
// and the wall under it still stands.
World carton_wall_world(const CartonWall& spec, std::uint64_t seed, const Trailer& trailer) {
  constexpr double kShift = 0.2;  // of the carton: how far a loose carton is off its place
  constexpr double kTurn = 0.25;  // rad
  constexpr int kTries = 20;      // places tried per loose carton
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_real_distribution<double> jitter(-0.4 * kGap, 0.4 * kGap);
  const double top = trailer.height - spec.headroom;
  const int layers = static_cast<int>(std::floor(top / spec.carton + 1e-9));
  const double h = top / layers;
  const int fit = static_cast<int>(std::floor((trailer.width - kGap) / (spec.carton + kGap)));
  const int columns = spec.columns > 0 ? spec.columns : fit;
  // Centred columns; the width they leave spreads evenly between them when
  // they fill the trailer, and stays at the sides when fewer are asked for.
  const double spare = spec.columns > 0 ? 0.0
                                        : (trailer.width - kGap - columns * (spec.carton + kGap)) /
                                              static_cast<double>(columns + 1);
  const double pitch = spec.carton + kGap + spare;
  const double y0 = -0.5 * (columns - 1) * pitch;
  const auto mass = [&] {
    return draw_mass(rng, spec.mass.median, spec.mass.spread, spec.mass.min, spec.mass.max);
  };
  World world;
  world.trailer = trailer;
  const auto place = [&](int slab, int column, int layer) {
    Box box;
    box.id = static_cast<std::uint32_t>(world.boxes.size() + 1);
    box.size = {spec.carton, spec.carton, h};
    box.pose = Eigen::Isometry3d::Identity();
    box.pose.translation() =
        Eigen::Vector3d(trailer.depth - kGap - (slab + 0.5) * spec.carton - slab * kGap,
                        y0 + column * pitch, (layer + 0.5) * h);
    return box;
  };
  const int fixed = layers - spec.loose_layers;
  for (int slab = 0; slab < spec.slabs; ++slab)
    for (int column = 0; column < columns; ++column)
      for (int layer = 0; layer < fixed; ++layer) {
        Box box = place(slab, column, layer);
        box.pose.translation() += Eigen::Vector3d(jitter(rng), jitter(rng), 0.0);
        box.mass = mass();
        world.boxes.push_back(box);
      }
  std::vector<int> all(world.boxes.size());
  std::iota(all.begin(), all.end(), 0);
  std::vector<Support> supports;
  for (const Box& box : world.boxes) supports.push_back(find_support(box, world.boxes, all));
  // Loose cartons: overlap is tested on footprints grown by the gap and
  // heights shrunk by it, so that neighbours keep a gap and the layer
  // below does not count.
  const fcl::Boxd shape(Eigen::Vector3d(spec.carton + kGap, spec.carton + kGap, h - kGap));
  fcl::CollisionRequestd request;
  for (int layer = fixed; layer < layers; ++layer)
    for (int slab = 0; slab < spec.slabs; ++slab)
      for (int column = 0; column < columns; ++column) {
        const Box home = place(slab, column, layer);
        const double m = mass();
        for (int t = 0; t < kTries; ++t) {
          Box box = home;
          box.mass = m;
          box.pose.linear() =
              Eigen::AngleAxisd(kTurn * (2 * unit(rng) - 1), Eigen::Vector3d::UnitZ())
                  .toRotationMatrix();
          box.pose.translation() += Eigen::Vector3d(kShift * spec.carton * (2 * unit(rng) - 1),
                                                    kShift * spec.carton * (2 * unit(rng) - 1), 0);
          const Eigen::Vector3d e = box.pose.linear().cwiseAbs() * (0.5 * box.size);
          const Eigen::Vector3d c = box.pose.translation();
          if (c.x() + e.x() > trailer.depth - kGap ||
              std::abs(c.y()) + e.y() > 0.5 * trailer.width - kGap)
            continue;
          const bool overlaps =
              std::any_of(world.boxes.begin(), world.boxes.end(), [&](const Box& o) {
                fcl::CollisionResultd result;
                return fcl::collide(&shape, box.pose, &shape, o.pose, request, result) > 0;
              });
          if (overlaps) continue;
          world.boxes.push_back(box);
          all.push_back(static_cast<int>(all.size()));
          supports.push_back(find_support(box, world.boxes, all));
          std::vector<bool> check(world.boxes.size(), false);
          check.back() = true;
          if (tipping(world.boxes, supports, top_down(world.boxes), check).empty()) break;
          world.boxes.pop_back();
          all.pop_back();
          supports.pop_back();
        }
      }
  return world;
}

}  // namespace

std::string_view to_string(EnvFamily family) {
  switch (family) {
    case EnvFamily::kA1:
      return "A1";
    case EnvFamily::kA2:
      return "A2";
    case EnvFamily::kB1:
      return "B1";
    case EnvFamily::kB2:
      return "B2";
    case EnvFamily::kC:
      return "C";
    case EnvFamily::kD1:
      return "D1";
    case EnvFamily::kD2:
      return "D2";
    case EnvFamily::kD3:
      return "D3";
  }
  return "?";
}

std::vector<EnvFamily> all_env_families() {
  return {EnvFamily::kA1, EnvFamily::kA2, EnvFamily::kB1, EnvFamily::kB2,
          EnvFamily::kC,  EnvFamily::kD1, EnvFamily::kD2, EnvFamily::kD3};
}

std::string env_family_names() {
  const std::vector<EnvFamily> all = all_env_families();
  std::string names;
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (i > 0) names += i + 1 == all.size() ? " or " : ", ";
    names += to_string(all[i]);
  }
  return names;
}

std::optional<EnvFamily> parse_env_family(std::string_view name) {
  for (EnvFamily f : all_env_families()) {
    const std::string_view s = to_string(f);
    if (name.size() == s.size() &&
        std::equal(name.begin(), name.end(), s.begin(),
                   [](char a, char b) { return std::toupper(static_cast<unsigned char>(a)) == b; }))
      return f;
  }
  return std::nullopt;
}

std::vector<std::uint32_t> toppling_boxes(const World& world) {
  std::vector<int> all(world.boxes.size());
  std::iota(all.begin(), all.end(), 0);
  std::vector<Support> supports;
  for (const Box& box : world.boxes) supports.push_back(find_support(box, world.boxes, all));
  std::vector<std::uint32_t> ids;
  for (const int i : tipping(world.boxes, supports, top_down(world.boxes), {})) {
    ids.push_back(world.boxes[static_cast<std::size_t>(i)].id);
  }
  std::sort(ids.begin(), ids.end());
  return ids;
}

MassPrior mass_prior(EnvFamily family) {
  if (family == EnvFamily::kD1 || family == EnvFamily::kD2 || family == EnvFamily::kD3)
    return carton_wall(family).mass;
  // C draws every mass from A2's prior (make_mixed).
  if (family == EnvFamily::kC) family = EnvFamily::kA2;
  if (family == EnvFamily::kA1 || family == EnvFamily::kA2) {
    const WallParams p = wall_params(family);
    return {p.mass_median, p.mass_spread, p.mass_min, p.mass_max};
  }
  const PileParams p = pile_params(family);
  return {p.mass_median, p.mass_spread, p.mass_min, p.mass_max};
}

World sample_masses(const World& visible, EnvFamily family, std::uint64_t seed) {
  const MassPrior prior = mass_prior(family);
  World w = visible;
  for (Box& b : w.boxes) {
    if (b.mass > 0.0) continue;
    // One generator per (seed, id), its seed mixed by splitmix64 so that
    // neighbouring seeds and ids give unrelated streams.
    std::uint64_t z = seed + 0x9e3779b97f4a7c15ULL * (static_cast<std::uint64_t>(b.id) + 1);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    std::mt19937_64 rng(z ^ (z >> 31));
    b.mass = draw_mass(rng, prior.median, prior.spread, prior.min, prior.max);
  }
  return w;
}

plr::Status set_masses(World& world, const std::vector<std::pair<std::uint32_t, double>>& masses) {
  std::vector<std::size_t> index;
  index.reserve(masses.size());
  for (const auto& [id, mass] : masses) {
    const auto it = std::find_if(world.boxes.begin(), world.boxes.end(),
                                 [id = id](const Box& b) { return b.id == id; });
    if (it == world.boxes.end()) {
      return plr::make_error(PLR_ERR_INVALID, "set_masses: no box " + std::to_string(id));
    }
    if (!std::isfinite(mass) || !(mass > 0.0)) {
      return plr::make_error(PLR_ERR_INVALID, "set_masses: box " + std::to_string(id) +
                                                  ": mass must be finite and > 0");
    }
    index.push_back(static_cast<std::size_t>(it - world.boxes.begin()));
  }
  for (std::size_t k = 0; k < masses.size(); ++k) world.boxes[index[k]].mass = masses[k].second;
  return {};
}

World generate_world(EnvFamily family, std::uint64_t seed, const Trailer& trailer) {
  if (trailer.width < 1.0 || trailer.height < 1.0 || trailer.depth < 4.0) {
    throw std::invalid_argument("generate_world: trailer smaller than 1 x 1 x 4 m");
  }
  if (family == EnvFamily::kA1 || family == EnvFamily::kA2) {
    return make_wall(family, seed, trailer);
  }
  if (family == EnvFamily::kC) return make_mixed(seed, trailer);
  if (family == EnvFamily::kB1 || family == EnvFamily::kB2) return make_pile(family, seed, trailer);
  auto wall = make_carton_wall(carton_wall(family), seed, trailer);
  if (!wall) throw std::invalid_argument("generate_world: " + wall.error().message);
  return std::move(*wall);
}

CartonWall carton_wall(EnvFamily family) {
  CartonWall wall;
  if (family == EnvFamily::kD2) wall.mass = {18.0, 0.25, 10.0, 28.0};  // heavy cartons
  if (family == EnvFamily::kD3) wall.loose_layers = 2;
  return wall;
}

plr::Status check(const CartonWall& w, const Trailer& t) {
  const auto bad = [](const std::string& what) {
    return plr::make_error(PLR_ERR_INVALID, "carton wall: " + what);
  };
  if (!(w.carton >= 0.1 && w.carton <= 1.5))
    return bad(fmt::format("carton {} m: must be within 0.1-1.5 m", w.carton));
  if (!(w.headroom >= 0 && t.height - w.headroom >= w.carton))
    return bad(
        fmt::format("headroom {} m: must be >= 0 and leave a {} m carton under the {} m ceiling",
                    w.headroom, w.carton, t.height));
  if (w.slabs < 1 || w.slabs * (w.carton + kGap) > 0.5 * t.depth)
    return bad(
        fmt::format("slabs {}: must be >= 1 and fill at most the front half of a {} m trailer",
                    w.slabs, t.depth));
  const int fit = static_cast<int>(std::floor((t.width - kGap) / (w.carton + kGap)));
  if (w.columns < 0 || w.columns > fit || fit < 1)
    return bad(fmt::format("columns {}: a {} m trailer holds 1-{} columns of {} m cartons",
                           w.columns, t.width, fit, w.carton));
  const int layers = static_cast<int>(std::floor((t.height - w.headroom) / w.carton + 1e-9));
  if (w.loose_layers < 0 || w.loose_layers > layers)
    return bad(fmt::format("loose_layers {}: must be within 0-{} (the wall's layers)",
                           w.loose_layers, layers));
  const MassPrior& m = w.mass;
  if (!(m.min > 0 && m.min <= m.median && m.median <= m.max && m.spread >= 0))
    return bad("mass: needs 0 < min <= median <= max and spread >= 0");
  return {};
}

plr::Expected<World> make_carton_wall(const CartonWall& wall, std::uint64_t seed,
                                      const Trailer& trailer) {
  if (auto ok = check(wall, trailer); !ok) return ok.error();
  return carton_wall_world(wall, seed, trailer);
}

std::uint64_t particle_seed(std::uint64_t seed, int particle) {
  std::uint64_t z = seed * 0x9e3779b97f4a7c15ull + static_cast<std::uint64_t>(particle) + 1;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

}  // namespace plr::sim
