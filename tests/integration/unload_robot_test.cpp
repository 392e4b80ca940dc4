// The robot pipeline end to end: `plr run configs/unload_robot.yaml`, where
// the driver streams every trajectory to the controller emulator (its own
// process) over DDS with ROS 2's types, and the simulator only follows what
// the controller reported. It must unload the same boxes as the
// simulator-only pipeline (configs/unload_sim_small.yaml) on the same world.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <string>

namespace {

namespace fs = std::filesystem;

struct Unloading {
  fs::path dir;
  std::string log;
  nlohmann::json report;
  std::set<int> boxes_left;
};

std::string read(const fs::path& file) {
  std::ifstream in(file);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

Unloading unload(const char* config, const std::string& tag, std::vector<std::string> overrides) {
  Unloading run;
  std::string pattern = (fs::temp_directory_path() / ("plr_unload_robot_XXXXXX")).string();
  run.dir = mkdtemp(pattern.data());
  const std::string err = (run.dir / "log.txt").string();
  const std::string report = (run.dir / "report").string();
  // Names of their own: two runs of one pipeline name cannot run at once.
  overrides.push_back("pipeline=" + tag + "_" + std::to_string(::getpid()));
  std::vector<std::string> args = {PLR_BIN, "run", config, "--report", report};
  for (const auto& o : overrides) {
    args.push_back("--set");
    args.push_back(o);
  }
  const pid_t pid = fork();
  if (pid == 0) {
    const int fd = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    dup2(fd, 1);
    dup2(fd, 2);
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    execv(PLR_BIN, argv.data());
    _exit(127);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  run.log = read(err);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << run.log;
  std::ifstream in(run.dir / "report" / "report.json");
  EXPECT_TRUE(in) << "no report.json\n" << run.log;
  if (in) run.report = nlohmann::json::parse(in);
  const std::string world = read(run.dir / "report" / "final_world.yaml");
  static const std::regex id(R"(\{id: *(\d+))");
  for (auto it = std::sregex_iterator(world.begin(), world.end(), id); it != std::sregex_iterator();
       ++it)
    run.boxes_left.insert(std::stoi((*it)[1]));
  return run;
}

TEST(UnloadRobot, UnloadsTheSameBoxesThroughTheEmulatedControllerAsTheSimulator) {
  // A domain of its own, so a run of this test elsewhere on the machine does not meet it.
  const std::string domain = std::to_string(150 + ::getpid() % 80);
  const Unloading robot = unload(
      UNLOAD_ROBOT_CONFIG, "unload_robot",
      {"nodes.driver.params.domain_id=" + domain, "nodes.controller.params.domain_id=" + domain});
  const Unloading sim = unload(UNLOAD_SMALL_CONFIG, "unload_small", {});
  ASSERT_FALSE(robot.report.is_null());
  ASSERT_FALSE(sim.report.is_null());
  EXPECT_EQ(robot.report.at("boxes_total").get<int>(), 30);
  EXPECT_GE(robot.report.at("boxes_unloaded").get<int>(), 27) << robot.report.dump(1);
  EXPECT_EQ(robot.report.at("boxes_unloaded"), sim.report.at("boxes_unloaded"));
  EXPECT_EQ(robot.boxes_left, sim.boxes_left);
  EXPECT_EQ(robot.report.at("robot_trailer_collisions").get<int>(), 0);
  // Every motion went through the controller: the emulator logged its goals.
  EXPECT_NE(robot.log.find("SUCCEEDED"), std::string::npos);
  if (!HasFailure()) {
    fs::remove_all(robot.dir);
    fs::remove_all(sim.dir);
  }
}

}  // namespace
