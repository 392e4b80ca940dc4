#include "plr/planning/testing/planner_conformance.hpp"

#include <plr/messages.hpp>
#include <plr/testing/conformance.hpp>
#include <plr/testing/fake_kernel.hpp>

#include <fcl/fcl.h>
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <functional>
#include <optional>

#include "plr/planning/plan_messages.hpp"
#include "plr/sim/collision.hpp"

namespace plr::planning::testing {
namespace {

using plr::testing::FakeKernel;
using plr::testing::NodeOptions;
using sim::Box;
using sim::JointVector;
using sim::World;
using namespace sim;  // joint indices

const RobotModel& robot() {
  static const RobotModel m = load_robot().value();
  return m;
}

// A wall of 0.4 m boxes across the trailer, front face at x = face: 5
// columns, the middle one on the trailer's axis.
World wall(double face, int rows = 5) {
  World w;
  std::uint32_t id = 1;
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < 5; ++c) {
      Box b;
      b.id = id++;
      b.size = Eigen::Vector3d(0.4, 0.4, 0.4);
      b.pose.translation() = Eigen::Vector3d(face + 0.2, 0.405 * (c - 2), 0.2 + 0.405 * r);
      w.boxes.push_back(b);
    }
  }
  return w;
}

// Box in row r (from the floor), column c (0..4, 2 centred).
const Box& at(const World& w, int r, int c) {
  return w.boxes[static_cast<std::size_t>(5 * r + c)];
}

PlanQuery pose_query(PlanMode mode, const JointVector& start, const Eigen::Vector3d& p,
                     double yaw) {
  PlanQuery q;
  q.mode = mode;
  q.start = start;
  PoseGoal g;
  g.target = {p, yaw};
  q.goal = g;
  return q;
}

PlanQuery joint_query(PlanMode mode, const JointVector& start, const JointVector& goal) {
  PlanQuery q;
  q.mode = mode;
  q.start = start;
  JointGoal g;
  g.q = goal;
  q.goal = g;
  return q;
}

JointVector position_at(const std::vector<TimedPoint>& points, double t) {
  if (t <= points.front().time_s) return points.front().position;
  for (std::size_t i = 1; i < points.size(); ++i) {
    if (t <= points[i].time_s) {
      const double span = points[i].time_s - points[i - 1].time_s;
      const double a = span > 0 ? (t - points[i - 1].time_s) / span : 1.0;
      return points[i - 1].position + a * (points[i].position - points[i - 1].position);
    }
  }
  return points.back().position;
}

// Independent re-check: every 2 ms of the trajectory, every link shape
// against every box not ignored and the trailer's inner walls as half-spaces,
// with FCL directly (no octree, no sweeps, no caches).
std::string dense_collision(const std::vector<TimedPoint>& points, const World& world,
                            const std::vector<std::uint32_t>& ignored, double from_s = 0.0) {
  const RobotModel& m = robot();
  const double hw = world.trailer.width / 2;
  const std::vector<std::shared_ptr<fcl::CollisionGeometryd>> planes = {
      std::make_shared<fcl::Halfspaced>(Eigen::Vector3d(0, 0, 1), -1e-3),  // floor z < 0
      std::make_shared<fcl::Halfspaced>(Eigen::Vector3d(0, 0, -1), -world.trailer.height - 1e-3),
      std::make_shared<fcl::Halfspaced>(Eigen::Vector3d(0, 1, 0), -hw - 1e-3),
      std::make_shared<fcl::Halfspaced>(Eigen::Vector3d(0, -1, 0), -hw - 1e-3),
      std::make_shared<fcl::Halfspaced>(Eigen::Vector3d(-1, 0, 0), -world.trailer.depth - 1e-3)};
  auto tf = [](const Eigen::Isometry3d& p) {
    fcl::Transform3d t = fcl::Transform3d::Identity();
    t.linear() = p.linear();
    t.translation() = p.translation();
    return t;
  };
  std::vector<Eigen::Isometry3d> poses;
  const double end = points.back().time_s;
  for (double t = from_s;; t += 0.002) {
    m.forward_kinematics(position_at(points, std::min(t, end)), poses);
    for (std::size_t l = 0; l < m.links().size(); ++l) {
      for (const CollisionShape& s : m.links()[l].shapes) {
        std::shared_ptr<fcl::CollisionGeometryd> g;
        if (s.type == CollisionShape::Type::kBox)
          g = std::make_shared<fcl::Boxd>(s.size);
        else if (s.type == CollisionShape::Type::kCylinder)
          g = std::make_shared<fcl::Cylinderd>(s.size.x(), s.size.y());
        else
          g = std::make_shared<fcl::Sphered>(s.size.x());
        const Eigen::Isometry3d p = poses[l] * s.origin;
        fcl::CollisionObjectd link(g, tf(p));
        auto hits = [&](const std::shared_ptr<fcl::CollisionGeometryd>& other,
                        const Eigen::Isometry3d& pose) {
          fcl::CollisionObjectd o(other, tf(pose));
          fcl::CollisionRequestd req;
          fcl::CollisionResultd res;
          return fcl::collide(&link, &o, req, res) > 0;
        };
        for (const Box& b : world.boxes) {
          if (std::find(ignored.begin(), ignored.end(), b.id) != ignored.end()) continue;
          if (hits(std::make_shared<fcl::Boxd>(b.size), b.pose))
            return m.links()[l].name + " - box " + std::to_string(b.id) +
                   " at t=" + std::to_string(t);
        }
        // Walls only inside the trailer (x >= 0): the rear is open.
        for (std::size_t i = 0; i < planes.size(); ++i) {
          if (i >= 2 && p.translation().x() < 0.0) continue;
          if (hits(planes[i], Eigen::Isometry3d::Identity()))
            return m.links()[l].name + " - trailer plane " + std::to_string(i) +
                   " at t=" + std::to_string(t);
        }
      }
    }
    if (t >= end) break;
  }
  return {};
}

void expect_within_limits(const std::vector<TimedPoint>& points) {
  for (const TimedPoint& p : points) {
    for (int j = 0; j < kNumJoints; ++j) {
      const JointLimits& l = robot().limits(j);
      EXPECT_GE(p.position[j], l.lower - 1e-9) << kJointNames[j] << " t=" << p.time_s;
      EXPECT_LE(p.position[j], l.upper + 1e-9) << kJointNames[j] << " t=" << p.time_s;
      EXPECT_LE(std::abs(p.velocity[j]), l.velocity + 1e-9) << kJointNames[j] << " t=" << p.time_s;
    }
  }
}

// The planner plug-in, configured and active in a fake kernel, answering
// queries over `plan` as a remote caller sees them.
class PlanClient {
 public:
  PlanClient(const std::string& plugin, const std::string& params_json) : kernel_(quiet()) {
    nlohmann::json params = nlohmann::json::parse(params_json);
    // Dense samples: the dense re-check interpolates between them.
    params["sample_dt"] = 0.005;
    auto node = kernel_.load_node(plugin, NodeOptions().with_params(params.dump()));
    if (!node) {
      error_ = node.error().message;
      return;
    }
    node_ = *node;
    if (auto s = node_->configure(); !s)
      error_ = "configure: " + s.error().message;
    else if (auto a = node_->activate(); !a)
      error_ = "activate: " + a.error().message;
  }

  const std::string& error() const { return error_; }

  DecodedPlanResponse plan(const PlanQuery& query, const World& world) {
    flatbuffers::FlatBufferBuilder fbb;
    encode_plan_request(query, world, fbb);
    return send(fbb);
  }

  DecodedPlanResponse send(const flatbuffers::FlatBufferBuilder& request) {
    auto reply = kernel_.call<msg::PlanRequest, msg::PlanResponse>("plan", request,
                                                                   std::chrono::minutes(10));
    DecodedPlanResponse r;
    if (!reply) {
      r.message = "the service failed: " + reply.error().message;
      return r;
    }
    auto decoded = decode_plan_response(*reply.value());
    if (!decoded) {
      r.message = "bad response: " + decoded.error().message;
      return r;
    }
    return *decoded;
  }

 private:
  static plr::testing::KernelOptions quiet() {
    return {.start_ns = 0, .echo_level = PLR_LOG_ERROR};
  }

  FakeKernel kernel_;
  std::optional<plr::testing::NodeHandle> node_;
  std::string error_;
};

bool unsupported(const DecodedPlanResponse& r) {
  return r.status == PlanStatus::kInvalidRequest &&
         r.message.find("is not a mode of planner") != std::string::npos;
}

#define PLR_SKIP_IF_UNSUPPORTED(r)                                     \
  do {                                                                 \
    if (unsupported(r)) GTEST_SKIP() << "planner says: " << r.message; \
  } while (0)

void expect_solved_cleanly(const DecodedPlanResponse& r, const PlanQuery& q, const World& w,
                           const std::vector<std::uint32_t>& ignored = {}) {
  ASSERT_EQ(r.status, PlanStatus::kSolved) << to_string(r.status) << ": " << r.message;
  ASSERT_GE(r.points.size(), 2u);
  EXPECT_LT((r.points.front().position - q.start).cwiseAbs().maxCoeff(), 1e-9)
      << "the trajectory must start at the query's start";
  EXPECT_EQ(r.points.front().time_s, 0.0);
  EXPECT_FALSE(r.planner.empty()) << "responses name the planner";
  EXPECT_EQ(dense_collision(r.points, w, ignored), "");
  expect_within_limits(r.points);
}

using Check = std::function<void(PlanClient&)>;

void arm_to_pre_grasp(PlanClient& c) {
  const World w = wall(4.0);
  const JointVector start = home_configuration(4.0 - 1.35);
  // Plate 15 cm in front of a box's face (row 2, column 1), square to it.
  const Eigen::Vector3d target(3.85, at(w, 2, 1).pose.translation().y(),
                               at(w, 2, 1).pose.translation().z());
  const PlanQuery q = pose_query(PlanMode::kArm, start, target, 0.0);
  const auto r = c.plan(q, w);
  ASSERT_FALSE(unsupported(r)) << "M1 is required of every planner";
  expect_solved_cleanly(r, q, w);
  if (r.points.empty()) return;
  const JointVector end = r.points.back().position;
  EXPECT_LT((robot().plate_target(end).position - target).norm(), 0.005 + 1e-6);
  for (int j : {kBaseX, kNose1, kNose2, kNose3})
    EXPECT_EQ(end[j], start[j]) << kJointNames[j] << " is not an M1 joint";
}

void arm_and_base_from_far_back(PlanClient& c) {
  const World w = wall(5.0);
  const PlanQuery q =
      pose_query(PlanMode::kArmBase, home_configuration(2.0), {4.85, 0.4, 1.8}, 0.0);
  const auto r = c.plan(q, w);
  PLR_SKIP_IF_UNSUPPORTED(r);
  expect_solved_cleanly(r, q, w);
  if (r.points.empty()) return;
  EXPECT_GT(r.points.back().position[kBaseX], q.start[kBaseX] + 0.3) << "it had to drive";
  EXPECT_LT(
      (robot().plate_target(r.points.back().position).position - Eigen::Vector3d(4.85, 0.4, 1.8))
          .norm(),
      0.005 + 1e-6);
}

void nose_down(PlanClient& c) {
  const World w = wall(6.0);
  JointVector down = home_configuration(4.0);
  down[kNose1] = 0.0;
  down[kNose2] = 0.05;
  down[kNose3] = 0.3;
  const PlanQuery q = joint_query(PlanMode::kNose, home_configuration(4.0), down);
  const auto r = c.plan(q, w);
  PLR_SKIP_IF_UNSUPPORTED(r);
  expect_solved_cleanly(r, q, w);
  if (!r.points.empty()) {
    EXPECT_LT((r.points.back().position - down).cwiseAbs().maxCoeff(), 1e-3);
  }
}

void base_line(PlanClient& c) {
  const World w = wall(6.0);
  JointVector back = home_configuration(4.0);
  back[kBaseX] = 2.5;
  const PlanQuery q = joint_query(PlanMode::kBaseLine, home_configuration(4.0), back);
  const auto r = c.plan(q, w);
  PLR_SKIP_IF_UNSUPPORTED(r);
  expect_solved_cleanly(r, q, w);
  for (const TimedPoint& p : r.points) {
    JointVector d = p.position - q.start;
    d[kBaseX] = 0.0;
    EXPECT_EQ(d.cwiseAbs().maxCoeff(), 0.0) << "only the base moves, t=" << p.time_s;
  }
  if (!r.points.empty()) {
    EXPECT_NEAR(r.points.back().position[kBaseX], 2.5, 1e-3);
  }
}

void cartesian_line(PlanClient& c) {
  const World w = wall(4.0);
  const Box& box = at(w, 2, 2);
  const Eigen::Vector3d face(4.0, box.pose.translation().y(), box.pose.translation().z());
  const auto pre =
      robot().arm_ik({face - Eigen::Vector3d(0.15, 0, 0), 0.0}, home_configuration(4.0 - 1.35));
  ASSERT_FALSE(pre.empty());
  PlanQuery q =
      pose_query(PlanMode::kArmCartesian, pre.front(), face - Eigen::Vector3d(0.005, 0, 0), 0.0);
  q.ignored_boxes = {box.id};
  const auto r = c.plan(q, w);
  PLR_SKIP_IF_UNSUPPORTED(r);
  expect_solved_cleanly(r, q, w, {box.id});
  for (const TimedPoint& p : r.points) {
    const Eigen::Vector3d at_t = robot().plate_pose(p.position).translation();
    EXPECT_LT(std::hypot(at_t.y() - face.y(), at_t.z() - face.z()), 0.006) << "t=" << p.time_s;
  }
}

void goal_in_collision(PlanClient& c) {
  JointVector goal = home_configuration(4.0 - 1.35);
  goal[kBaseX] = 4.5;  // inside the wall
  const auto r = c.plan(joint_query(PlanMode::kBaseLine, home_configuration(2.0), goal), wall(4.0));
  PLR_SKIP_IF_UNSUPPORTED(r);
  EXPECT_EQ(r.status, PlanStatus::kGoalInvalid) << r.message;
  EXPECT_NE(r.message.find("box"), std::string::npos) << "say what the goal hits: " << r.message;
}

void invalid_requests(PlanClient& c) {
  const World empty;
  PlanQuery q;
  q.mode = PlanMode::kNose;
  q.start = home_configuration(1.0);
  q.goal = PoseGoal{};
  auto r = c.plan(q, empty);
  EXPECT_EQ(r.status, PlanStatus::kInvalidRequest);
  EXPECT_EQ(r.message, "M3 nose needs a joint goal");

  q = joint_query(PlanMode::kArm, home_configuration(1.0), home_configuration(1.0));
  std::get<JointGoal>(q.goal).q[kArm2] = 20.0;
  r = c.plan(q, empty);
  EXPECT_EQ(r.status, PlanStatus::kInvalidRequest);
  EXPECT_EQ(r.message.rfind("joint goal arm_2 = 20.000000 is beyond limits", 0), 0u) << r.message;

  q = joint_query(PlanMode::kArm, home_configuration(1.0), home_configuration(1.0));
  q.start[kArm1] = std::nan("");
  r = c.plan(q, empty);
  EXPECT_EQ(r.status, PlanStatus::kInvalidRequest);
  EXPECT_EQ(r.message, "start configuration has a non-finite value");

  // Undecodable: 3 joint values for 8 joints.
  flatbuffers::FlatBufferBuilder fbb;
  const std::vector<double> start{1.0, 0.0, -1.0}, goal{2.5, 0, -1.0, 2.0, 0.0, 0.5, 0, 0};
  const msg::Vec3 trailer(2.5, 2.7, 16.0);
  const auto world = msg::CreateWorldStateDirect(fbb, 0, &trailer);
  fbb.Finish(msg::CreatePlanRequestDirect(fbb, msg::PlanMode::M5, &start, &goal, nullptr, false,
                                          5.0, nullptr, world));
  r = c.send(fbb);
  EXPECT_EQ(r.status, PlanStatus::kInvalidRequest);
  EXPECT_EQ(r.message, "PlanRequest.start: needs 8 joint values, got 3");
}

// The plate pressed 8 mm into a box: the planner leaves the contact (M6),
// then plans from there.
void escapes_light_contact(PlanClient& c) {
  const World w = wall(4.0);
  const Box& box = at(w, 2, 2);
  const Eigen::Vector3d face(4.0, box.pose.translation().y(), box.pose.translation().z());
  const auto pre =
      robot().arm_ik({face - Eigen::Vector3d(0.08, 0, 0), 0.0}, home_configuration(4.0 - 1.35));
  ASSERT_FALSE(pre.empty());
  JointVector pressed = pre.front();
  pressed[kBaseX] += 0.088;

  PlanQuery esc;
  esc.mode = PlanMode::kEscape;
  esc.start = pressed;
  const auto e = c.plan(esc, w);
  ASSERT_EQ(e.status, PlanStatus::kSolved) << e.message;
  EXPECT_TRUE(e.stats.escaped);
  ASSERT_FALSE(e.points.empty());
  EXPECT_LT((robot().plate_pose(e.points.back().position).translation() -
             robot().plate_pose(pressed).translation())
                .norm(),
            0.03)
      << "the nearest free state, not a long retreat";

  const PlanQuery q = joint_query(PlanMode::kArm, pressed, home_configuration(pressed[kBaseX]));
  const auto r = c.plan(q, w);
  ASSERT_EQ(r.status, PlanStatus::kSolved) << r.message;
  EXPECT_TRUE(r.stats.escaped);
  EXPECT_LT((r.points.back().position - home_configuration(pressed[kBaseX])).cwiseAbs().maxCoeff(),
            1e-3);
  // Free of collisions once out of the contact.
  double out_s = 0.0;
  {
    CollisionChecker checker(robot(), w);
    for (const TimedPoint& p : r.points) {
      if (checker.is_valid(p.position)) {
        out_s = p.time_s;
        break;
      }
    }
  }
  EXPECT_EQ(dense_collision(r.points, w, {}, out_s), "");
}

// With an expansion budget the answer is a function of the request.
void budget_is_deterministic(PlanClient& c) {
  const World w = wall(5.0);
  PlanQuery q = pose_query(PlanMode::kArmBase, home_configuration(2.0), {4.85, 0.4, 1.8}, 0.0);
  q.max_expansions = 400;
  q.time_limit_s = 120.0;  // the budget decides, not the clock
  const auto a = c.plan(q, w);
  PLR_SKIP_IF_UNSUPPORTED(a);
  ASSERT_EQ(a.status, PlanStatus::kSolved) << a.message;
  EXPECT_LE(a.stats.expansions, q.max_expansions);
  EXPECT_FALSE(a.stats.time_limit_hit);
  const auto b = c.plan(q, w);
  ASSERT_EQ(b.points.size(), a.points.size());
  for (std::size_t i = 0; i < a.points.size(); ++i) {
    EXPECT_EQ(a.points[i].time_s, b.points[i].time_s);
    EXPECT_EQ(a.points[i].position, b.points[i].position);
  }

  q.max_expansions = 3;
  const auto none = c.plan(q, w);
  EXPECT_EQ(none.status, PlanStatus::kTimeout);
  EXPECT_EQ(none.message, "no solution within the expansion budget of 3");
  EXPECT_TRUE(none.stats.budget_exhausted);
  EXPECT_TRUE(none.points.empty());
}

class PlannerCheck : public ::testing::Test {
 public:
  PlannerCheck(Check body, std::string plugin, std::string params)
      : body_(std::move(body)), plugin_(std::move(plugin)), params_(std::move(params)) {}
  void TestBody() override {
    PlanClient client(plugin_, params_);
    ASSERT_EQ(client.error(), "");
    body_(client);
  }

 private:
  Check body_;
  std::string plugin_, params_;
};

}  // namespace

void register_planner_conformance_tests(const std::string& plugin_path,
                                        const std::string& params_json) {
  plr::testing::register_conformance_tests({plugin_path, params_json});
  const std::pair<const char*, Check> checks[] = {
      {"ArmToPreGrasp", &arm_to_pre_grasp},
      {"ArmAndBaseFromFarBack", &arm_and_base_from_far_back},
      {"NoseDown", &nose_down},
      {"BaseLine", &base_line},
      {"CartesianLine", &cartesian_line},
      {"GoalInCollision", &goal_in_collision},
      {"InvalidRequests", &invalid_requests},
      {"EscapesLightContact", &escapes_light_contact},
      {"BudgetIsDeterministic", &budget_is_deterministic},
  };
  for (const auto& [name, body] : checks) {
    ::testing::RegisterTest("PlannerConformance", name, nullptr, plugin_path.c_str(), __FILE__,
                            __LINE__, [body, plugin_path, params_json]() -> ::testing::Test* {
                              return new PlannerCheck(body, plugin_path, params_json);
                            });
  }
}

}  // namespace plr::planning::testing
