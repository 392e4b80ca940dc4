#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <set>

#include "plr/jobs/engine.hpp"
#include "plr/jobs/process_runner.hpp"

namespace fs = std::filesystem;
using namespace plr::jobs;

namespace {

class ProcessRunnerTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("plr_jobs_process_test_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::unique_ptr<ProcessRunner> runner(unsigned workers, double timeout_s, unsigned attempts) {
    auto r =
        ProcessRunner::create({{TEST_WORKER}, nullptr, workers, timeout_s, attempts, false, {}});
    EXPECT_TRUE(r) << r.error().message;
    return r ? std::move(*r) : nullptr;
  }
  std::vector<Result> run_all(const std::vector<Job>& jobs, ProcessRunner& r) {
    auto out = run(jobs, r, nullptr);
    EXPECT_TRUE(out) << out.error().message;
    return out ? out->results : std::vector<Result>{};
  }

  fs::path dir_;
};

TEST_F(ProcessRunnerTest, WorkersServeManyJobsEach) {
  auto r = runner(2, 60, 1);
  ASSERT_TRUE(r);
  std::vector<Job> jobs;
  for (int i = 0; i < 6; ++i) jobs.push_back({"test.pid", "j" + std::to_string(i), {}});
  const auto results = run_all(jobs, *r);
  std::set<std::string> pids;
  for (const Result& res : results) {
    ASSERT_TRUE(res.ok) << res.error;
    pids.insert(to_text(res.output));
  }
  const auto workers = r->pids();
  EXPECT_LE(pids.size(), 2u);
  for (const std::string& p : pids)
    EXPECT_NE(std::find(workers.begin(), workers.end(), std::stoi(p)), workers.end());
  // Printing on stdout does not break the frames.
  const auto echoed = run_all({{"test.print", "p", to_bytes("back")}}, *r);
  ASSERT_EQ(echoed.size(), 1u);
  EXPECT_EQ(to_text(echoed[0].output), "back");
  EXPECT_EQ(r->restarts(), 0u);
}

TEST_F(ProcessRunnerTest, AWorkerKilledOnAJobIsStartedAgainAndTheJobRetried) {
  auto r = runner(1, 60, 2);
  ASSERT_TRUE(r);
  const pid_t first = r->pids()[0];
  const auto results = run_all({{"test.crash_once", "c", to_bytes((dir_ / "mark").string())}}, *r);
  ASSERT_EQ(results.size(), 1u);
  ASSERT_TRUE(results[0].ok) << results[0].error;
  EXPECT_EQ(to_text(results[0].output), "second time");
  EXPECT_EQ(results[0].attempts, 2u);
  EXPECT_EQ(r->restarts(), 1u);
  EXPECT_NE(r->pids()[0], first);
}

TEST_F(ProcessRunnerTest, AJobPastItsTimeoutFailsAfterItsAttempts) {
  auto r = runner(1, 0.2, 2);
  ASSERT_TRUE(r);
  const auto results = run_all({{"test.hang", "h", {}}, {"test.pid", "after", {}}}, *r);
  ASSERT_EQ(results.size(), 2u);
  EXPECT_FALSE(results[0].ok);
  EXPECT_EQ(results[0].error.rfind("killed after", 0), 0u) << results[0].error;
  EXPECT_EQ(results[0].attempts, 2u);
  EXPECT_TRUE(results[1].ok) << results[1].error;
  EXPECT_EQ(r->restarts(), 2u);
}

TEST_F(ProcessRunnerTest, AMissingProgramIsNamed) {
  auto r =
      ProcessRunner::create({{(dir_ / "no_such_worker").string()}, nullptr, 1, 60, 1, false, {}});
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("no_such_worker"), std::string::npos);
}

}  // namespace
