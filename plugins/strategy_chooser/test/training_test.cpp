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
    const pid_t pid = fork();
    if (pid == 0) {
      const std::string settings = (dir_ / "train.yaml").string(),
                        set = "out=" + (dir_ / out).string();
      freopen("/dev/null", "w", stdout);
      execl(PLR_CHOOSER_TOOL, PLR_CHOOSER_TOOL, "train", settings.c_str(), "--set", set.c_str(),
            "--set", also.c_str(), static_cast<char*>(nullptr));
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
