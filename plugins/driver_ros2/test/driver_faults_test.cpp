// The driver against the controller emulator (both plug-ins, real DDS on
// loopback): a motion that runs, and faults that must each end in a safe stop
// and a clear error — feedback lost, e-stop, a trajectory beyond a joint
// limit, a preempting goal, a tolerance violation.
#include <plr/messages.hpp>
#include <plr/ros2/domain.hpp>
#include <plr/ros2/names.hpp>
#include <plr/ros2/wire.hpp>
#include <plr/testing/fake_kernel.hpp>

#include <gtest/gtest.h>
#include <unistd.h>

#include <chrono>
#include <optional>
#include <thread>

namespace {

using namespace std::chrono_literals;
using Outcome = plr::Expected<plr::Message<plr::msg::ExecuteOutcome>>;

constexpr double kHome[] = {0.0, 0.0, -1.0, 2.0, 0.0, 0.5, 0.0, 0.0};

int test_domain() {
  return 100 + static_cast<int>((::getpid() + 50) % 100);
}

class DriverFaults : public ::testing::Test {
 protected:
  void SetUp() override {
    const std::string common = R"("loopback_only": true, "domain_id": )" + std::to_string(domain_);
    auto emulator =
        k_.load_node(EMULATOR_SO, plr::testing::NodeOptions()
                                      .with_name("emulator")
                                      .with_params("{" + common + R"(, "lag_s": 0.02})"));
    ASSERT_TRUE(emulator);
    auto driver =
        k_.load_node(DRIVER_SO, plr::testing::NodeOptions().with_name("driver").with_params(
                                    "{" + common + R"(, "world_execute": "", "watchdog_s": 0.3})"));
    ASSERT_TRUE(driver);
    driver_ = *driver;
    for (auto* n : {&*emulator, &*driver}) {
      ASSERT_TRUE(n->configure());
      ASSERT_TRUE(n->activate());
    }
    auto p = plr::ros2::open_participant(static_cast<std::uint32_t>(domain_), true);
    ASSERT_TRUE(p);
    participant_ = *p;
    const dds_entity_t t =
        dds_create_topic(participant_, &std_msgs_msg_dds__String__desc,
                         "rt/unloader_controller/inject_fault", nullptr, nullptr);
    dds_qos_t* q = plr::ros2::default_qos();
    faults_ = dds_create_writer(participant_, t, q, nullptr);
    dds_delete_qos(q);
    ASSERT_GT(faults_, 0);
    // The driver refuses motion until the first joint state arrives.
    std::this_thread::sleep_for(500ms);
  }
  void TearDown() override {
    if (participant_ > 0) dds_delete(participant_);
  }

  // base_x from home to `x` in `duration` s (controller time = wall time here).
  static flatbuffers::FlatBufferBuilder move_base(double x, double duration, double arm_2 = -1.0) {
    flatbuffers::FlatBufferBuilder fbb;
    std::vector<flatbuffers::Offset<plr::msg::TrajectoryPoint>> pts;
    std::vector<double> q(kHome, kHome + 8), zero(8, 0.0);
    pts.push_back(plr::msg::CreateTrajectoryPointDirect(fbb, 0.0, &q, &zero));
    q[0] = x;
    q[2] = arm_2;
    pts.push_back(plr::msg::CreateTrajectoryPointDirect(fbb, duration, &q, &zero));
    fbb.Finish(plr::msg::CreateExecuteRequest(
        fbb, plr::msg::CreateTrajectory(fbb, fbb.CreateVector(pts))));
    return fbb;
  }

  // base_x to `x` by `duration` s from wherever the joints are: one point,
  // which the controller reaches from its current state.
  static flatbuffers::FlatBufferBuilder move_base_from_here(double x, double duration) {
    flatbuffers::FlatBufferBuilder fbb;
    std::vector<double> q(kHome, kHome + 8), zero(8, 0.0);
    q[0] = x;
    std::vector<flatbuffers::Offset<plr::msg::TrajectoryPoint>> pts = {
        plr::msg::CreateTrajectoryPointDirect(fbb, duration, &q, &zero)};
    fbb.Finish(plr::msg::CreateExecuteRequest(
        fbb, plr::msg::CreateTrajectory(fbb, fbb.CreateVector(pts))));
    return fbb;
  }

  plr::testing::CallHandle<plr::msg::ExecuteOutcome> execute(
      const flatbuffers::FlatBufferBuilder& fbb) {
    auto c =
        k_.call_async<plr::msg::ExecuteRequest, plr::msg::ExecuteOutcome>("sim/execute", fbb, 30s);
    k_.spin();
    return c;
  }

  Outcome wait(const plr::testing::CallHandle<plr::msg::ExecuteOutcome>& c) {
    for (int i = 0; i < 3000 && !c.ready(); ++i) {
      k_.spin();
      std::this_thread::sleep_for(5ms);
    }
    return c.result();
  }

  // Waits until the driver reports the running motion past `fraction`.
  bool wait_progress(double fraction) {
    for (int i = 0; i < 2000; ++i) {
      k_.spin();
      for (const auto& s : k_.published("driver/status"))
        if (const auto* st = s.as<plr::msg::Statistics>(); st && st->stats())
          for (const auto* stat : *st->stats())
            if (stat->key()->str() == "progress" && stat->value() >= fraction) return true;
      std::this_thread::sleep_for(5ms);
    }
    return false;
  }

  void inject(const std::string& fault) {
    plr::ros2::Wire<std_msgs_msg_dds__String_> m(&std_msgs_msg_dds__String__desc);
    m.msg.data = plr::ros2::wire_string(fault);
    ASSERT_EQ(dds_write(faults_, &m.msg), DDS_RETCODE_OK);
  }

  bool logged(const std::string& node, const std::string& text) const {
    for (const auto& l : k_.logs())
      if (l.node == node && l.text.find(text) != std::string::npos) return true;
    return false;
  }

  // Waits (real time) until `node` has logged `text`.
  bool wait_logged(const std::string& node, const std::string& text) const {
    for (int i = 0; i < 400; ++i) {
      if (logged(node, text)) return true;
      std::this_thread::sleep_for(5ms);
    }
    return false;
  }

  int domain_ = test_domain();
  plr::testing::FakeKernel k_;
  std::optional<plr::testing::NodeHandle> driver_;
  dds_entity_t participant_ = 0, faults_ = 0;
};

TEST_F(DriverFaults, AMotionRunsThroughTheEmulatedController) {
  auto r = wait(execute(move_base(0.3, 1.0)));
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_TRUE(r.value()->ok());
  EXPECT_TRUE(logged("emulator", "SUCCEEDED"));
}

// A base move from home by `dx` in `seconds`, with what it asks of the I/O.
void io_motion(flatbuffers::FlatBufferBuilder& fbb, double dx, double seconds,
               plr::msg::Suction before, plr::msg::Suction after, bool conveyor,
               const std::vector<uint8_t>& cups_open = {}) {
  std::vector<double> q(kHome, kHome + 8), zero(8, 0.0);
  std::vector<flatbuffers::Offset<plr::msg::TrajectoryPoint>> pts = {
      plr::msg::CreateTrajectoryPointDirect(fbb, 0.0, &q, &zero)};
  q[0] += dx;
  pts.push_back(plr::msg::CreateTrajectoryPointDirect(fbb, seconds, &q, &zero));
  const auto traj = plr::msg::CreateTrajectory(fbb, fbb.CreateVector(pts));
  const auto cups = cups_open.empty() ? 0 : fbb.CreateVector(cups_open);
  plr::msg::ExecuteRequestBuilder b(fbb);
  b.add_trajectory(traj);
  b.add_suction_before(before);
  b.add_suction_after(after);
  b.add_conveyor(conveyor);
  if (!cups_open.empty()) b.add_cups_open(cups);
  fbb.Finish(b.Finish());
}

// The suction and the conveyor reach the I/O controller (here the emulator,
// as a forward_command_controller) on /io_controller/commands: the vacuum and
// the cup valves before the motion, the vacuum's release after it.
TEST_F(DriverFaults, SuctionAndConveyorGoToTheIoControllerAroundTheMotion) {
  std::vector<uint8_t> cups(20, 1);
  for (int i = 0; i < 4; ++i) cups[static_cast<std::size_t>(i)] = 0;
  flatbuffers::FlatBufferBuilder fbb;
  io_motion(fbb, 0.3, 1.0, plr::msg::Suction::On, plr::msg::Suction::Off, false, cups);
  auto r = wait(execute(fbb));
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_TRUE(
      wait_logged("emulator", "I/O: vacuum on, conveyor stopped, 16 of 20 cup valves open"));
  EXPECT_TRUE(
      wait_logged("emulator", "I/O: vacuum off, conveyor stopped, 16 of 20 cup valves open"));
}

TEST_F(DriverFaults, WithoutAnIoControllerAMotionThatNeedsOneIsRefusedBeforeSending) {
  auto lonely = k_.load_node(
      DRIVER_SO,
      plr::testing::NodeOptions()
          .with_name("lonely")
          .with_remap("sim/execute", "lonely/execute")
          .with_remap("driver/status", "lonely/status")
          .with_params(R"({"loopback_only": true, "world_execute": "", "accept_timeout_s": 0.5, )"
                       R"("io_commands": "/nobody/commands", "domain_id": )" +
                       std::to_string(domain_) + "}"));
  ASSERT_TRUE(lonely);
  ASSERT_TRUE(lonely->configure());
  ASSERT_TRUE(lonely->activate());
  std::this_thread::sleep_for(500ms);  // its first joint state
  auto c = k_.call_async<plr::msg::ExecuteRequest, plr::msg::ExecuteOutcome>(
      "lonely/execute", move_base(0.3, 1.0), 30s);
  const auto r = wait(c);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("no I/O controller subscribes to '/nobody/commands'"),
            std::string::npos)
      << r.error().message;
  EXPECT_FALSE(logged("emulator", "goal"));  // the controller never heard of the motion
}

TEST_F(DriverFaults, ATrajectoryBeyondAJointLimitIsRefusedBeforeSending) {
  // arm_2's URDF limits are [-2.2, 1.3].
  auto r = wait(execute(move_base(0.3, 1.0, /*arm_2=*/1.6)));
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("refused before sending: trajectory point 1 (t=1.000 s), joint "
                                   "arm_2: position 1.6000 outside its limits"),
            std::string::npos)
      << r.error().message;
  std::this_thread::sleep_for(200ms);
  EXPECT_FALSE(logged("emulator", "goal"));  // the controller never heard of it
}

TEST_F(DriverFaults, ATrajectoryStartingAwayFromTheJointsIsRefusedBeforeSending) {
  flatbuffers::FlatBufferBuilder fbb;
  std::vector<double> q(kHome, kHome + 8), zero(8, 0.0);
  q[0] = 0.3;  // the joints are at home, base_x 0
  std::vector<flatbuffers::Offset<plr::msg::TrajectoryPoint>> pts = {
      plr::msg::CreateTrajectoryPointDirect(fbb, 0.0, &q, &zero),
      plr::msg::CreateTrajectoryPointDirect(fbb, 1.0, &q, &zero)};
  fbb.Finish(
      plr::msg::CreateExecuteRequest(fbb, plr::msg::CreateTrajectory(fbb, fbb.CreateVector(pts))));
  auto r = wait(execute(fbb));
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("refused before sending: the trajectory starts 0.3000 from "
                                   "joint base_x (start tolerance 0.0100)"),
            std::string::npos)
      << r.error().message;
  EXPECT_FALSE(logged("emulator", "goal"));
}

TEST_F(DriverFaults, FeedbackLostMidTrajectoryStopsTheRobot) {
  auto c = execute(move_base(0.5, 2.0));
  ASSERT_TRUE(wait_progress(0.2));
  inject("drop_feedback");
  auto r = wait(c);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("joint state on /joint_states stale for"), std::string::npos)
      << r.error().message;
  EXPECT_NE(r.error().message.find("stopped"), std::string::npos);
  // The cancel reached the controller: it holds the joints where they are.
  EXPECT_TRUE(logged("emulator", "CANCELED"));
}

TEST_F(DriverFaults, EStopMidTrajectoryHaltsAndRefusesMotionUntilReset) {
  auto c = execute(move_base(0.5, 2.0));
  ASSERT_TRUE(wait_progress(0.2));
  flatbuffers::FlatBufferBuilder stop;
  stop.Finish(plr::msg::CreateEStopDirect(stop, true, "operator"));
  ASSERT_TRUE(k_.publish<plr::msg::EStop>("estop", stop));
  auto r = wait(c);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("e-stop engaged (operator): halted mid-trajectory"),
            std::string::npos)
      << r.error().message;
  EXPECT_TRUE(logged("emulator", "CANCELED"));

  auto refused = wait(execute(move_base_from_here(0.1, 1.0)));
  ASSERT_FALSE(refused);
  EXPECT_NE(refused.error().message.find("motion refused until it is reset"), std::string::npos);

  flatbuffers::FlatBufferBuilder reset;
  reset.Finish(plr::msg::CreateEStopDirect(reset, false, "checked"));
  ASSERT_TRUE(k_.publish<plr::msg::EStop>("estop", reset));
  k_.spin();
  auto again = wait(execute(move_base_from_here(0.1, 1.0)));
  EXPECT_TRUE(again) << again.error().message;
}

// The belt stops with the robot; the vacuum stays on (a held box is not
// dropped).
TEST_F(DriverFaults, EStopStopsTheConveyorAndKeepsTheVacuum) {
  flatbuffers::FlatBufferBuilder fbb;
  io_motion(fbb, 0.5, 2.0, plr::msg::Suction::On, plr::msg::Suction::Keep, true);
  auto c = execute(fbb);
  ASSERT_TRUE(wait_progress(0.2));
  ASSERT_TRUE(wait_logged("emulator", "I/O: vacuum on, conveyor running"));
  flatbuffers::FlatBufferBuilder stop;
  stop.Finish(plr::msg::CreateEStopDirect(stop, true, "operator"));
  ASSERT_TRUE(k_.publish<plr::msg::EStop>("estop", stop));
  EXPECT_FALSE(wait(c));
  EXPECT_TRUE(wait_logged("emulator", "I/O: vacuum on, conveyor stopped"));
}

TEST_F(DriverFaults, ANewMotionPreemptsTheRunningOne) {
  auto first = execute(move_base(0.5, 3.0));
  ASSERT_TRUE(wait_progress(0.1));
  auto second = execute(move_base_from_here(0.2, 1.0));
  auto r1 = wait(first);
  ASSERT_FALSE(r1);
  EXPECT_NE(r1.error().message.find("preempted by a newer motion"), std::string::npos)
      << r1.error().message;
  auto r2 = wait(second);
  EXPECT_TRUE(r2) << r2.error().message;
}

TEST_F(DriverFaults, ATolerenceViolationAbortsHoldingPosition) {
  auto c = execute(move_base(0.5, 2.0));
  ASSERT_TRUE(wait_progress(0.2));
  inject("tolerance_violation arm_3 0.4");
  auto r = wait(c);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("controller ended the goal ABORTED: PATH_TOLERANCE_VIOLATED"),
            std::string::npos)
      << r.error().message;
  EXPECT_NE(r.error().message.find("joint arm_3"), std::string::npos);
}

TEST_F(DriverFaults, DeactivatingTheDriverMidTrajectoryStopsTheRobot) {
  auto c = execute(move_base(0.5, 2.0));
  ASSERT_TRUE(wait_progress(0.2));
  ASSERT_TRUE(driver_->deactivate());
  auto r = wait(c);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("the driver was deactivated: halted mid-trajectory"),
            std::string::npos)
      << r.error().message;
  EXPECT_TRUE(logged("emulator", "CANCELED"));
}

TEST_F(DriverFaults, ALateStartIsCaughtByThePathTolerance) {
  inject("late_start 1.0");
  std::this_thread::sleep_for(100ms);
  auto r = wait(execute(move_base(0.5, 2.0)));
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("PATH_TOLERANCE_VIOLATED"), std::string::npos)
      << r.error().message;
}

}  // namespace
