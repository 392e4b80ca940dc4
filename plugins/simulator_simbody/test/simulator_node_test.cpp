// The simulator plug-in in the fake kernel: its services on a small world
// file, snapshot/restore through the service, and bad requests answered with
// a clear error.
#include <gtest/gtest.h>
#include <unistd.h>

#include <plr/messages.hpp>
#include <plr/testing/fake_kernel.hpp>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace plr {
namespace {

using testing::FakeKernel;
using testing::NodeOptions;

class SimulatorService : public ::testing::Test {
 protected:
  void SetUp() override {
    auto n = kernel_.load_node(SIMULATOR_SO, NodeOptions().with_params(params()));
    ASSERT_TRUE(n) << n.error().message;
    node_ = *n;
    ASSERT_TRUE(node_->configure());
    ASSERT_TRUE(node_->activate());
  }

  Expected<Message<msg::WorldState>> reset(const std::string& env, const std::string& file) {
    flatbuffers::FlatBufferBuilder fbb;
    fbb.Finish(msg::CreateResetRequestDirect(fbb, env.c_str(), 0, file.c_str()));
    return kernel_.call<msg::ResetRequest, msg::WorldState>("sim/reset", fbb,
                                                            std::chrono::seconds(60));
  }

  Expected<Message<msg::WorldState>> observe(bool true_state) {
    flatbuffers::FlatBufferBuilder fbb;
    fbb.Finish(msg::CreateObserveRequest(fbb, true_state));
    return kernel_.call<msg::ObserveRequest, msg::WorldState>("sim/observe", fbb);
  }

  // The robot waits at `q` from t = 0 to `duration` (the boxes keep moving).
  Expected<Message<msg::ExecuteOutcome>> execute(const std::vector<std::vector<double>>& qs,
                                                 const std::vector<double>& times) {
    flatbuffers::FlatBufferBuilder fbb;
    std::vector<flatbuffers::Offset<msg::TrajectoryPoint>> points;
    for (std::size_t i = 0; i < qs.size(); ++i) {
      points.push_back(msg::CreateTrajectoryPointDirect(fbb, times[i], &qs[i]));
    }
    const auto traj = msg::CreateTrajectoryDirect(fbb, &points);
    fbb.Finish(
        msg::CreateExecuteRequest(fbb, traj, msg::Suction::Keep, msg::Suction::Keep, false, 0.0));
    return kernel_.call<msg::ExecuteRequest, msg::ExecuteOutcome>("sim/execute", fbb,
                                                                  std::chrono::seconds(60));
  }

  Expected<Message<msg::SnapshotReply>> snapshot(const std::string& service,
                                                 const std::string& name) {
    flatbuffers::FlatBufferBuilder fbb;
    fbb.Finish(msg::CreateSnapshotRequestDirect(fbb, name.c_str()));
    return kernel_.call<msg::SnapshotRequest, msg::SnapshotReply>(service, fbb);
  }

  static std::vector<double> home() { return {0.0, 0.0, -1.0, 2.0, 0.0, 0.5, 0.0, 0.0}; }
  virtual std::string params() const { return "{}"; }

  FakeKernel kernel_;
  std::optional<testing::NodeHandle> node_;
};

TEST_F(SimulatorService, ObserveBeforeResetAnswersAnEmptyTrailer) {
  const auto w = observe(false);
  ASSERT_TRUE(w) << w.error().message;
  EXPECT_EQ(w.value()->boxes()->size(), 0u);
}

TEST_F(SimulatorService, ServicesBeforeResetSayWhatIsMissing) {
  const auto e = execute({home(), home()}, {0.0, 0.1});
  ASSERT_FALSE(e);
  EXPECT_EQ(e.error().message, "no world yet: call sim/reset first");
  const auto s = snapshot("sim/snapshot", "a");
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().message, "no world yet: call sim/reset first");
  const auto r = snapshot("sim/restore", "a");
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().message, "no snapshot named 'a'");
}

TEST_F(SimulatorService, BadResetRequestsNameTheProblem) {
  const auto family = reset("C7", "");
  ASSERT_FALSE(family);
  EXPECT_EQ(family.error().message, "env 'C7': expected A1, A2, B1, B2, C, D1, D2 or D3");
  const auto file = reset("", "/nonexistent/world.yaml");
  ASSERT_FALSE(file);
  EXPECT_EQ(file.error().message,
            "/nonexistent/world.yaml: cannot read the world: No such file or directory");
  // A perceived world (masses unknown) is a valid world file, but not one to simulate.
  const auto perceived =
      std::filesystem::temp_directory_path() / ("plr_perceived_" + std::to_string(::getpid()));
  std::ofstream(perceived) << "format: plr-world\nversion: 1\n"
                              "trailer: {width: 2.5, height: 2.7, depth: 16}\n"
                              "boxes:\n  - {id: 4, size: [1, 1, 1], position: [4, 0, 0.5]}\n";
  const auto massless = reset("", perceived.string());
  std::filesystem::remove(perceived);
  ASSERT_FALSE(massless);
  EXPECT_EQ(massless.error().message,
            "Simulation: box 4 has no mass (the simulator needs the true world)");
}

TEST_F(SimulatorService, ResetFromAFileThenObservePerceivedAndTrueState) {
  const auto w = reset("", SMALL_WORLD);
  ASSERT_TRUE(w) << w.error().message;
  ASSERT_EQ(w.value()->boxes()->size(), 30u);
  EXPECT_DOUBLE_EQ(w.value()->trailer_size()->z(), 8.0);
  EXPECT_FALSE(w.value()->is_true_state());
  EXPECT_GT(w.value()->octree()->size(), 0u);
  for (const auto* b : *w.value()->boxes()) EXPECT_EQ(b->mass(), 0.0) << "box " << b->id();

  const auto t = observe(true);
  ASSERT_TRUE(t) << t.error().message;
  EXPECT_TRUE(t.value()->is_true_state());
  for (const auto* b : *t.value()->boxes()) EXPECT_GT(b->mass(), 0.0) << "box " << b->id();
  // The reset published the world and the progress.
  EXPECT_FALSE(kernel_.published("world").empty());
  EXPECT_FALSE(kernel_.published("progress").empty());
}

TEST_F(SimulatorService, BadTrajectoriesAreRefusedWithTheReason) {
  ASSERT_TRUE(reset("", SMALL_WORLD));
  const auto short_point = execute({home(), {0.0, 0.0, -1.0}}, {0.0, 0.1});
  ASSERT_FALSE(short_point);
  EXPECT_EQ(short_point.error().message,
            "ExecuteRequest.trajectory: every point needs 8 positions");
  const auto backwards = execute({home(), home()}, {0.5, 0.1});
  ASSERT_FALSE(backwards);
  EXPECT_EQ(backwards.error().message, "ExecuteRequest.trajectory: times must not decrease");
  // Planned from another state: the robot would jump to its first point.
  auto elsewhere = home();
  elsewhere[0] += 0.5;
  const auto jump = execute({elsewhere, elsewhere}, {0.0, 0.1});
  ASSERT_FALSE(jump);
  EXPECT_EQ(jump.error().code, PLR_ERR_STATE);
  EXPECT_EQ(jump.error().message,
            "the trajectory starts 0.5000 (rad or m) away from the robot's "
            "configuration");
}

TEST_F(SimulatorService, RestoreThroughTheServiceGoesBackInTime) {
  ASSERT_TRUE(reset("", SMALL_WORLD));
  const auto saved = snapshot("sim/snapshot", "before");
  ASSERT_TRUE(saved) << saved.error().message;
  EXPECT_TRUE(saved.value()->ok());
  const auto w0 = observe(true);
  ASSERT_TRUE(w0);
  const double t0 = static_cast<double>(w0.value()->stamp_ns()) * 1e-9;

  // The base drives 1 m into the trailer.
  std::vector<double> forward = home();
  forward[0] = 1.0;
  const auto out = execute({home(), forward}, {0.0, 2.0});
  ASSERT_TRUE(out) << out.error().message;
  EXPECT_TRUE(out.value()->ok());
  EXPECT_NEAR(out.value()->sim_time_s(), t0 + 2.0, 0.02);
  const auto moved = observe(true);
  ASSERT_TRUE(moved);
  EXPECT_DOUBLE_EQ(moved.value()->robot()->positions()->Get(0), 1.0);

  const auto back = snapshot("sim/restore", "before");
  ASSERT_TRUE(back) << back.error().message;
  const auto w1 = observe(true);
  ASSERT_TRUE(w1);
  EXPECT_EQ(w1.value()->stamp_ns(), w0.value()->stamp_ns());
  EXPECT_DOUBLE_EQ(w1.value()->robot()->positions()->Get(0), 0.0);
  ASSERT_EQ(w1.value()->boxes()->size(), w0.value()->boxes()->size());
  for (flatbuffers::uoffset_t i = 0; i < w0.value()->boxes()->size(); ++i) {
    const auto* a = w0.value()->boxes()->Get(i);
    const auto* b = w1.value()->boxes()->Get(i);
    EXPECT_EQ(a->id(), b->id());
    EXPECT_EQ(a->pose().position().x(), b->pose().position().x());
    EXPECT_EQ(a->pose().position().z(), b->pose().position().z());
  }
  const auto unknown = snapshot("sim/restore", "never-saved");
  ASSERT_FALSE(unknown);
  EXPECT_EQ(unknown.error().message, "no snapshot named 'never-saved'");
}

// A live view moves with the robot: the world is published during a motion,
// not only at its end, and a motion can be held to real time.
class SimulatorLiveFrames : public SimulatorService {
 protected:
  std::string params() const override { return R"({"frame_rate_hz": 20, "real_time_factor": 1})"; }
};

TEST_F(SimulatorLiveFrames, TheWorldIsPublishedWhileTheBaseDrivesInRealTime) {
  ASSERT_TRUE(reset("", SMALL_WORLD));
  kernel_.clear_published();
  std::vector<double> forward = home();
  forward[0] = 0.6;
  const auto out = execute({home(), forward}, {0.0, 1.0});
  ASSERT_TRUE(out) << out.error().message;

  // About 20 frames during the motion and one at its end; the base moves
  // forward through them. Frames are published at most 20 times a wall
  // second: that many, with the middle one halfway, show the motion held to
  // real time (unheld, the second of motion takes ~60 ms and gives two).
  const auto frames = kernel_.published("world");
  ASSERT_GE(frames.size(), 8u);
  double base = -1.0;
  std::int64_t stamp = -1;
  for (const auto& f : frames) {
    const auto* w = f.as<msg::WorldState>();
    ASSERT_NE(w, nullptr);
    ASSERT_EQ(w->boxes()->size(), 30u);
    const double x = w->robot()->positions()->Get(0);
    EXPECT_GE(x, base);
    EXPECT_GE(w->stamp_ns(), stamp);  // the last frame and the end state may coincide
    base = x;
    stamp = w->stamp_ns();
  }
  const double middle =
      frames[frames.size() / 2].as<msg::WorldState>()->robot()->positions()->Get(0);
  EXPECT_GT(middle, 0.1);
  EXPECT_LT(middle, 0.5);
  EXPECT_DOUBLE_EQ(base, 0.6);
}

// control_period_s: 1e-7 made sim/execute never return; an octree at 0.1 mm
// grew until the process was killed.
TEST(SimulatorParams, RatesAndResolutionsAreBounded) {
  for (const auto& [params, message] :
       {std::pair{R"({"control_period_s": 1e-7})",
                  "param 'control_period_s': must be between 0.001 and 0.1, got 1e-07"},
        std::pair{R"({"octree_resolution": 0.0001})",
                  "param 'octree_resolution': must be between 0.01 and 0.5, got 0.0001"},
        std::pair{R"({"frame_rate_hz": 1e6})",
                  "param 'frame_rate_hz': must be between 0 and 100, got 1000000"}}) {
    FakeKernel kernel;
    auto node = kernel.load_node(SIMULATOR_SO, NodeOptions().with_params(params));
    ASSERT_TRUE(node) << node.error().message;
    const Status configured = node->configure();
    ASSERT_FALSE(configured);
    EXPECT_EQ(configured.error().message, message);
  }
}

// The fidelity is a word: the three levels configure, others name the value.
TEST(SimulatorParams, FidelityIsFullAdaptiveOrFast) {
  for (const auto& [params, message] :
       {std::pair{R"({"fidelity": "adaptive"})", ""}, std::pair{R"({"fidelity": "fast"})", ""},
        std::pair{R"({"fidelity": "exact"})",
                  "param fidelity: 'exact' is not one of full, adaptive, fast"}}) {
    FakeKernel kernel;
    auto node = kernel.load_node(SIMULATOR_SO, NodeOptions().with_params(params));
    ASSERT_TRUE(node) << node.error().message;
    const Status configured = node->configure();
    if (std::string(message).empty()) {
      EXPECT_TRUE(configured) << configured.error().message;
    } else {
      ASSERT_FALSE(configured);
      EXPECT_EQ(configured.error().message, message);
    }
  }
}

// A checkpoint on disk says how many bytes the folder holds once written: a
// long run compares them at the same state (a trailer's start) to see the
// checkpoint grow, or not.
class SimulatorCheckpointOnDisk : public SimulatorService {
 protected:
  void TearDown() override { std::filesystem::remove_all(dir_); }
  std::string params() const override { return R"({"checkpoint_dir": ")" + dir_.string() + "\"}"; }
  std::uintmax_t folder_bytes() const {
    std::uintmax_t bytes = 0;
    for (const auto& f : std::filesystem::recursive_directory_iterator(dir_))
      if (f.is_regular_file()) bytes += f.file_size();
    return bytes;
  }

  std::filesystem::path dir_ = std::filesystem::temp_directory_path() /
                               ("plr_sim_checkpoint_bytes_" + std::to_string(::getpid()));
};

TEST_F(SimulatorCheckpointOnDisk, TheReplySaysTheFoldersBytesTheSameForTheSameState) {
  ASSERT_TRUE(reset("", SMALL_WORLD));
  const auto start = snapshot("sim/snapshot", "checkpoint");
  ASSERT_TRUE(start) << start.error().message;
  ASSERT_TRUE(start.value()->ok());
  EXPECT_GT(start.value()->checkpoint_bytes(), 0u);
  EXPECT_EQ(start.value()->checkpoint_bytes(), folder_bytes());

  std::vector<double> forward = home();
  forward[0] = 1.0;
  ASSERT_TRUE(execute({home(), forward}, {0.0, 2.0}));
  const auto moved = snapshot("sim/snapshot", "checkpoint");
  ASSERT_TRUE(moved);
  EXPECT_EQ(moved.value()->checkpoint_bytes(), folder_bytes());

  ASSERT_TRUE(reset("", SMALL_WORLD));
  const auto again = snapshot("sim/snapshot", "checkpoint");
  ASSERT_TRUE(again);
  EXPECT_EQ(again.value()->checkpoint_bytes(), start.value()->checkpoint_bytes());

  // What is not kept on disk says 0.
  const auto in_memory = snapshot("sim/snapshot", "before");
  ASSERT_TRUE(in_memory);
  EXPECT_EQ(in_memory.value()->checkpoint_bytes(), 0u);
}

TEST(SimulatorCheckpoint, ADamagedOneFailsConfigureWithTheFilesError) {
  const auto dir =
      std::filesystem::temp_directory_path() / ("plr_sim_checkpoint_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "state.json") << "{}";  // and no world.yaml
  FakeKernel kernel;
  auto node = kernel.load_node(
      SIMULATOR_SO, NodeOptions().with_params(R"({"checkpoint_dir": ")" + dir.string() + "\"}"));
  ASSERT_TRUE(node) << node.error().message;
  const Status configured = node->configure();
  std::filesystem::remove_all(dir);
  ASSERT_FALSE(configured);
  EXPECT_EQ(configured.error().message,
            (dir / "world.yaml").string() + ": cannot read the world: No such file or directory");
}

}  // namespace
}  // namespace plr
