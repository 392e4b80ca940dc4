// The unloading pipeline end to end: `plr run configs/unload_sim_small.yaml`
// with the real simulator, planner, strategy H and executor, then the report.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <nlohmann/json.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace {

namespace fs = std::filesystem;

TEST(UnloadSmall, UnloadsMostBoxesWithoutHittingTheTrailer) {
  std::string pattern = (fs::temp_directory_path() / "plr_unload_small_XXXXXX").string();
  const fs::path dir = mkdtemp(pattern.data());
  const std::string cmd = std::string(PLR_BIN) + " run " + UNLOAD_SMALL_CONFIG + " --report " +
                          dir.string() + " 2> " + (dir / "stderr.txt").string();
  const int status = std::system(cmd.c_str());
  std::ifstream err(dir / "stderr.txt");
  const std::string log((std::istreambuf_iterator<char>(err)), {});
  ASSERT_TRUE(WIFEXITED(status)) << cmd << "\n" << log;
  EXPECT_EQ(WEXITSTATUS(status), 0) << log;

  std::ifstream in(dir / "report.json");
  ASSERT_TRUE(in) << "no report.json in " << dir << "\n" << log;
  const auto report = nlohmann::json::parse(in);
  const int total = report.at("boxes_total").get<int>();
  const int unloaded = report.at("boxes_unloaded").get<int>();
  EXPECT_GE(total, 25);
  EXPECT_GT(unloaded, 0) << report.dump(1);
  EXPECT_GE(unloaded, (9 * total + 9) / 10) << report.dump(1);
  EXPECT_EQ(report.at("robot_trailer_collisions").get<int>(), 0);
  for (const char* m : {"M1", "M2", "M3", "M4", "M5", "M6"})
    EXPECT_TRUE(report.at("planner_modes").contains(m)) << m;
  EXPECT_GT(report["planner_modes"]["M5"]["queries"].get<int>(), 0);
  EXPECT_GT(report["actions"]["pick"]["executions"].get<int>() +
                report["actions"]["sweep"]["executions"].get<int>(),
            0);
  EXPECT_GT(report.at("sim_time_s").get<double>(), 0.0);
  EXPECT_GT(report.at("wall_time_s").get<double>(), 0.0);
  for (const char* f : {"unloading.svg", "scene_side.svg"}) EXPECT_TRUE(fs::exists(dir / f)) << f;
  std::cerr << report.dump(1) << "\n";
  fs::remove_all(dir);
}

}  // namespace
