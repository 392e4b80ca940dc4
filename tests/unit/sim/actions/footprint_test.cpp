// Outlines of boxes from above (sim/actions/footprint.hpp), on shapes whose
// answers can be worked out by hand.
#include "footprint.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace plr::actions {
namespace {

sim::Box box(double x, double y, double yaw, double size = 0.4) {
  sim::Box b;
  b.size = {size, size, size};
  b.pose.translation() = Eigen::Vector3d(x, y, size / 2);
  b.pose.linear() = Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  return b;
}

TEST(Footprint, AnUprightBoxIsItsRectangleATurnedOneADiamond) {
  const Polygon square = footprint(box(0, 0, 0));
  ASSERT_EQ(square.size(), 4u);
  for (const auto& p : square) EXPECT_NEAR(p.cwiseAbs().maxCoeff(), 0.2, 1e-12);
  const Polygon diamond = footprint(box(0, 0, M_PI / 4));
  ASSERT_EQ(diamond.size(), 4u);
  for (const auto& p : diamond) EXPECT_NEAR(p.cwiseAbs().sum(), 0.2 * std::sqrt(2.0), 1e-12);
}

TEST(Footprint, SeparationIsTheGapOrTheOverlap) {
  EXPECT_NEAR(separation(footprint(box(0, 0, 0)), footprint(box(0.5, 0, 0))), 0.1, 1e-12);
  EXPECT_NEAR(separation(footprint(box(0, 0, 0)), footprint(box(0.3, 0, 0))), -0.1, 1e-12);
  // Flush neighbours touch.
  EXPECT_NEAR(separation(footprint(box(0, 0, 0)), footprint(box(0.4, 0, 0))), 0.0, 1e-12);
  // Turned 45 degrees, a box's corner reaches 0.283 m from its centre: at
  // 0.5 m, 0.017 m from the other's face. Their axis-aligned bounds would overlap.
  EXPECT_NEAR(separation(footprint(box(0, 0, 0)), footprint(box(0.5, 0, M_PI / 4))),
              0.3 - 0.2 * std::sqrt(2.0), 1e-12);
}

TEST(Footprint, SweptOutlineCoversBothEnds) {
  const Polygon s = swept(footprint(box(0, 0, 0)), Eigen::Vector2d(-1.0, 0));
  EXPECT_LT(separation(s, footprint(box(-0.8, 0, 0))), 0.0);
  EXPECT_GT(separation(s, footprint(box(-0.8, 0.5, 0))), 0.0);
}

TEST(Footprint, SpanInBandIsThePartWithinTheStrip) {
  const Polygon p = footprint(box(-0.5, 0.3, 0));  // x -0.7..-0.3, y 0.1..0.5
  const Eigen::Vector2d o(0, 0), n(1, 0);
  // The strip |y| <= 0.25 takes its part y 0.1..0.25: along x -0.7..-0.3.
  const auto in = span_in_band(p, o, n, 0.25);
  ASSERT_TRUE(in);
  EXPECT_NEAR(in->min, -0.7, 1e-12);
  EXPECT_NEAR(in->max, -0.3, 1e-12);
  EXPECT_FALSE(span_in_band(p, o, n, 0.05));
  // A diamond on a narrow strip's centre line: tip to tip, though no
  // corner but the tips lies in the strip.
  const auto tips = span_in_band(footprint(box(-1.0, 0.0, M_PI / 4)), o, n, 0.01);
  ASSERT_TRUE(tips);
  EXPECT_NEAR(tips->max, -1.0 + 0.2 * std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(tips->min, -1.0 - 0.2 * std::sqrt(2.0), 1e-12);
  // Off the centre line, by the strip's width: only the slopes' part.
  const auto slope = span_in_band(footprint(box(-1.0, 0.1, M_PI / 4)), o, n, 0.01);
  ASSERT_TRUE(slope);
  EXPECT_NEAR(slope->max, -1.0 + 0.2 * std::sqrt(2.0) - 0.09, 1e-12);
  EXPECT_NEAR(slope->min, -1.0 - 0.2 * std::sqrt(2.0) + 0.09, 1e-12);
}

}  // namespace
}  // namespace plr::actions
