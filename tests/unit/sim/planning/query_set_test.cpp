// Query sets (sim/planning/query_set.cpp): recorded queries come back with
// their worlds, and a damaged file is refused naming the query.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

#include "plr/planning/query_set.hpp"

namespace plr::planning {
namespace {

using namespace plr::sim;

std::filesystem::path temp_file(const std::string& name) {
  return std::filesystem::path(::testing::TempDir()) / name;
}

TEST(QuerySet, QueriesComeBackWithTheirWorlds) {
  std::vector<std::vector<std::uint8_t>> frames;
  for (int k = 0; k < 3; ++k) {
    World w;
    for (std::uint32_t id = 1; id <= static_cast<std::uint32_t>(k + 1); ++id) {
      Box b;
      b.id = id;
      b.pose.translation() = Eigen::Vector3d(5.0 + id, 0.0, 0.2);
      w.boxes.push_back(b);
    }
    PlanQuery q;
    q.mode = PlanMode::kArmBase;
    q.start = plr::sim::home_configuration(1.0 + k);
    q.goal = JointGoal{plr::sim::home_configuration(2.0 + k), 1e-3};
    q.max_expansions = 5000;
    frames.push_back(frame_query(q, w));
  }
  const auto file = temp_file("query_set_test.bin");
  ASSERT_TRUE(save_query_set(frames, file));
  const auto set = load_query_set(file);
  ASSERT_TRUE(set) << set.error().message;
  ASSERT_EQ(set->size(), 3u);
  for (int k = 0; k < 3; ++k) {
    const RecordedQuery& r = (*set)[static_cast<std::size_t>(k)];
    EXPECT_EQ(r.query.mode, PlanMode::kArmBase);
    EXPECT_EQ(r.query.start, plr::sim::home_configuration(1.0 + k));
    EXPECT_EQ(std::get<JointGoal>(r.query.goal).q, plr::sim::home_configuration(2.0 + k));
    EXPECT_EQ(r.query.max_expansions, 5000u);
    EXPECT_EQ(r.world.boxes.size(), static_cast<std::size_t>(k + 1));
  }
}

TEST(QuerySet, ADamagedFileIsRefusedNamingTheQuery) {
  PlanQuery q;
  q.mode = PlanMode::kBaseLine;
  q.start = plr::sim::home_configuration(1.0);
  q.goal = JointGoal{plr::sim::home_configuration(2.0), 1e-3};
  const auto frame = frame_query(q, World{});
  const auto file = temp_file("query_set_damaged.bin");
  {
    std::ofstream out(file, std::ios::binary);
    out.write(reinterpret_cast<const char*>(frame.data()),
              static_cast<std::streamsize>(frame.size()));
    out.write(reinterpret_cast<const char*>(frame.data()), 10);  // the second cut short
  }
  auto set = load_query_set(file);
  ASSERT_FALSE(set);
  EXPECT_NE(set.error().message.find("query 2"), std::string::npos) << set.error().message;
  auto bad = frame;
  bad[20] ^= 0xff;  // the CRC no longer matches
  {
    std::ofstream out(file, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(bad.data()), static_cast<std::streamsize>(bad.size()));
  }
  set = load_query_set(file);
  ASSERT_FALSE(set);
  EXPECT_NE(set.error().message.find(file.string()), std::string::npos) << set.error().message;
  EXPECT_FALSE(load_query_set(temp_file("no_such_set.bin")));
}

}  // namespace
}  // namespace plr::planning
