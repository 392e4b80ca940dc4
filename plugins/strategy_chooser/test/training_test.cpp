// The chooser's training on two small hand-made worlds and a hand-made
// library: settings errors, and a training killed with SIGKILL and run again
// ends with the model of an undisturbed one.
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <thread>

#include "plr/chooser/model.hpp"
#include "plr/chooser/testing/library.hpp"
#include "plr/chooser/training/data_set.hpp"
#include "plr/chooser/training/settings.hpp"
#include "plr/sim/library.hpp"

namespace fs = std::filesystem;
using namespace plr::chooser;

namespace {

const fs::path kData = CHOOSER_TEST_DATA;

class TrainingTest : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = fs::path(::testing::TempDir()) /
           ("plr_chooser_training_" + std::to_string(getpid()) + "_" +
            ::testing::UnitTest::GetInstance()->current_test_info()->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_);
    const plr::sim::Library library = plr::chooser::testing::two_world_library(kData);
    ASSERT_TRUE(plr::sim::save_library(library, dir_ / "library.plrl"));
    std::ofstream(dir_ / "train.yaml")
        << "format: plr-chooser-training\nlibrary: " << (dir_ / "library.plrl").string()
        << "\nout: " << (dir_ / "out").string() << "\ntrain: ["
        << (kData / "floor_row.yaml").string() << ", " << (kData / "two_columns.yaml").string()
        << "]\nvalidation: [" << (kData / "two_columns.yaml").string()
        << "]\nstates_per_world: 2\nrollout_actions: 1\ntie_boxes: 1\nworkers: 2\nfolds: 2\n"
        << "particles: 2\nmass_prior: B1\n";
  }
  void TearDown() override { fs::remove_all(dir_); }

  pid_t start(const std::string& out, const std::string& also = "folds=2") {
    return start(out, std::vector<std::string>{also});
  }
  // `plr chooser train` on the settings, with out= and each override.
  pid_t start(const std::string& out, const std::vector<std::string>& overrides) {
    std::vector<std::string> args = {PLR_CHOOSER_TOOL, "train", (dir_ / "train.yaml").string(),
                                     "--set", "out=" + (dir_ / out).string()};
    for (const auto& o : overrides) args.insert(args.end(), {"--set", o});
    const pid_t pid = fork();
    if (pid == 0) {
      std::vector<char*> argv;
      for (auto& a : args) argv.push_back(a.data());
      argv.push_back(nullptr);
      freopen("/dev/null", "w", stdout);
      execv(PLR_CHOOSER_TOOL, argv.data());
      _exit(127);
    }
    return pid;
  }
  int wait_for(pid_t pid) {
    int status = 0;
    waitpid(pid, &status, 0);
    return status;
  }
  std::vector<std::uint8_t> read(const fs::path& p) {
    std::ifstream in(p, std::ios::binary);
    return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
  }

  std::string read_text(const fs::path& p) {
    const auto bytes = read(p);
    return {bytes.begin(), bytes.end()};
  }

  fs::path dir_;
};

TEST_F(TrainingTest, KilledAndResumedEndsWithTheModelOfAnUndisturbedRun) {
  const int whole = wait_for(start("whole"));
  ASSERT_TRUE(WIFEXITED(whole) && WEXITSTATUS(whole) == 0);
  const auto expected = read(dir_ / "whole" / "model.plrm");
  ASSERT_FALSE(expected.empty());

  // Killed once its first training state is labelled, before it ends.
  const pid_t pid = start("resumed");
  const fs::path data = dir_ / "resumed" / "data.plrd";
  for (;;) {
    if (fs::exists(data)) {
      auto d = load_data_set(data);
      if (d && !d->training.empty()) break;
    }
    int status = 0;
    ASSERT_EQ(waitpid(pid, &status, WNOHANG), 0) << "the training ended before it was killed";
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  kill(pid, SIGKILL);
  wait_for(pid);
  const auto interrupted = load_data_set(data).value();
  const auto whole_data = load_data_set(dir_ / "whole" / "data.plrd").value();
  ASSERT_LT(interrupted.training.size(), whole_data.training.size());

  const int again = wait_for(start("resumed"));
  ASSERT_TRUE(WIFEXITED(again) && WEXITSTATUS(again) == 0);
  EXPECT_EQ(read(dir_ / "resumed" / "model.plrm"), expected);
  const auto resumed = load_data_set(data).value();
  ASSERT_EQ(resumed.training.size(), whole_data.training.size());
  for (std::size_t i = 0; i < resumed.training.size(); ++i) {
    EXPECT_EQ(resumed.training[i].label, whole_data.training[i].label);
    EXPECT_EQ(resumed.training[i].features, whole_data.training[i].features);
  }
  EXPECT_EQ(resumed.iterations.size(), 2u);
  EXPECT_TRUE(fs::exists(dir_ / "resumed" / "validation.svg"));
}

TEST_F(TrainingTest, AnUnknownSettingIsNamedWithItsLine) {
  std::ofstream(dir_ / "train.yaml", std::ios::app) << "rollout_action: 3\n";
  const auto s = TrainingSettings::load(dir_ / "train.yaml");
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("train.yaml:13:1"), std::string::npos) << s.error().message;
  EXPECT_NE(s.error().message.find("rollout_action"), std::string::npos) << s.error().message;
}

TEST_F(TrainingTest, AWorldThatIsNeitherAFamilyNorAFileIsRefused) {
  const auto s = TrainingSettings::load(dir_ / "train.yaml", {"validation=[Z9:1]"});
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("not a family:seed such as A1:3"), std::string::npos)
      << s.error().message;
}

TEST_F(TrainingTest, ParticlesOfAWorldFileNeedAMassPrior) {
  const auto s = TrainingSettings::load(dir_ / "train.yaml", {"mass_prior=Z9"});
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message.find("mass_prior"), std::string::npos) << s.error().message;
  std::string text = read_text(dir_ / "train.yaml");
  text.erase(text.find("mass_prior: B1\n"));
  std::ofstream(dir_ / "train.yaml") << text;
  const auto without = TrainingSettings::load(dir_ / "train.yaml");
  ASSERT_FALSE(without);
  EXPECT_NE(without.error().message.find("floor_row.yaml is a world file; mass_prior names"),
            std::string::npos)
      << without.error().message;
}

TEST_F(TrainingTest, TheFidelityIsASettingFullByDefaultAndNamedWhenWrong) {
  const auto full = TrainingSettings::load(dir_ / "train.yaml");
  ASSERT_TRUE(full) << full.error().message;
  EXPECT_EQ(full->fidelity, plr::sim::Fidelity::kFull);
  const auto fast = TrainingSettings::load(dir_ / "train.yaml", {"fidelity=fast"});
  ASSERT_TRUE(fast) << fast.error().message;
  EXPECT_EQ(fast->fidelity, plr::sim::Fidelity::kFast);
  // Data labelled at another level is not resumed; full's settings read as before it existed.
  EXPECT_NE(fast->hash(1), full->hash(1));
  EXPECT_EQ(full->describe(1).find("fidelity"), std::string::npos);
  std::ofstream(dir_ / "train.yaml", std::ios::app) << "fidelity: quick\n";
  const auto bad = TrainingSettings::load(dir_ / "train.yaml");
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("train.yaml:13:11"), std::string::npos) << bad.error().message;
  EXPECT_NE(bad.error().message.find("fidelity: 'quick'"), std::string::npos)
      << bad.error().message;
  EXPECT_EQ(bad.error().message.find('\n'), std::string::npos) << bad.error().message;
}

TEST_F(TrainingTest, ADataSetOfOtherSettingsIsNotResumed) {
  DataSet d;
  d.settings_hash = 1;
  d.scaling.scale.fill(1.0);
  fs::create_directories(dir_ / "out");
  ASSERT_TRUE(save_data_set(d, dir_ / "out" / "data.plrd"));
  const int status = [&] {
    const pid_t pid = start("out");
    return wait_for(pid);
  }();
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 1);
}

// A model trained on fewer labelled states than min_samples says so; one
// trained on enough does not.
TEST_F(TrainingTest, ADataSetBelowItsMinimumIsReportedNotTrainedOnSilently) {
  const int small = wait_for(start("small", "min_samples=1000"));
  ASSERT_TRUE(WIFEXITED(small) && WEXITSTATUS(small) == 0);
  const auto d = load_data_set(dir_ / "small" / "data.plrd").value();
  ASSERT_FALSE(d.training.empty());
  const auto marked = Model::load(dir_ / "small" / "model.plrm").value();
  EXPECT_NE(marked.made_by().find(std::to_string(d.training.size()) +
                                  " labelled states, below the minimum of 1000 (min_samples)"),
            std::string::npos)
      << marked.made_by();

  const int enough = wait_for(start("enough", "min_samples=1"));
  ASSERT_TRUE(WIFEXITED(enough) && WEXITSTATUS(enough) == 0);
  const auto unmarked = Model::load(dir_ / "enough" / "model.plrm").value();
  EXPECT_EQ(unmarked.made_by().find(kBelowMinimum), std::string::npos) << unmarked.made_by();
}

// DAgger ends once the held-out accuracy stops rising, and not before the
// data set holds min_samples. Four training worlds: the held-out accuracy
// reaches 1 at the second, so the third cannot raise it, and with patience
// 1 the fourth is not labelled.
TEST_F(TrainingTest, TrainingEndsWhenTheHeldOutAccuracyStopsRising) {
  const std::string floor_row = (kData / "floor_row.yaml").string(),
                    two_columns = (kData / "two_columns.yaml").string();
  const std::string four_worlds =
      "train=[" + floor_row + ", " + two_columns + ", " + floor_row + ", " + two_columns + "]";
  std::ofstream(dir_ / "train.yaml", std::ios::app) << "min_samples: 1\n";
  const int all = wait_for(start("all", four_worlds));
  ASSERT_TRUE(WIFEXITED(all) && WEXITSTATUS(all) == 0);
  const auto whole = load_data_set(dir_ / "all" / "data.plrd").value();
  ASSERT_EQ(whole.iterations.size(), 4u);
  ASSERT_EQ(whole.iterations[1].validation_accuracy, 1.0)
      << "the test needs a held-out accuracy that cannot rise after the second iteration";

  std::ofstream(dir_ / "train.yaml", std::ios::app) << "patience: 1\n";
  const int early = wait_for(start("early", four_worlds));
  ASSERT_TRUE(WIFEXITED(early) && WEXITSTATUS(early) == 0);
  const auto ended = load_data_set(dir_ / "early" / "data.plrd").value();
  EXPECT_EQ(ended.iterations.size(), 3u);
  EXPECT_LT(ended.training.size(), whole.training.size());

  // Below its minimum the data set keeps growing, however flat the curve.
  const int small = wait_for(start("small", {four_worlds, "min_samples=1000"}));
  ASSERT_TRUE(WIFEXITED(small) && WEXITSTATUS(small) == 0);
  EXPECT_EQ(load_data_set(dir_ / "small" / "data.plrd").value().iterations.size(), 4u);
}

TEST_F(TrainingTest, RolloutsThatDifferByFewerThanTieBoxesAreNotSamples) {
  // One action from each state moves a handful of boxes at most: with
  // tie_boxes beyond that, every state is a tie and nothing is learnt.
  const int status = wait_for(start("out", "tie_boxes=1000"));
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 1);
  const auto d = load_data_set(dir_ / "out" / "data.plrd").value();
  EXPECT_TRUE(d.validation.empty());
  EXPECT_TRUE(d.training.empty());
  EXPECT_TRUE(fs::exists(dir_ / "out" / "data.plrd"));
}

}  // namespace
