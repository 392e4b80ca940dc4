#include "plr/sim/robot_model.hpp"
#include "plr/sim/shipped_files.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <stdexcept>

using plr::sim::JointVector;
using plr::sim::load_robot;
using plr::sim::RobotModel;

namespace {

const RobotModel& robot() {
  static const RobotModel m = load_robot().value();
  return m;
}

std::string error_of(const std::string& xml) {
  const auto model = RobotModel::from_urdf_string(xml, "bad.urdf");
  return model ? "" : model.error().message;
}

}  // namespace

TEST(RobotModel, LoadsShippedUrdf) {
  const RobotModel& m = robot();
  EXPECT_GE(m.links().size(), 10u);
  EXPECT_GE(m.plate_link(), 0);
  for (int j = 0; j < plr::sim::kNumJoints; ++j) {
    EXPECT_LT(m.limits(j).lower, m.limits(j).upper) << j;
    EXPECT_GT(m.limits(j).velocity, 0.0) << j;
    EXPECT_GT(m.limits(j).acceleration, 0.0) << j;
  }
  for (const auto& l : m.links()) {
    if (l.name != "ground") {
      EXPECT_FALSE(l.shapes.empty()) << l.name;
    }
  }
}

TEST(RobotModel, ZeroConfigurationPlatePose) {
  // Arm stretched forward: plate at yaw origin + upper + fore + plate along x.
  const RobotModel& m = robot();
  JointVector q = JointVector::Zero();
  q[plr::sim::kBaseX] = 2.0;
  const auto& a = m.arm();
  const Eigen::Vector3d p = m.plate_pose(q).translation();
  EXPECT_NEAR(p.x(), 2.0 + a.yaw_origin.x() + a.upper + a.fore + a.plate, 1e-9);
  EXPECT_NEAR(p.y(), 0.0, 1e-9);
  EXPECT_NEAR(p.z(), a.yaw_origin.z() + a.shoulder_height, 1e-9);
}

TEST(RobotModel, ReachesFloorToCeilingAcrossTheWidth) {
  const RobotModel& m = robot();
  JointVector seed = JointVector::Zero();
  for (double y : {-1.0, 0.0, 1.0}) {
    for (double z : {0.2, 1.3, 2.5}) {
      const auto sols = m.arm_ik({Eigen::Vector3d(1.2, y, z), 0.0}, seed);
      EXPECT_FALSE(sols.empty()) << "y=" << y << " z=" << z;
    }
  }
}

TEST(RobotModel, IkInvertsFkOnRandomConfigurations) {
  const RobotModel& m = robot();
  std::mt19937 rng(7);
  int checked = 0;
  for (int i = 0; i < 500; ++i) {
    JointVector q;
    for (int j = 0; j < plr::sim::kNumJoints; ++j) {
      std::uniform_real_distribution<double> u(m.limits(j).lower, m.limits(j).upper);
      q[j] = u(rng);
    }
    const auto target = m.plate_target(q);
    // The arm reaching back over itself is the turned-away branch; both are covered.
    const auto sols = m.arm_ik(target, q);
    ASSERT_FALSE(sols.empty()) << "no IK for a reachable FK pose, i=" << i;
    bool found_original = false;
    for (const JointVector& s : sols) {
      EXPECT_TRUE(m.within_limits(s));
      const auto back = m.plate_target(s);
      EXPECT_LT((back.position - target.position).norm(), 1e-7);
      EXPECT_NEAR(std::remainder(back.yaw - target.yaw, 2 * M_PI), 0.0, 1e-7);
      EXPECT_TRUE(m.plate_pose(s).linear().isApprox(m.plate_pose(q).linear(), 1e-6));
      if ((s - q).norm() < 1e-6) found_original = true;
    }
    EXPECT_TRUE(found_original) << "i=" << i;
    ++checked;
  }
  EXPECT_EQ(checked, 500);
}

TEST(RobotModel, PlateStaysVerticalWhateverTheArmDoes) {
  // The parallelogram keeps the wrist level: the plate's normal is
  // horizontal and its yaw is arm_1 + arm_4.
  const RobotModel& m = robot();
  std::mt19937 rng(11);
  for (int i = 0; i < 200; ++i) {
    JointVector q;
    for (int j = 0; j < plr::sim::kNumJoints; ++j) {
      std::uniform_real_distribution<double> u(m.limits(j).lower, m.limits(j).upper);
      q[j] = u(rng);
    }
    const Eigen::Matrix3d r = m.plate_pose(q).linear();
    EXPECT_NEAR(r.col(0).z(), 0.0, 1e-9) << "i=" << i;
    EXPECT_NEAR(r.col(2).z(), 1.0, 1e-9) << "i=" << i;
    EXPECT_NEAR(
        std::remainder(m.plate_target(q).yaw - q[plr::sim::kArm1] - q[plr::sim::kArm4], 2 * M_PI),
        0.0, 1e-9);
  }
}

TEST(RobotModel, FacesEveryColumnSquarelyFromBehindTheLoweredNose) {
  // Base 1.1 m short of a wall face (the lowered nose's length plus a
  // margin): the plate reaches every face of the wall square on, at the
  // grasp and at the pre-grasp 0.25 m back, from the floor to under the
  // ceiling and out to the side walls.
  const RobotModel& m = robot();
  JointVector seed = JointVector::Zero();
  const double face_x = 1.1;
  for (double y : {-0.97, -0.5, 0.0, 0.5, 0.97}) {
    for (double z : {0.3, 0.8, 1.3, 1.9, 2.47}) {
      for (double back : {0.005, 0.25}) {
        const auto sols = m.arm_ik({Eigen::Vector3d(face_x - back, y, z), 0.0}, seed);
        EXPECT_FALSE(sols.empty()) << "y=" << y << " z=" << z << " back=" << back;
      }
    }
  }
}

TEST(RobotModel, UnreachableTargetHasNoSolution) {
  EXPECT_TRUE(robot().arm_ik({Eigen::Vector3d(6.0, 0.0, 1.0), 0.0}, JointVector::Zero()).empty());
}

TEST(RobotModel, MissingFileNamesFileAndCause) {
  const auto model = RobotModel::from_urdf_file("/nonexistent/robot.urdf");
  ASSERT_FALSE(model);
  EXPECT_EQ(model.error().message, "/nonexistent/robot.urdf: cannot open file");
}

TEST(RobotModel, XmlSyntaxErrorGivesLine) {
  const std::string msg = error_of("<robot name='r'>\n<link name='a'>\n</robot>");
  EXPECT_EQ(msg.rfind("bad.urdf: XML error at line", 0), 0u) << msg;
}

// 60,000 nested elements overflowed the parser's stack (SIGSEGV).
TEST(RobotModel, DeepNestingIsRefusedBeforeParsing) {
  std::string xml = "<robot name='r'>\n<link name='a'>";
  for (int i = 0; i < 60000; ++i) xml += "<visual a='>'>";
  for (int i = 0; i < 60000; ++i) xml += "</visual>";
  xml += "</link></robot>";
  EXPECT_EQ(error_of(xml), "bad.urdf: line 2: elements nested deeper than 32 levels");
  // Comments, declarations and empty elements do not count.
  std::string flat = "<?xml version='1.0'?>\n<!-- <a><b><c> -->\n<robot name='r'>";
  for (int i = 0; i < 100; ++i) flat += "<link name='l" + std::to_string(i) + "'/>";
  flat += "</robot>";
  EXPECT_EQ(error_of(flat).find("nested deeper"), std::string::npos) << error_of(flat);
}

// TinyXML read past the text for a multi-byte UTF-8 sequence cut short at
// its end (fuzzing, ASan: heap-buffer-overflow in TiXmlBase::ReadName).
TEST(RobotModel, TextThatIsNotUtf8IsRefusedBeforeParsing) {
  const std::string head = "<robot name='r'>\n<link name='a'/>\n<link ";
  EXPECT_EQ(error_of(head + "\xDA"), "bad.urdf: line 3: not UTF-8 text");
  EXPECT_EQ(error_of(head + "name='\xE5\x80'/></robot>"), "bad.urdf: line 3: not UTF-8 text");
  EXPECT_EQ(error_of(head + std::string("name='b'/>\0</robot>", 19)),
            "bad.urdf: line 3: not UTF-8 text");
  // Well-formed multi-byte text passes this check (and fails later, or not at all).
  EXPECT_EQ(error_of(head + "name='\xC3\xA9'/></robot>").find("UTF-8"), std::string::npos);
}

// urdfdom leaked the model it built for joints that do not make a tree (fuzzing).
TEST(RobotModel, JointsThatDoNotMakeATreeAreRefused) {
  const std::string head = "<robot name='r'><link name='a'/><link name='b'/>";
  const auto joint = [](const char* name, const char* parent, const char* child) {
    return std::string("<joint name='") + name + "' type='fixed'><parent link='" + parent +
           "'/><child link='" + child + "'/></joint>";
  };
  EXPECT_EQ(error_of(head + joint("j1", "a", "b") + joint("j2", "a", "b") + "</robot>"),
            "bad.urdf: line 1: link 'b' is the child of joints 'j1' and 'j2'");
  EXPECT_EQ(error_of(head + joint("j1", "a", "b") + joint("j2", "b", "a") + "</robot>"),
            "bad.urdf: the joints make a loop through link 'a'");
}

// /dev/zero as a URDF read until memory ran out.
TEST(RobotModel, AnEndlessFileIsRefusedAtTheSizeBound) {
  const auto model = RobotModel::from_urdf_file("/dev/zero");
  ASSERT_FALSE(model);
  EXPECT_EQ(model.error().message, "/dev/zero: larger than 8388608 bytes");
}

TEST(RobotModel, MissingJointIsNamed) {
  const std::string msg = error_of("<robot name='r'><link name='a'/></robot>");
  EXPECT_EQ(msg, "bad.urdf: missing joint 'base_x'");
}

TEST(RobotModel, UrdfdomRejectionCarriesItsReason) {
  const std::string msg = error_of(
      "<robot name='r'><link name='a'/><joint name='j' type='revolute'><parent link='a'/>"
      "<child link='nope'/></joint></robot>");
  EXPECT_EQ(msg.rfind("bad.urdf: invalid URDF: ", 0), 0u) << msg;
  EXPECT_GT(msg.size(), std::string("bad.urdf: invalid URDF: ").size());
}

namespace {
std::string shipped_urdf() {
  std::ifstream in(plr::sim::shipped_file("robots/unloader.urdf").value());
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}
}  // namespace

TEST(RobotModel, MovableJointThatIsNeitherPlannedNorMimicIsNamed) {
  std::string xml = shipped_urdf();
  const std::string mimic = "<mimic joint=\"arm_2\" multiplier=\"-1\" offset=\"0\"/>";
  const auto pos = xml.find(mimic);
  ASSERT_NE(pos, std::string::npos);
  xml.erase(pos, mimic.size());
  EXPECT_EQ(error_of(xml),
            "bad.urdf: joint 'arm_level_2' is movable but neither one of the 8 planned joints "
            "nor a <mimic> of one");
}

TEST(RobotModel, WristThatDoesNotStayLevelIsRefused) {
  std::string xml = shipped_urdf();
  const std::string mimic = "<mimic joint=\"arm_3\" multiplier=\"-1\"";
  const auto pos = xml.find(mimic);
  ASSERT_NE(pos, std::string::npos);
  xml.replace(pos, mimic.size(), "<mimic joint=\"arm_3\" multiplier=\"-0.5\"");
  EXPECT_EQ(error_of(xml).rfind("bad.urdf: arm_4 must sit on a level flange", 0), 0u)
      << error_of(xml);
}

TEST(RobotModel, MissingAccelerationLimitIsNamed) {
  std::string xml = shipped_urdf();
  const auto pos = xml.find("<acceleration_limit value=\"2.5\"/>");
  ASSERT_NE(pos, std::string::npos);
  xml.erase(pos, std::string("<acceleration_limit value=\"2.5\"/>").size());
  EXPECT_EQ(error_of(xml), "bad.urdf: joint 'arm_1' has no positive <acceleration_limit value=..>");
}
