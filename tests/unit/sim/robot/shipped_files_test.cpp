// Finding the data PLR ships (sim/robot/shipped_files.cpp).
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>

#include "plr/sim/robot_model.hpp"
#include "plr/sim/shipped_files.hpp"

namespace plr::sim {
namespace {

namespace fs = std::filesystem;

TEST(ShippedFiles, FoundNextToTheBinaryInTheBuildTree) {
  ::unsetenv("PLR_DATA_DIR");
  auto urdf = shipped_file("robots/unloader.urdf");
  ASSERT_TRUE(urdf) << urdf.error().message;
  EXPECT_TRUE(fs::is_regular_file(*urdf));
  EXPECT_EQ(urdf->filename(), "unloader.urdf");
  EXPECT_TRUE(shipped_file("robots/unloader_lattice.yaml"));
}

TEST(ShippedFiles, DataDirFromTheEnvironmentComesFirst) {
  const fs::path dir = fs::temp_directory_path() / ("plr_data_" + std::to_string(::getpid()));
  fs::create_directories(dir / "robots");
  std::ofstream(dir / "robots" / "unloader.urdf") << "<robot/>";
  ::setenv("PLR_DATA_DIR", dir.c_str(), 1);
  auto urdf = shipped_file("robots/unloader.urdf");
  ::unsetenv("PLR_DATA_DIR");
  ASSERT_TRUE(urdf) << urdf.error().message;
  EXPECT_EQ(*urdf, dir / "robots" / "unloader.urdf");
  fs::remove_all(dir);
}

TEST(ShippedFiles, MissingFileSaysWhereItLooked) {
  ::setenv("PLR_DATA_DIR", "/nonexistent/plr", 1);
  auto missing = shipped_file("robots/no_such.urdf");
  ::unsetenv("PLR_DATA_DIR");
  ASSERT_FALSE(missing);
  const std::string& why = missing.error().message;
  EXPECT_EQ(
      why.rfind("shipped file 'robots/no_such.urdf' not found (looked in /nonexistent/plr", 0), 0u)
      << why;
  EXPECT_EQ(why.find('\n'), std::string::npos);
}

TEST(ShippedFiles, TheShippedRobotLoads) {
  const auto robot = load_robot();
  ASSERT_TRUE(robot) << robot.error().message;
  EXPECT_GE(robot->plate_link(), 0);
  auto bad = load_robot("/nonexistent/robot.urdf");
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error().message, "/nonexistent/robot.urdf: cannot open file");
}

}  // namespace
}  // namespace plr::sim
