// The unloading pipeline end to end: `plr run configs/unload_sim_small.yaml`
// with the real simulator (its own process), planner, strategy H and
// executor, then the report. The second run kills the simulator's process
// mid-run: it is restarted, restores the last checkpoint, and the executor
// repeats the interrupted action. The third swaps the planner mid-run.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <string>
#include <thread>

namespace {

namespace fs = std::filesystem;

struct Outcome {
  fs::path dir;
  std::string log;
  nlohmann::json report;
};

fs::path make_dir() {
  std::string pattern = (fs::temp_directory_path() / "plr_unload_small_XXXXXX").string();
  return mkdtemp(pattern.data());
}

std::string read(const fs::path& file) {
  std::ifstream in(file);
  return std::string((std::istreambuf_iterator<char>(in)), {});
}

// A name of its own: a pipeline's control socket is named after it, and two
// runs of one name (this test in two build trees, say) cannot run at once.
std::string pipeline_name() {
  return "unload_small_" + std::to_string(::getpid());
}

// Runs the pipeline; `meanwhile`, if given, runs `at` seconds in with the pid
// of the `plr run` process.
Outcome unload(double at = 0, const std::function<void(pid_t)>& meanwhile = {}) {
  Outcome run;
  run.dir = make_dir();
  const std::string err = (run.dir / "stderr.txt").string();
  const std::string report = (run.dir / "report").string();
  const std::string name = "pipeline=" + pipeline_name();
  const pid_t pid = fork();
  if (pid == 0) {
    const int fd = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0600);
    dup2(fd, 2);
    execl(PLR_BIN, PLR_BIN, "run", UNLOAD_SMALL_CONFIG, "--report", report.c_str(), "--set",
          name.c_str(), nullptr);
    _exit(127);
  }
  if (meanwhile) {
    std::this_thread::sleep_for(std::chrono::duration<double>(at));
    meanwhile(pid);
  }
  int status = 0;
  waitpid(pid, &status, 0);
  run.log = read(err);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << run.log;
  std::ifstream in(run.dir / "report" / "report.json");
  EXPECT_TRUE(in) << "no report.json\n" << run.log;
  if (in) run.report = nlohmann::json::parse(in);
  return run;
}

// Messages the executor has published on executor/state so far (one as each
// step of an action starts), from `plr status`; -1 while the pipeline does
// not answer.
int executor_states() {
  const std::string cmd =
      std::string(PLR_BIN) + " status --pipeline " + pipeline_name() + " 2>/dev/null";
  FILE* out = ::popen(cmd.c_str(), "r");
  if (!out) return -1;
  std::string text;
  char buf[4096];
  for (std::size_t n; (n = std::fread(buf, 1, sizeof buf, out)) > 0;) text.append(buf, n);
  if (::pclose(out) != 0) return -1;
  const auto status = nlohmann::json::parse(text, nullptr, false);
  if (!status.is_object()) return -1;
  for (const auto& t : status.value("topics", nlohmann::json::array()))
    if (t.value("name", "") == "executor/state") return t.value("messages", -1);
  return -1;
}

// Waits (at most 60 s) until the executor has started `more` steps past `from`.
void wait_for_steps(int from, int more) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (executor_states() < from + more && std::chrono::steady_clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
}

// Boxes neither appear nor vanish: what is left plus what left is the total.
int boxes_left(const fs::path& final_world) {
  const std::string text = read(final_world);
  int n = 0;
  for (std::size_t at = text.find("{id:"); at != std::string::npos; at = text.find("{id:", at + 1))
    ++n;
  return n;
}

// `at_least`: the boxes that must be out at the end.
void expect_unloaded(const Outcome& run, int at_least) {
  ASSERT_FALSE(run.report.is_null());
  const auto& r = run.report;
  const int total = r.at("boxes_total").get<int>();
  const int unloaded = r.at("boxes_unloaded").get<int>();
  EXPECT_EQ(total, 30);
  EXPECT_GE(unloaded, at_least) << r.dump(1);
  EXPECT_EQ(unloaded + boxes_left(run.dir / "report" / "final_world.yaml"), total);
  EXPECT_EQ(r.at("robot_trailer_collisions").get<int>(), 0);
  for (const char* m : {"M1", "M2", "M3", "M4", "M5", "M6"})
    EXPECT_TRUE(r.at("planner_modes").contains(m)) << m;
  EXPECT_GT(r["planner_modes"]["M5"]["queries"].get<int>(), 0);
  EXPECT_GT(r["actions"]["pick"]["executions"].get<int>(), 0);
  EXPECT_GT(r.at("sim_time_s").get<double>(), 0.0);
  EXPECT_GT(r.at("wall_time_s").get<double>(), 0.0);
  for (const char* f : {"unloading.svg", "scene_side.svg", "scene_top.svg"})
    EXPECT_TRUE(fs::exists(run.dir / "report" / f)) << f;
}

TEST(UnloadSmall, UnloadsTheTrailerWithoutHittingIt) {
  const Outcome run = unload();
  expect_unloaded(run, 27);
  EXPECT_EQ(run.report.value("recoveries", -1), 0);
  // The unloading curve rises one box at a time, when each box left, and
  // ends at the count unloaded.
  const auto& curve = run.report["curve"];
  ASSERT_TRUE(curve.is_array() && !curve.empty());
  double last_t = 0;
  int last_n = 0;
  for (const auto& p : curve) {
    EXPECT_GE(p[0].get<double>(), last_t);
    EXPECT_GE(p[1].get<int>(), last_n);
    EXPECT_LE(p[1].get<int>(), last_n + 1);
    last_t = p[0].get<double>();
    last_n = p[1].get<int>();
  }
  EXPECT_EQ(last_n, run.report.value("boxes_unloaded", -1));
  if (!HasFailure()) fs::remove_all(run.dir);
}

TEST(UnloadSmall, SurvivesTheSimulatorBeingKilled) {
  // Restored from the checkpoint on disk (box poses, not the integrator's
  // exact state), the run takes another course than the undisturbed one;
  // what it must do is finish, with every box accounted for. Some courses
  // stall at half the trailer (15 of 30: the top boxes of a stepped front
  // that no pick region takes, issue 18), so the count asked for here is
  // only that the run went on after the restart; how much H unloads is the
  // first test's to check.
  const Outcome run = unload(2.0, [](pid_t pid) {
    // The supervisor's child that runs host 'sim'.
    const std::string cmd = "pkill -KILL -P " + std::to_string(pid) + " -f -- '--host sim'";
    EXPECT_EQ(std::system(cmd.c_str()), 0) << "no simulator host to kill";
  });
  expect_unloaded(run, 10);
  EXPECT_GE(run.report.value("recoveries", 0), 1) << run.log;
  if (!HasFailure()) fs::remove_all(run.dir);
}

// RRTConnect has no M6: a start in collision (a box resting on the nose)
// stalls it, so the planner goes back to ARA* after a while. The swaps follow
// the run's progress, not the clock (the whole run takes about 2.7 s on an
// idle 2-core VM and ten times that under load): the first once the executor
// has begun, the second once it has started a few steps on RRTConnect's plans.
TEST(UnloadSmall, FinishesWhenThePlannerIsSwappedMidRun) {
  const Outcome run = unload(0, [](pid_t) {
    const auto swap = [](const char* plugin) {
      const std::string cmd =
          std::string(PLR_BIN) + " swap planner " + plugin + " --pipeline " + pipeline_name();
      EXPECT_EQ(std::system(cmd.c_str()), 0) << "plr swap planner " << plugin << " failed";
    };
    wait_for_steps(0, 3);
    swap("planner_ompl");
    wait_for_steps(executor_states(), 3);
    swap("planner_arastar");
  });
  expect_unloaded(run, 20);
  // Both planners answered, and no query went unanswered across the swap.
  ASSERT_TRUE(run.report.contains("planners")) << run.report.dump(1);
  EXPECT_GT(run.report["planners"].value("arastar", 0), 0) << run.report["planners"].dump();
  EXPECT_GT(run.report["planners"].value("rrtconnect", 0), 0) << run.report["planners"].dump();
  EXPECT_EQ(run.report.value("plan_calls_unanswered", -1), 0);
  if (!HasFailure()) fs::remove_all(run.dir);
}

}  // namespace
