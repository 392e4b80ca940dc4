// The robot pipeline end to end: `plr run configs/unload_robot.yaml`, where
// the driver streams every trajectory to the controller emulator (its own
// process) over DDS with ROS 2's types, and the simulator only follows what
// the controller reported. It must unload the same boxes as the
// simulator-only pipeline (configs/unload_sim_small.yaml) on the same world.
// The second run kills the simulator's process mid-run: the world comes back
// from its checkpoint with the robot where it was then, and the controller
// must be brought there before the run goes on.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <regex>
#include <set>
#include <string>
#include <thread>

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

std::set<int> box_ids(const fs::path& world_file) {
  const std::string world = read(world_file);
  static const std::regex id(R"(\{id: *(\d+))");
  std::set<int> ids;
  for (auto it = std::sregex_iterator(world.begin(), world.end(), id); it != std::sregex_iterator();
       ++it)
    ids.insert(std::stoi((*it)[1]));
  return ids;
}

// `meanwhile`, if given, runs alongside with the pid of `plr run` and its report folder.
Unloading unload(const char* config, const std::string& tag, std::vector<std::string> overrides,
                 const std::function<void(pid_t, const fs::path&)>& meanwhile = {}) {
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
  if (meanwhile) meanwhile(pid, report);
  int status = 0;
  waitpid(pid, &status, 0);
  run.log = read(err);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << run.log;
  std::ifstream in(run.dir / "report" / "report.json");
  EXPECT_TRUE(in) << "no report.json\n" << run.log;
  if (in) run.report = nlohmann::json::parse(in);
  run.boxes_left = box_ids(run.dir / "report" / "final_world.yaml");
  return run;
}

// A domain of its own, so a run of this test elsewhere on the machine does not meet it.
std::vector<std::string> own_domain() {
  const std::string domain = std::to_string(150 + ::getpid() % 80);
  return {"nodes.driver.params.domain_id=" + domain, "nodes.controller.params.domain_id=" + domain};
}

TEST(UnloadRobot, UnloadsTheSameBoxesThroughTheEmulatedControllerAsTheSimulator) {
  const Unloading robot = unload(UNLOAD_ROBOT_CONFIG, "unload_robot", own_domain());
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

TEST(UnloadRobot, GoesOnAfterTheSimulatorIsKilledMidRun) {
  int out_at_kill = -1;
  const Unloading robot = unload(
      UNLOAD_ROBOT_CONFIG, "unload_robot_kill", own_domain(),
      [&](pid_t pid, const fs::path& report) {
        // Mid-run: once the checkpoint holds a world with 5 boxes out.
        const auto checkpoint = report / "checkpoint" / "world.yaml";
        for (const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(120);
             std::chrono::steady_clock::now() < until;
             std::this_thread::sleep_for(std::chrono::milliseconds(100))) {
          const auto left = box_ids(checkpoint).size();
          if (fs::exists(checkpoint) && left > 0 && left <= 25) {
            out_at_kill = 30 - static_cast<int>(left);
            break;
          }
        }
        ASSERT_GE(out_at_kill, 5) << "no checkpoint with 5 boxes out in 120 s";
        // The supervisor's child that runs host 'sim'.
        const std::string cmd = "pkill -KILL -P " + std::to_string(pid) + " -f -- '--host sim'";
        EXPECT_EQ(std::system(cmd.c_str()), 0) << "no simulator host to kill";
      });
  ASSERT_FALSE(robot.report.is_null());
  EXPECT_GE(robot.report.value("recoveries", 0), 1) << robot.log;
  // Before the fix every motion after the restore was refused: the
  // controller stayed where the killed world had left it.
  EXPECT_EQ(robot.log.find("refused before sending"), std::string::npos) << robot.log;
  EXPECT_GE(robot.report.at("boxes_unloaded").get<int>(), out_at_kill + 5) << robot.report.dump(1);
  EXPECT_EQ(robot.report.at("robot_trailer_collisions").get<int>(), 0);
  if (!HasFailure()) fs::remove_all(robot.dir);
}

}  // namespace
