// Boxes seen from above: the convex outline of a (possibly turned or
// tilted) box on the floor plane, and the tests the pick instantiation
// makes with it. Axis-aligned bounds of a turned box are up to 40 % wider
// than the box, and they made neighbours of every turned box look in the
// way.
#pragma once

#include <Eigen/Core>
#include <optional>
#include <vector>

#include "plr/sim/world.hpp"

namespace plr::actions {

using Polygon = std::vector<Eigen::Vector2d>;  // convex, counter-clockwise

// The box's outline from above (its 8 corners projected, their hull).
Polygon footprint(const sim::Box& box);
// The outline swept when it moves by `d` (the hull of both outlines).
Polygon swept(const Polygon& p, const Eigen::Vector2d& d);
// How far apart two outlines are along the axis that separates them best:
// > 0 apart by that much, < 0 overlapping by that much at least.
double separation(const Polygon& a, const Polygon& b);

// Of the part of `p` within `half_width` of the line through `origin`
// along `n`, the range of its distance along `n` from `origin`; nullopt
// when no part of `p` is within the band.
struct Span {
  double min = 0, max = 0;
};
std::optional<Span> span_in_band(const Polygon& p, const Eigen::Vector2d& origin,
                                 const Eigen::Vector2d& n, double half_width);

}  // namespace plr::actions
