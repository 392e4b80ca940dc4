#include <gtest/gtest.h>
#include <unistd.h>

#include <csignal>
#include <filesystem>

#include "plr/jobs/engine.hpp"
#include "plr/jobs/in_process_runner.hpp"
#include "plr/jobs/progress.hpp"
#include "plr/jobs/signals.hpp"

namespace fs = std::filesystem;
using namespace plr::jobs;

namespace {

class EngineTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("plr_jobs_engine_test_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    kinds_.add("test.double", [this](const Bytes& in) -> plr::Expected<Bytes> {
      ++calls_;
      Bytes out;
      for (const std::uint8_t b : in) out.push_back(static_cast<std::uint8_t>(2 * b));
      return out;
    });
    kinds_.add("test.fail", [](const Bytes&) -> plr::Expected<Bytes> {
      return plr::make_error(PLR_ERR_INVALID, "no good");
    });
  }
  void TearDown() override { fs::remove_all(dir_); }

  std::vector<Job> batch(int n) {
    std::vector<Job> jobs;
    for (int i = 0; i < n; ++i)
      jobs.push_back({"test.double", "job" + std::to_string(i), {static_cast<std::uint8_t>(i)}});
    return jobs;
  }

  fs::path dir_;
  Kinds kinds_;
  int calls_ = 0;
};

TEST_F(EngineTest, AFinishedRunRunAgainRunsNothing) {
  auto store = Store::open(dir_);
  ASSERT_TRUE(store);
  InProcessRunner runner(kinds_);
  const auto jobs = batch(4);
  auto first = run(jobs, runner, &*store);
  ASSERT_TRUE(first) << first.error().message;
  EXPECT_EQ(first->ran, 4u);
  EXPECT_EQ(calls_, 4);
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    EXPECT_TRUE(first->results[i].ok);
    EXPECT_EQ(first->results[i].output, Bytes{static_cast<std::uint8_t>(2 * i)});
  }
  std::size_t stored = 0, to_run = 9;
  auto second = run(jobs, runner, &*store,
                    {[&](std::size_t s, std::size_t r) {
                       stored = s;
                       to_run = r;
                     },
                     {},
                     {}});
  ASSERT_TRUE(second);
  EXPECT_EQ(calls_, 4);
  EXPECT_EQ(stored, 4u);
  EXPECT_EQ(to_run, 0u);
  EXPECT_EQ(second->stored, 4u);
  EXPECT_EQ(second->ran, 0u);
  for (std::size_t i = 0; i < jobs.size(); ++i) {
    EXPECT_TRUE(second->results[i].stored);
    EXPECT_EQ(second->results[i].output, first->results[i].output);
  }
  // Without one result, only that job runs.
  fs::remove(store->result_file("job2"));
  auto third = run(jobs, runner, &*store);
  ASSERT_TRUE(third);
  EXPECT_EQ(calls_, 5);
  EXPECT_EQ(third->ran, 1u);
  EXPECT_FALSE(third->results[2].stored);
}

TEST_F(EngineTest, AFailureIsAResultAndIsKept) {
  auto store = Store::open(dir_);
  ASSERT_TRUE(store);
  InProcessRunner runner(kinds_);
  const std::vector<Job> jobs = {{"test.fail", "bad", {}}, {"no.such.kind", "unknown", {}}};
  auto out = run(jobs, runner, &*store);
  ASSERT_TRUE(out);
  EXPECT_FALSE(out->results[0].ok);
  EXPECT_EQ(out->results[0].error, "no good");
  EXPECT_NE(out->results[1].error.find("no.such.kind"), std::string::npos);
  auto again = run(jobs, runner, &*store);
  ASSERT_TRUE(again);
  EXPECT_EQ(again->stored, 2u);
  EXPECT_EQ(again->results[0].error, "no good");
}

// Run again, the progress line says which stored runs had failed, since
// they are not run again.
TEST_F(EngineTest, StoredFailuresAreNamedWhenRunAgain) {
  auto store = Store::open(dir_);
  ASSERT_TRUE(store);
  InProcessRunner runner(kinds_);
  std::vector<Job> jobs = batch(2);
  jobs.push_back({"test.fail", "bad", {}});
  ASSERT_TRUE(run(jobs, runner, &*store));
  ::testing::internal::CaptureStderr();
  auto again = run_with_progress("engine_test", jobs, runner, *store);
  const std::string err = ::testing::internal::GetCapturedStderr();
  ASSERT_TRUE(again);
  EXPECT_EQ(again->ran, 0u);
  EXPECT_NE(err.find("1 of the runs already in"), std::string::npos) << err;
  EXPECT_NE(err.find("bad: no good"), std::string::npos) << err;
}

TEST_F(EngineTest, RefusesBadAndDuplicateKeys) {
  InProcessRunner runner(kinds_);
  EXPECT_FALSE(run({{"test.double", "a/b", {}}}, runner, nullptr));
  EXPECT_FALSE(run({{"test.double", "a", {}}, {"test.double", "a", {}}}, runner, nullptr));
  EXPECT_EQ(calls_, 0);
}

TEST_F(EngineTest, StoppedBySignalKeepsWhatFinished) {
  auto store = Store::open(dir_);
  ASSERT_TRUE(store);
  // The second job's handler gets a SIGINT, as from Ctrl-C.
  kinds_.add("test.interrupt", [](const Bytes&) -> plr::Expected<Bytes> {
    std::raise(SIGINT);
    return Bytes{};
  });
  std::vector<Job> jobs = batch(4);
  jobs[1].kind = "test.interrupt";
  InProcessRunner runner(kinds_);
  {
    StopOnSignals stop;
    auto out = run(jobs, runner, &*store, {{}, [&] { return stop(); }, {}});
    ASSERT_TRUE(out);
    EXPECT_TRUE(out->stopped);
    EXPECT_EQ(out->ran, 2u);
    EXPECT_EQ(stop.signal(), SIGINT);
    EXPECT_FALSE(out->results[2].ok);
  }
  EXPECT_TRUE(store->load("job0"));
  EXPECT_TRUE(store->load("job1"));
  EXPECT_FALSE(store->load("job2"));
  auto resumed = run(jobs, runner, &*store);
  ASSERT_TRUE(resumed);
  EXPECT_FALSE(resumed->stopped);
  EXPECT_EQ(resumed->stored, 2u);
  EXPECT_EQ(resumed->ran, 2u);
}

}  // namespace
