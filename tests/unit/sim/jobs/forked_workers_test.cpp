#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "plr/jobs/engine.hpp"
#include "plr/jobs/process_runner.hpp"

namespace fs = std::filesystem;
using namespace plr::jobs;

namespace {

class ForkedWorkersTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("plr_jobs_fork_test_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    kinds_.add("test.pid", [](const Bytes&) -> plr::Expected<Bytes> {
      return to_bytes(std::to_string(::getpid()));
    });
    kinds_.add("test.hang", [](const Bytes&) -> plr::Expected<Bytes> {
      while (true) ::pause();
    });
    kinds_.add("test.crash", [](const Bytes&) -> plr::Expected<Bytes> {
      std::fprintf(stderr, "about to die\n");
      std::fflush(stderr);
      ::kill(::getpid(), SIGKILL);
      return Bytes{};
    });
    // Dies on its first attempt only: the attempt leaves a mark in the folder.
    kinds_.add("test.crash_once", [this](const Bytes&) -> plr::Expected<Bytes> {
      const fs::path mark = dir_ / "attempted";
      if (!fs::exists(mark)) {
        std::ofstream(mark) << "1";
        ::kill(::getpid(), SIGKILL);
      }
      return to_bytes("second time");
    });
    kinds_.add("test.fail", [](const Bytes&) -> plr::Expected<Bytes> {
      return plr::make_error(PLR_ERR_INVALID, "refused");
    });
  }
  void TearDown() override { fs::remove_all(dir_); }

  // A fresh child of this process per job, as the evaluation runs them.
  std::unique_ptr<ProcessRunner> forked(unsigned workers, double timeout_s, unsigned attempts,
                                        const fs::path& log_dir = {}) {
    auto r = ProcessRunner::create({{}, &kinds_, workers, timeout_s, attempts, true, log_dir});
    EXPECT_TRUE(r) << r.error().message;
    return r ? std::move(*r) : nullptr;
  }
  std::vector<Result> run_all(const std::vector<Job>& jobs, ProcessRunner& runner) {
    auto out = run(jobs, runner, nullptr);
    EXPECT_TRUE(out) << out.error().message;
    return out ? out->results : std::vector<Result>{};
  }

  fs::path dir_;
  Kinds kinds_;
};

TEST_F(ForkedWorkersTest, EachJobRunsInAChildOfItsOwn) {
  auto runner = forked(2, 60, 1);
  const auto results =
      run_all({{"test.pid", "a", {}}, {"test.pid", "b", {}}, {"test.pid", "c", {}}}, *runner);
  ASSERT_EQ(results.size(), 3u);
  std::set<std::string> pids;
  for (const Result& r : results) {
    ASSERT_TRUE(r.ok) << r.error;
    EXPECT_EQ(r.attempts, 1u);
    pids.insert(to_text(r.output));
  }
  EXPECT_EQ(pids.size(), 3u);
  EXPECT_EQ(pids.count(std::to_string(::getpid())), 0u);
}

TEST_F(ForkedWorkersTest, AJobPastItsTimeoutIsKilled) {
  auto runner = forked(1, 0.2, 1);
  const auto results = run_all({{"test.hang", "slow", {}}, {"test.pid", "quick", {}}}, *runner);
  ASSERT_EQ(results.size(), 2u);
  EXPECT_FALSE(results[0].ok);
  EXPECT_EQ(results[0].error.rfind("killed after", 0), 0u) << results[0].error;
  EXPECT_TRUE(results[1].ok);
}

TEST_F(ForkedWorkersTest, ADeadChildIsTriedAgainUpToMaxAttempts) {
  auto twice = forked(1, 60, 2);
  const auto once = run_all({{"test.crash_once", "flaky", {}}}, *twice);
  ASSERT_EQ(once.size(), 1u);
  ASSERT_TRUE(once[0].ok) << once[0].error;
  EXPECT_EQ(to_text(once[0].output), "second time");
  EXPECT_EQ(once[0].attempts, 2u);
  EXPECT_EQ(twice->retries(), 1u);

  auto thrice = forked(1, 60, 3, dir_);
  const auto always = run_all({{"test.crash", "doomed", {}}}, *thrice);
  ASSERT_EQ(always.size(), 1u);
  EXPECT_FALSE(always[0].ok);
  EXPECT_EQ(always[0].attempts, 3u);
  EXPECT_NE(always[0].error.find("signal 9"), std::string::npos) << always[0].error;
  EXPECT_NE(always[0].error.find("doomed.log"), std::string::npos) << always[0].error;
  std::ifstream log(dir_ / "doomed.log");
  std::stringstream text;
  text << log.rdbuf();
  EXPECT_EQ(text.str(), "about to die\n");
}

TEST_F(ForkedWorkersTest, AHandlersErrorIsAResultNotARetry) {
  auto runner = forked(1, 60, 3);
  const auto results = run_all({{"test.fail", "f", {}}}, *runner);
  ASSERT_EQ(results.size(), 1u);
  EXPECT_FALSE(results[0].ok);
  EXPECT_EQ(results[0].error, "refused");
  EXPECT_EQ(results[0].attempts, 1u);
  EXPECT_EQ(runner->retries(), 0u);
}

TEST_F(ForkedWorkersTest, StopEndsTheRunningChildrenAndKeepsTheFinished) {
  auto store = Store::open(dir_ / "store");
  ASSERT_TRUE(store);
  auto runner = forked(2, 600, 1);
  const std::vector<Job> jobs = {{"test.pid", "done", {}}, {"test.hang", "hangs", {}}};
  std::size_t finished = 0;
  auto out = run(jobs, *runner, &*store,
                 {{}, [&] { return finished == 1; }, [&](const Result&) { ++finished; }});
  ASSERT_TRUE(out) << out.error().message;
  EXPECT_TRUE(out->stopped);
  EXPECT_TRUE(out->results[0].ok);
  EXPECT_FALSE(out->results[1].ok);
  EXPECT_TRUE(store->load("done"));
  EXPECT_FALSE(store->load("hangs"));
}

}  // namespace
