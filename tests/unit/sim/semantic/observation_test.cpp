#include "plr/sim/observation.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace plr::sim {
namespace {

// Thresholds for these hand-made scenes of 0.4 m boxes (not the defaults,
// which are set for the generated trailers).
const ObservationParams kParams{.h_pile = 0.55,
                                .wall_depth = 0.7,
                                .min_pile_depth = 0.3,
                                .pile_mid = 0.25,
                                .pile_high = 0.4,
                                .wall_mid = 1.2,
                                .wall_high = 1.9,
                                .side_band = 1.0 / 3};

// A box resting with its bottom at z0, centred at (x, y).
Box box(std::uint32_t id, double x, double y, double z0, Eigen::Vector3d size = {0.4, 0.4, 0.4}) {
  Box b;
  b.id = id;
  b.size = size;
  b.pose = Eigen::Isometry3d::Identity();
  b.pose.translation() = Eigen::Vector3d(x, y, z0 + size.z() / 2);
  return b;
}

// A wall of `cols` x `rows` 0.4 m boxes with its front face at x_front, centred on y = y_mid.
void add_wall(World& w, double x_front, int cols, int rows, double y_mid = 0.0) {
  std::uint32_t id = static_cast<std::uint32_t>(w.boxes.size()) + 1;
  for (int c = 0; c < cols; ++c)
    for (int r = 0; r < rows; ++r)
      w.boxes.push_back(box(id++, x_front + 0.2, y_mid + (c - (cols - 1) / 2.0) * 0.4, r * 0.4));
}

TEST(Observation, EmptyTrailerHasNoObservation) {
  const World w;
  const auto a = analyse(w, kParams);
  EXPECT_FALSE(a.observation);
  EXPECT_TRUE(a.pile.empty());
  EXPECT_TRUE(a.wall.empty());
}

TEST(Observation, FullWallIsWallHigh) {
  World w;
  add_wall(w, 10.0, 6, 6);  // 2.4 m high
  const auto a = analyse(w, kParams);
  ASSERT_TRUE(a.observation);
  EXPECT_EQ(structure(*a.observation), Structure::kWall);
  EXPECT_EQ(height(*a.observation), Height::kHigh);
  EXPECT_NEAR(a.wall_height, 2.4, 1e-9);
  EXPECT_NEAR(a.wall_near_x, 10.0, 1e-9);
  EXPECT_EQ(a.first_wall.size(), 36u);
  EXPECT_TRUE(a.pile.empty());
  EXPECT_DOUBLE_EQ(a.pile_depth, 0.0);
}

TEST(Observation, WallHeightClassesFollowThresholds) {
  ObservationParams p = kParams;
  p.wall_mid = 1.0;
  p.wall_high = 2.0;
  for (const auto& [rows, expected] : std::vector<std::pair<int, Height>>{
           {2, Height::kLow}, {3, Height::kMid}, {5, Height::kHigh}}) {
    World w;
    add_wall(w, 8.0, 3, rows);
    const auto o = classify(w, p);
    ASSERT_TRUE(o);
    EXPECT_EQ(*o, make_observation(Structure::kWall, expected, Side::kCenter)) << rows << " rows";
  }
}

TEST(Observation, SideOfTheTopBox) {
  // A staircase wall: the tallest column decides the side (y > 0 is left).
  for (const auto& [y, expected] : std::vector<std::pair<double, Side>>{
           {0.8, Side::kLeft}, {0.0, Side::kCenter}, {-0.8, Side::kRight}}) {
    World w;
    add_wall(w, 9.0, 6, 3);
    w.boxes.push_back(box(100, 9.2, y, 1.2));
    w.boxes.push_back(box(101, 9.2, y, 1.6));
    const auto a = analyse(w, kParams);
    ASSERT_TRUE(a.observation);
    EXPECT_EQ(side(*a.observation), expected) << "y = " << y;
    EXPECT_EQ(a.top_box, 101u);
    EXPECT_NEAR(a.wall_height, 2.0, 1e-9);
  }
}

TEST(Observation, DeepPileInFrontOfAWallIsThePile) {
  World w;
  add_wall(w, 10.0, 6, 5);
  // Boxes lying on the floor in front of the wall, from x = 8.6 to 9.8.
  std::uint32_t id = 200;
  for (double x : {8.8, 9.2, 9.6})
    for (double y : {-0.6, 0.0, 0.6}) w.boxes.push_back(box(id++, x, y, 0.0, {0.4, 0.4, 0.3}));
  // One flat box on another one: still below h_pile.
  w.boxes.push_back(box(id++, 9.2, 0.6, 0.3, {0.4, 0.4, 0.2}));
  const auto a = analyse(w, kParams);
  ASSERT_TRUE(a.observation);
  EXPECT_EQ(a.front_pile.size(), 10u);
  EXPECT_NEAR(a.pile_near_x, 8.6, 1e-9);
  EXPECT_NEAR(a.pile_far_x, 9.8, 1e-9);
  EXPECT_NEAR(a.pile_depth, 1.2, 1e-9);
  EXPECT_NEAR(a.pile_height, 0.5, 1e-9);
  EXPECT_EQ(*a.observation, Observation::PileHighLeft);
  EXPECT_EQ(a.top_box, id - 1);
  EXPECT_NEAR(a.wall_height, 2.0, 1e-9);
}

TEST(Observation, ThinPileInFrontOfAWallLeavesTheWall) {
  World w;
  add_wall(w, 10.0, 6, 4);
  w.boxes.push_back(box(300, 9.85, 0.0, 0.0, {0.2, 0.3, 0.2}));
  ObservationParams p = kParams;
  p.min_pile_depth = 0.3;
  const auto a = analyse(w, p);
  ASSERT_TRUE(a.observation);
  EXPECT_EQ(structure(*a.observation), Structure::kWall);
  EXPECT_EQ(a.front_pile.size(), 1u);
  EXPECT_NEAR(a.pile_depth, 0.2, 1e-9);
}

TEST(Observation, HPileSplitsPileFromWall) {
  // Two columns: one 0.45 m high, one 0.8 m high.
  World w;
  w.boxes.push_back(box(1, 5.0, 0.5, 0.0, {0.4, 0.4, 0.45}));
  w.boxes.push_back(box(2, 5.0, -0.5, 0.0));
  w.boxes.push_back(box(3, 5.0, -0.5, 0.4));
  ObservationParams p = kParams;
  p.h_pile = 0.5;
  auto a = analyse(w, p);
  EXPECT_EQ(a.pile, (std::vector<std::uint32_t>{1}));
  EXPECT_EQ(a.wall, (std::vector<std::uint32_t>{2, 3}));  // the bottom box belongs to its column
  p.h_pile = 0.9;
  a = analyse(w, p);
  EXPECT_EQ(a.pile.size(), 3u);
  EXPECT_TRUE(a.wall.empty());
  ASSERT_TRUE(a.observation);
  EXPECT_EQ(structure(*a.observation), Structure::kPile);
}

TEST(Observation, SecondWallIsNotTheFirst) {
  World w;
  add_wall(w, 12.0, 6, 6);
  add_wall(w, 10.0, 6, 2);
  ObservationParams p = kParams;
  p.wall_depth = 0.7;
  const auto a = analyse(w, p);
  EXPECT_EQ(a.first_wall.size(), 12u);
  EXPECT_NEAR(a.wall_near_x, 10.0, 1e-9);
  EXPECT_NEAR(a.wall_height, 0.8, 1e-9);
  ASSERT_TRUE(a.observation);
  EXPECT_EQ(height(*a.observation), Height::kLow);
}

TEST(Observation, ABoxLyingBeforeTheWallBesideAColumnStandingFurtherOutIsInFront) {
  // A wall across the trailer, one column of it standing 1.2 m further out
  // on the left, and a box lying on the floor before the wall on the right
  // (A1 seed 6: a leaning column kept two such boxes out of every region).
  World w;
  add_wall(w, 12.0, 6, 5);
  add_wall(w, 10.8, 1, 5, 1.0);
  w.boxes.push_back(box(100, 11.75, -0.8, 0.0));
  const auto a = analyse(w, kParams);
  EXPECT_NEAR(a.wall_near_x, 10.8, 1e-9);
  EXPECT_NE(std::find(a.front_pile.begin(), a.front_pile.end(), 100u), a.front_pile.end());
  // Behind a wall box across its width, it stays out of reach.
  add_wall(w, 11.0, 1, 4, -0.8);
  const auto hidden = analyse(w, kParams);
  EXPECT_EQ(std::find(hidden.front_pile.begin(), hidden.front_pile.end(), 100u),
            hidden.front_pile.end());
}

TEST(Observation, RotatedBoxesUseTheirWorldBounds) {
  Box b = box(1, 3.0, 0.0, 0.0, {0.8, 0.2, 0.2});
  b.pose.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitY()).toRotationMatrix();
  b.pose.translation().z() = 0.4;  // standing on end: 0.8 m high
  const Bounds bb = bounds(b);
  EXPECT_NEAR(bb.z1 - bb.z0, 0.8, 1e-9);
  EXPECT_NEAR(bb.x1 - bb.x0, 0.2, 1e-9);
  World w;
  w.boxes.push_back(b);
  EXPECT_EQ(structure(*classify(w, kParams)), Structure::kWall);
}

TEST(Observation, ParamsCheck) {
  ObservationParams p = kParams;
  EXPECT_TRUE(p.check());
  p.wall_high = 1.0;
  EXPECT_EQ(p.check().error().message,
            "params 'observation.wall_mid'/'observation.wall_high': need 0 < mid < high");
  p = {};
  p.h_pile = -1;
  EXPECT_EQ(p.check().error().message, "param 'observation.h_pile': must be > 0");
}

TEST(Observation, ParamsFromJson) {
  auto p =
      ObservationParams::from_json(nlohmann::json::parse(R"({"h_pile": 0.9, "wall_high": 2})"));
  ASSERT_TRUE(p) << p.error().message;
  EXPECT_EQ(p.value().h_pile, 0.9);
  EXPECT_EQ(p.value().wall_high, 2.0);
  EXPECT_EQ(p.value().wall_mid, ObservationParams{}.wall_mid);
  EXPECT_TRUE(ObservationParams::from_json(nullptr));
  EXPECT_EQ(ObservationParams::from_json(nlohmann::json::parse(R"({"h_pil": 1})")).error().message,
            "param 'observation.h_pil': unknown");
  EXPECT_EQ(
      ObservationParams::from_json(nlohmann::json::parse(R"({"h_pile": "high"})")).error().message,
      "param 'observation.h_pile': expected a number, got \"high\"");
  EXPECT_EQ(ObservationParams::from_json(nlohmann::json::parse("[1]")).error().message,
            "param 'observation': expected a map of thresholds");
  EXPECT_EQ(
      ObservationParams::from_json(nlohmann::json::parse(R"({"pile_high": 0.1})")).error().message,
      "params 'observation.pile_mid'/'observation.pile_high': need 0 < mid < high");
}

TEST(Observation, FromMessage) {
  flatbuffers::FlatBufferBuilder fbb;
  const msg::Vec3 size(2.5, 2.7, 16.0);
  std::vector<msg::BoxState> boxes;
  boxes.emplace_back(7, msg::Vec3(0.4, 0.5, 0.6),
                     msg::Pose(msg::Vec3(9, 0.1, 0.3), msg::Quat(0, 0, 0, 1)), 0.0);
  boxes.emplace_back(8, msg::Vec3(0.4, 0.4, 0.4),
                     msg::Pose(msg::Vec3(9, 0.1, 0.8), msg::Quat(0, 0, 0, 0)), 3.0);
  fbb.Finish(msg::CreateWorldStateDirect(fbb, 0, &size, nullptr, 0.05, &boxes));
  const World w =
      world_from_message(*flatbuffers::GetRoot<msg::WorldState>(fbb.GetBufferPointer()));
  EXPECT_DOUBLE_EQ(w.trailer.width, 2.5);
  EXPECT_DOUBLE_EQ(w.trailer.height, 2.7);
  EXPECT_DOUBLE_EQ(w.trailer.depth, 16.0);
  ASSERT_EQ(w.boxes.size(), 2u);
  EXPECT_EQ(w.boxes[0].id, 7u);
  EXPECT_DOUBLE_EQ(w.boxes[0].size.y(), 0.5);
  EXPECT_TRUE(w.boxes[1].pose.linear().isIdentity());
  EXPECT_DOUBLE_EQ(w.boxes[1].mass, 3.0);
}

}  // namespace
}  // namespace plr::sim
