// plr evaluate on a real single-node Slurm cluster (tests/common/
// slurm_cluster.hpp): its runs as job arrays give the local runner's
// results; a task cancelled mid-run is submitted again and nothing is lost
// or counted twice; SIGTERM cancels the arrays, keeps what finished, and the
// same command resumes. The strategy generator's strategies and a chooser
// training's rollouts as array tasks make the library and the model a local
// run makes, and so do simulation workers started as a Slurm job. Skips,
// saying why, where the daemons cannot start.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <regex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include <nlohmann/json.hpp>

#include "plr/chooser/testing/library.hpp"
#include "plr/jobs/store.hpp"
#include "plr/sim/library.hpp"
#include "plr/sim/testing/library_fingerprint.hpp"
#include "slurm_cluster.hpp"
#include "small_evaluation.hpp"

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using plr::slurm_test::SlurmCluster;

namespace {

// 2 environments x 2 methods x 1 seed.
constexpr std::size_t kRuns = 4;

// A run's JSON without what the wall clock measured (its wall time, the
// planner's milliseconds): what must be equal wherever the run ran.
nlohmann::json deterministic(nlohmann::json j) {
  if (j.is_object()) {
    nlohmann::json out = nlohmann::json::object();
    for (auto& [k, v] : j.items())
      if (k != "wall_s" && k.find("_ms") == std::string::npos) out[k] = deterministic(v);
    return out;
  }
  if (j.is_array())
    for (auto& v : j) v = deterministic(v);
  return j;
}

// Every result of a report's store: key -> the run's JSON.
std::map<std::string, nlohmann::json> results(const fs::path& report) {
  std::map<std::string, nlohmann::json> out;
  auto store = plr::jobs::Store::open(report / "runs");
  if (!store) return out;
  for (const auto& f : fs::directory_iterator(report / "runs" / "results")) {
    const std::string key = f.path().stem().string();
    if (const auto r = store->load(key); r && r->ok)
      out[key] = nlohmann::json::parse(plr::jobs::to_text(r->output));
  }
  return out;
}

// The store's result files: a task writes one as ".<key>.result.XXXXXX" and
// renames it, so a temporary file (or one a cancelled task left) is none.
std::map<std::string, fs::file_time_type> result_times(const fs::path& report) {
  std::map<std::string, fs::file_time_type> out;
  std::error_code ec;  // no folder yet: the command has not opened its store
  for (const auto& f : fs::directory_iterator(report / "runs" / "results", ec)) {
    const std::string name = f.path().filename().string();
    if (name.front() != '.' && f.path().extension() == ".result") out[name] = f.last_write_time();
  }
  return out;
}

nlohmann::json report_json(const fs::path& report) {
  std::ifstream in(report / "report.json");
  return nlohmann::json::parse(in, nullptr, false);
}

class SlurmTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string why = cluster_.start();
    if (!why.empty()) GTEST_SKIP() << "no Slurm cluster here: " << why;
    dir_ = fs::temp_directory_path() / ("plr_slurm_test_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    const std::string error = plr::evaluation_test::write_small_evaluation(dir_, "[H, PLR]");
    ASSERT_TRUE(error.empty()) << error;
    job_name_ = "plr-test-" + std::to_string(::getpid());
  }
  void TearDown() override {
    cluster_.stop();
    if (!HasFailure()) fs::remove_all(dir_);
  }

  // plr evaluate into `report` with `extra` arguments, started in the
  // background; its output goes to report.log beside the report.
  pid_t start(const std::string& report, std::vector<std::string> extra) {
    std::vector<std::string> argv = {PLR_EVALUATE, (dir_ / "evaluate.yaml").string(), "--report",
                                     (dir_ / report).string()};
    argv.insert(argv.end(), {"--set", "seeds=1"});
    argv.insert(argv.end(), extra.begin(), extra.end());
    return spawn(std::move(argv), report);
  }
  // `argv` in the background, its output in <name>.log.
  pid_t spawn(std::vector<std::string> argv, const std::string& report) {
    std::vector<char*> args;
    for (auto& a : argv) args.push_back(a.data());
    args.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    const std::string log = (dir_ / (report + ".log")).string();
    posix_spawn_file_actions_addopen(&actions, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, 1, 2);
    pid_t pid = -1;
    EXPECT_EQ(posix_spawn(&pid, args[0], &actions, nullptr, args.data(), environ), 0);
    posix_spawn_file_actions_destroy(&actions);
    return pid;
  }
  int wait(pid_t pid) {
    int status = 0;
    ::waitpid(pid, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
  }
  std::vector<std::string> slurm_args() const {
    return {"--runner",         "slurm", "--set",
            "slurm.poll_s=0.2", "--set", "slurm.job_name=" + job_name_};
  }
  std::string log(const std::string& report) const {
    std::ifstream in(dir_ / (report + ".log"));
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  // This test's array tasks in the queue, as "jobid_task STATE" lines.
  std::string queue() const {
    std::string out;
    SlurmCluster::run("squeue -h -r -n " + job_name_ + " -o '%i %T'", &out);
    return out;
  }

  SlurmCluster cluster_;
  fs::path dir_;
  std::string job_name_;
};

TEST_F(SlurmTest, RunsGiveTheLocalRunnersResults) {
  // Runs cut at 20 robot-seconds: a few actions each, enough to compare.
  const std::vector<std::string> short_runs = {"--set", "max_robot_time_s=20"};
  auto on_slurm = slurm_args();
  on_slurm.insert(on_slurm.end(), short_runs.begin(), short_runs.end());
  ASSERT_EQ(wait(start("local", short_runs)), 0) << log("local");
  ASSERT_EQ(wait(start("slurm", on_slurm)), 0) << log("slurm");
  const auto local = results(dir_ / "local"), slurm = results(dir_ / "slurm");
  ASSERT_EQ(local.size(), kRuns);
  ASSERT_EQ(slurm.size(), kRuns);
  for (const auto& [key, run] : local) {
    ASSERT_TRUE(slurm.count(key)) << key;
    EXPECT_EQ(deterministic(run), deterministic(slurm.at(key)))
        << key << ": " << nlohmann::json::diff(deterministic(run), deterministic(slurm.at(key)));
    EXPECT_GT(run.value("robot_time_s", 0.0), 0.0) << key;
  }
  // The report's figures too; the Slurm one says what the scheduler did.
  auto a = report_json(dir_ / "local"), b = report_json(dir_ / "slurm");
  ASSERT_TRUE(b.contains("runner"));
  EXPECT_EQ(b["runner"]["kind"], "slurm");
  EXPECT_EQ(b["runner"]["tasks"], kRuns);
  EXPECT_EQ(b["runner"]["resubmitted"], 0);
  EXPECT_GE(b["runner"]["submit_to_first_running_s"].get<double>(), 0.0);
  b.erase("runner");
  EXPECT_EQ(deterministic(a), deterministic(b))
      << nlohmann::json::diff(deterministic(a), deterministic(b));
  EXPECT_TRUE(queue().empty()) << queue();
}

TEST_F(SlurmTest, ACancelledTaskIsSubmittedAgain) {
  auto args = slurm_args();
  args.insert(args.end(), {"--set", "slurm.max_parallel=1"});
  const pid_t pid = start("slurm", args);
  // Cancel the first task seen running, once.
  std::string cancelled;
  for (int i = 0; i < 600 && cancelled.empty(); ++i) {
    std::this_thread::sleep_for(100ms);
    std::istringstream lines(queue());
    for (std::string task, state; lines >> task >> state;)
      if (state == "RUNNING") {
        cancelled = task;
        break;
      }
  }
  ASSERT_FALSE(cancelled.empty()) << "no task ran; " << log("slurm");
  ASSERT_EQ(SlurmCluster::run("scancel " + cancelled), 0);
  ASSERT_EQ(wait(pid), 0) << log("slurm");

  const auto runs = results(dir_ / "slurm");
  EXPECT_EQ(runs.size(), kRuns);
  const auto j = report_json(dir_ / "slurm");
  EXPECT_GE(j["runner"]["resubmitted"].get<int>(), 1) << j["runner"];
  EXPECT_GE(j["runner"]["ended_without_result"].value("CANCELLED", 0), 1) << j["runner"];
  // Nothing counted twice: each environment's methods ran their seed once.
  for (const char* env : {"S", "T"})
    for (const auto& [m, d] : j["environments"][env]["methods"].items()) {
      EXPECT_EQ(d["runs"].get<int>(), 1) << env << " " << m;
      EXPECT_EQ(d["failed"].get<int>(), 0) << env << " " << m;
    }
  EXPECT_TRUE(queue().empty()) << queue();
}

TEST_F(SlurmTest, SigtermCancelsTheArraysAndTheSameCommandResumes) {
  auto args = slurm_args();
  args.insert(args.end(), {"--set", "slurm.max_parallel=1"});
  const pid_t pid = start("slurm", args);
  // Stop it once a result is in and tasks are still to come (on a loaded
  // machine the first may take long: ctest's timeout bounds the wait).
  int status = 0;
  while (result_times(dir_ / "slurm").empty() && ::waitpid(pid, &status, WNOHANG) == 0)
    std::this_thread::sleep_for(100ms);
  ASSERT_FALSE(result_times(dir_ / "slurm").empty()) << log("slurm");
  ::kill(pid, SIGTERM);
  EXPECT_EQ(wait(pid), 130) << log("slurm");
  // No task of its arrays is left queued or running: scancel has returned,
  // and the controller marks a cancelled task so at once.
  std::string left;
  SlurmCluster::run("squeue -h -r -n " + job_name_ + " -t PENDING,RUNNING -o '%i %T'", &left);
  EXPECT_TRUE(left.empty()) << left;
  // The one it cancelled while running may still be ending (COMPLETING):
  // what is stored is known once it has.
  while (!queue().empty()) std::this_thread::sleep_for(100ms);

  const auto before = result_times(dir_ / "slurm");
  ASSERT_LT(before.size(), kRuns);
  ASSERT_EQ(wait(start("slurm", slurm_args())), 0) << log("slurm");
  const auto after = result_times(dir_ / "slurm");
  EXPECT_EQ(after.size(), kRuns);
  // What finished before the stop was not run again.
  for (const auto& [file, time] : before) EXPECT_EQ(after.at(file), time) << file;
  EXPECT_EQ(report_json(dir_ / "slurm")["runner"]["tasks"].get<std::size_t>(),
            kRuns - before.size());
}

// The strategy generator with `runner: slurm`: each world's strategy is an
// array task of the worker program; the library equals a local
// generation's.
TEST_F(SlurmTest, AGenerationsStrategiesAsArrayTasksEqualALocalOnes) {
  // The block world under two names: two strategies, two tasks.
  for (const char* name : {"block_a.yaml", "block_b.yaml"}) fs::copy_file(BLOCK_WORLD, dir_ / name);
  auto config = [&](const std::string& name, const std::string& runner) {
    const fs::path file = dir_ / (name + ".yaml");
    std::ofstream(file) << "pipeline: " << name << "_" << ::getpid() << "\n"
                        << "nodes:\n  generator:\n    plugin: strategy_generator\n    params:\n"
                        << "      library: ${report_dir}/library.plrl\n"
                        << "      checkpoint_dir: ${report_dir}/checkpoint\n"
                        << "      worlds: [{family: A1, world_file: "
                        << (dir_ / "block_a.yaml").string()
                        << "}, {family: A1, world_file: " << (dir_ / "block_b.yaml").string()
                        << "}]\n"
                        << "      particles: 3\n      horizon: 3\n      trials: 6\n"
                        << "      workers: 0\n      progress: false\n"
                        << "      observation: {h_pile: 0.55, pile_mid: 0.25, pile_high: 0.4, "
                           "wall_mid: 1.2, wall_high: 1.9}\n"
                        << runner;
    return std::vector<std::string>{PLR_BINARY, "run", file.string(), "--report",
                                    (dir_ / name).string()};
  };
  ASSERT_EQ(wait(spawn(config("generate_local", ""), "generate_local")), 0)
      << log("generate_local");
  const std::string slurm =
      "      runner: slurm\n      slurm: {poll_s: 0.2, job_name: " + job_name_ + "}\n";
  ASSERT_EQ(wait(spawn(config("generate_slurm", slurm), "generate_slurm")), 0)
      << log("generate_slurm");
  const auto local = plr::sim::load_library(dir_ / "generate_local" / "library.plrl");
  const auto on_slurm = plr::sim::load_library(dir_ / "generate_slurm" / "library.plrl");
  ASSERT_TRUE(local && on_slurm) << log("generate_slurm");
  ASSERT_EQ(on_slurm->entries.size(), 2u);
  EXPECT_EQ(on_slurm->entries[0].name, "block_a");
  EXPECT_EQ(on_slurm->entries[1].name, "block_b");
  EXPECT_EQ(plr::sim::testing::library_fingerprint(dir_ / "generate_slurm" / "library.plrl"),
            plr::sim::testing::library_fingerprint(dir_ / "generate_local" / "library.plrl"));
  EXPECT_NE(log("generate_slurm").find("\"tasks\":2"), std::string::npos) << log("generate_slurm");
  EXPECT_TRUE(queue().empty()) << queue();
}

// plr chooser train with --runner slurm: each state's rollouts are one
// array; the model is the one a local training makes, byte for byte, and
// no rollout result is left behind.
TEST_F(SlurmTest, AChooserTrainingsRolloutsAsArraysMakeTheLocalModel) {
  const fs::path data = CHOOSER_TEST_DATA;
  const plr::sim::Library library = plr::chooser::testing::two_world_library(data);
  ASSERT_TRUE(plr::sim::save_library(library, dir_ / "library.plrl"));
  std::ofstream(dir_ / "train.yaml")
      << "format: plr-chooser-training\nlibrary: " << (dir_ / "library.plrl").string()
      << "\nout: " << (dir_ / "out").string() << "\ntrain: [" << (data / "floor_row.yaml").string()
      << ", " << (data / "two_columns.yaml").string() << "]\nvalidation: ["
      << (data / "two_columns.yaml").string()
      << "]\nstates_per_world: 2\nrollout_actions: 1\ntie_boxes: 1\nworkers: 2\nfolds: 2\n"
      << "particles: 2\nmass_prior: B1\nslurm: {poll_s: 0.2, job_name: " << job_name_ << "}\n";
  auto train = [&](const std::string& out, std::vector<std::string> extra) {
    std::vector<std::string> argv = {PLR_CHOOSER_TOOL, "train", (dir_ / "train.yaml").string(),
                                     "--set", "out=" + (dir_ / out).string()};
    argv.insert(argv.end(), extra.begin(), extra.end());
    return wait(spawn(std::move(argv), out));
  };
  ASSERT_EQ(train("train_local", {}), 0) << log("train_local");
  ASSERT_EQ(train("train_slurm", {"--runner", "slurm"}), 0) << log("train_slurm");
  auto bytes = [](const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  };
  const std::string model = bytes(dir_ / "train_local" / "model.plrm");
  ASSERT_FALSE(model.empty());
  EXPECT_EQ(bytes(dir_ / "train_slurm" / "model.plrm"), model);
  // The rollouts went through the store as array tasks (their logs are
  // there); their results and batches are gone once their states were
  // labelled.
  const fs::path rollouts = dir_ / "train_slurm" / "rollouts";
  EXPECT_FALSE(fs::is_empty(rollouts / "logs"));
  EXPECT_TRUE(fs::is_empty(rollouts / "results"));
  EXPECT_TRUE(fs::is_empty(rollouts / "batches"));
  EXPECT_TRUE(queue().empty()) << queue();
}

// The generator's live simulations on workers started as a Slurm job: the
// worker kernel (plr run of a simulation_worker pipeline) runs as a batch
// job, the generator finds its sim/simulate by DDS discovery, and the
// library is the one a generation with in-process simulations makes.
TEST_F(SlurmTest, SimulationWorkersStartedAsASlurmJobServeTheGenerator) {
  const int domain = 100 + ::getpid() % 50;
  const fs::path worker = dir_ / "sim_worker.yaml";
  std::ofstream(worker) << "pipeline: sim_worker_" << ::getpid()
                        << "\nnodes:\n  worker:\n    plugin: simulation_worker\n"
                        << "    params: {threads: 2}\nremote:\n  dds: {domain: " << domain
                        << ", interfaces: [lo], export: [\"sim/simulate\"]}\n";
  const fs::path worker_log = dir_ / "sim_worker.log";
  std::string out;
  ASSERT_EQ(SlurmCluster::run("sbatch --parsable --job-name=" + job_name_ + " --output=" +
                                  worker_log.string() + " --wrap '" + PLR_BINARY + " run " +
                                  worker.string() + " --report " + (dir_ / "w").string() + "'",
                              &out),
            0)
      << out;
  const std::string job = out.substr(0, out.find_first_of(";\n"));
  for (int i = 0; i < 600 && log("sim_worker").find("running (1 nodes)") == std::string::npos; ++i)
    std::this_thread::sleep_for(100ms);
  ASSERT_NE(log("sim_worker").find("running (1 nodes)"), std::string::npos) << log("sim_worker");

  auto generate = [&](const std::string& name, const std::string& workers) {
    const fs::path file = dir_ / (name + ".yaml");
    std::ofstream(file) << "pipeline: " << name << "_" << ::getpid() << "\n"
                        << "nodes:\n  generator:\n    plugin: strategy_generator\n    params:\n"
                        << "      library: ${report_dir}/library.plrl\n"
                        << "      checkpoint_dir: ${report_dir}/checkpoint\n"
                        << "      worlds: [{family: A1, world_file: " << BLOCK_WORLD << "}]\n"
                        << "      particles: 3\n      horizon: 3\n      trials: 6\n"
                        << "      progress: false\n"
                        << "      observation: {h_pile: 0.55, pile_mid: 0.25, pile_high: 0.4, "
                           "wall_mid: 1.2, wall_high: 1.9}\n"
                        << workers;
    return wait(
        spawn({PLR_BINARY, "run", file.string(), "--report", (dir_ / name).string()}, name));
  };
  ASSERT_EQ(generate("in_process", "      workers: 0\n"), 0) << log("in_process");
  ASSERT_EQ(
      generate("on_slurm_workers",
               "      workers: 0\n      remote_workers: 2\nremote:\n  dds: {domain: " +
                   std::to_string(domain) + ", interfaces: [lo], import: [\"sim/simulate\"]}\n"),
      0)
      << log("on_slurm_workers");
  EXPECT_EQ(plr::sim::testing::library_fingerprint(dir_ / "on_slurm_workers" / "library.plrl"),
            plr::sim::testing::library_fingerprint(dir_ / "in_process" / "library.plrl"));
  // Its simulations ran on the Slurm job's worker.
  std::smatch m;
  const std::string generated = log("on_slurm_workers");
  ASSERT_TRUE(std::regex_search(generated, m, std::regex(R"(remote workers: (\d+) jobs answered)")))
      << generated;
  EXPECT_GT(std::stoi(m[1]), 0);
  SlurmCluster::run("scancel " + job, &out);
  for (int i = 0; i < 100 && !queue().empty(); ++i) std::this_thread::sleep_for(100ms);
  EXPECT_TRUE(queue().empty()) << queue();
}

}  // namespace
