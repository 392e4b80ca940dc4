#include "plr/sim/robot_model.hpp"

#include "plr/sim/shipped_files.hpp"

#include <console_bridge/console.h>
#include <tinyxml.h>

#include <urdf_parser/urdf_parser.h>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>

namespace plr::sim {
namespace {

// The reader stops at the first error; the public functions return it.
// Bounds on a URDF: a robot's description is far smaller and flatter.
constexpr std::size_t kMaxUrdfBytes = 8u << 20;
constexpr std::size_t kMaxUrdfDepth = 32;
constexpr std::size_t kMaxLinks = 1000;

struct Failure {
  std::string what;
};

[[noreturn]] void fail(const std::string& source, const std::string& cause) {
  throw Failure{source + ": " + cause};
}

// urdfdom reports why it rejected a model only through console_bridge; keep
// the first error so our exception can name the cause.
class CaptureErrors : public console_bridge::OutputHandler {
 public:
  void log(const std::string& text, console_bridge::LogLevel level, const char*, int) override {
    if (level >= console_bridge::CONSOLE_BRIDGE_LOG_ERROR && first_error.empty()) {
      first_error = text;
    }
  }
  std::string first_error;
};

Eigen::Isometry3d to_isometry(const urdf::Pose& p) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.translation() = Eigen::Vector3d(p.position.x, p.position.y, p.position.z);
  t.linear() = Eigen::Quaterniond(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z)
                   .normalized()
                   .toRotationMatrix();
  return t;
}

// Acceleration limits are not part of URDF; read our extension element.
std::map<std::string, double> read_acceleration_limits(const TiXmlDocument& doc) {
  std::map<std::string, double> out;
  const TiXmlElement* robot = doc.FirstChildElement("robot");
  if (robot == nullptr) return out;
  for (const TiXmlElement* j = robot->FirstChildElement("joint"); j != nullptr;
       j = j->NextSiblingElement("joint")) {
    const char* name = j->Attribute("name");
    const TiXmlElement* acc = j->FirstChildElement("acceleration_limit");
    double value = 0.0;
    if (name != nullptr && acc != nullptr &&
        acc->QueryDoubleAttribute("value", &value) == TIXML_SUCCESS) {
      out[name] = value;
    }
  }
  return out;
}

bool is_pure_offset(const Eigen::Isometry3d& t, const Eigen::Vector3d& along) {
  const Eigen::Vector3d p = t.translation();
  return t.linear().isIdentity(1e-9) && (p - p.dot(along) * along).norm() < 1e-9;
}

double wrap_near(double a, double lo, double hi) {
  // Bring an angle into [lo, hi] by whole turns if possible.
  while (a > hi + 1e-12) a -= 2.0 * M_PI;
  while (a < lo - 1e-12) a += 2.0 * M_PI;
  return a;
}

// Joints must make a tree: urdfdom leaks the model it built (shared_ptr
// cycles) when a link is the child of two joints or the joints loop.
void check_tree(const TiXmlElement& robot, const std::string& source) {
  std::map<std::string, std::pair<std::string, std::string>> parent;  // child -> parent, joint
  for (const TiXmlElement* j = robot.FirstChildElement("joint"); j != nullptr;
       j = j->NextSiblingElement("joint")) {
    const char* name = j->Attribute("name");
    const TiXmlElement* p = j->FirstChildElement("parent");
    const TiXmlElement* c = j->FirstChildElement("child");
    const char* pl = p != nullptr ? p->Attribute("link") : nullptr;
    const char* cl = c != nullptr ? c->Attribute("link") : nullptr;
    if (name == nullptr || pl == nullptr || cl == nullptr) continue;  // urdfdom names it
    const auto [it, fresh] = parent.emplace(cl, std::pair{std::string(pl), std::string(name)});
    if (!fresh)
      fail(source, "line " + std::to_string(j->Row()) + ": link '" + cl +
                       "' is the child of joints '" + it->second.second + "' and '" + name + "'");
  }
  for (const auto& [link, up] : parent) {
    std::string at = link;
    for (std::size_t steps = 0; parent.count(at) != 0; ++steps) {
      if (steps > parent.size()) fail(source, "the joints make a loop through link '" + link + "'");
      at = parent.at(at).first;
    }
  }
}

// The line of the first byte that is not well-formed UTF-8, or a NUL, if
// any. TinyXML 2.6 steps over a multi-byte sequence by its lead byte's
// length: one cut short at the end made it read past the text (fuzzing).
std::optional<std::size_t> line_of_bad_utf8(const std::string& xml) {
  std::size_t line = 1;
  const std::size_t n = xml.size();
  for (std::size_t i = 0; i < n;) {
    const auto b = static_cast<unsigned char>(xml[i]);
    if (b == '\n') ++line;
    if (b == 0) return line;
    const std::size_t length = b < 0x80                 ? 1
                               : b >= 0xC2 && b <= 0xDF ? 2
                               : b >= 0xE0 && b <= 0xEF ? 3
                               : b >= 0xF0 && b <= 0xF4 ? 4
                                                        : 0;
    if (length == 0 || i + length > n) return line;
    for (std::size_t k = 1; k < length; ++k)
      if ((static_cast<unsigned char>(xml[i + k]) & 0xC0) != 0x80) return line;
    i += length;
  }
  return std::nullopt;
}

// The line of the first element nested deeper than `max_depth`, if any. A
// scan of tags only (comments, declarations and quoted attribute values
// skipped), so nothing recursive runs on the text before it is bounded.
std::optional<std::size_t> line_nested_deeper(const std::string& xml, std::size_t max_depth) {
  std::size_t depth = 0, line = 1;
  const std::size_t n = xml.size();
  for (std::size_t i = 0; i < n; ++i) {
    if (xml[i] == '\n') ++line;
    if (xml[i] != '<' || i + 1 >= n) continue;
    const char next = xml[i + 1];
    if (next == '!' || next == '?') {
      // <!-- ... -->, <![CDATA[ ... ]]>, <!DOCTYPE ...>, <?xml ...?>: to the end, lines counted.
      const std::string end = xml.compare(i, 4, "<!--") == 0        ? "-->"
                              : xml.compare(i, 9, "<![CDATA[") == 0 ? "]]>"
                                                                    : ">";
      const std::size_t stop = xml.find(end, i + 2);
      const std::size_t last = stop == std::string::npos ? n : stop + end.size();
      line += static_cast<std::size_t>(std::count(xml.begin() + static_cast<std::ptrdiff_t>(i),
                                                  xml.begin() + static_cast<std::ptrdiff_t>(last),
                                                  '\n'));
      i = last - 1;
      continue;
    }
    const bool closing = next == '/';
    // To the tag's end, past quoted attribute values (which may hold '>').
    char quote = 0;
    std::size_t j = i + 1;
    for (; j < n; ++j) {
      if (xml[j] == '\n') ++line;
      if (quote != 0) {
        if (xml[j] == quote) quote = 0;
      } else if (xml[j] == '"' || xml[j] == '\'') {
        quote = xml[j];
      } else if (xml[j] == '>') {
        break;
      }
    }
    const bool empty_element = j < n && xml[j - 1] == '/';
    if (closing) {
      if (depth > 0) --depth;
    } else if (!empty_element && ++depth > max_depth) {
      return line;
    }
    i = j;
  }
  return std::nullopt;
}

}  // namespace

JointVector home_configuration(double base_x) {
  JointVector q;
  q << base_x, 0.0, -1.0, 2.0, 0.0, 0.5, 0.0, 0.0;
  return q;
}

plr::Expected<RobotModel> RobotModel::from_urdf_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return plr::make_error(PLR_ERR_INVALID, path + ": cannot open file");
  // Read in bounded pieces: /dev/zero or a FIFO has no size to check first.
  std::string text;
  char buf[1 << 16];
  while (in.read(buf, sizeof buf) || in.gcount() > 0) {
    text.append(buf, static_cast<std::size_t>(in.gcount()));
    if (text.size() > kMaxUrdfBytes)
      return plr::make_error(PLR_ERR_INVALID,
                             path + ": larger than " + std::to_string(kMaxUrdfBytes) + " bytes");
  }
  return from_urdf_string(text, path);
}

plr::Expected<RobotModel> load_robot(const std::string& urdf) {
  if (!urdf.empty()) return RobotModel::from_urdf_file(urdf);
  const auto shipped = shipped_file("robots/unloader.urdf");
  if (!shipped) return shipped.error();
  return RobotModel::from_urdf_file(shipped->string());
}

plr::Expected<RobotModel> RobotModel::from_urdf_string(const std::string& xml,
                                                       const std::string& source) {
  try {
    return parse_urdf(xml, source);
  } catch (const Failure& f) {
    return plr::make_error(PLR_ERR_INVALID, f.what);
  }
}

RobotModel RobotModel::parse_urdf(const std::string& xml, const std::string& source) {
  if (xml.size() > kMaxUrdfBytes)
    fail(source, "larger than " + std::to_string(kMaxUrdfBytes) + " bytes");
  if (const auto line = line_of_bad_utf8(xml))
    fail(source, "line " + std::to_string(*line) + ": not UTF-8 text");
  // TinyXML and urdfdom recurse once per level: 60,000 levels overflowed the stack.
  if (const auto line = line_nested_deeper(xml, kMaxUrdfDepth))
    fail(source, "line " + std::to_string(*line) + ": elements nested deeper than " +
                     std::to_string(kMaxUrdfDepth) + " levels");
  TiXmlDocument doc;
  doc.Parse(xml.c_str());
  if (doc.Error()) {
    fail(source, "XML error at line " + std::to_string(doc.ErrorRow()) + ": " + doc.ErrorDesc());
  }
  if (doc.FirstChildElement("robot") == nullptr) fail(source, "no <robot> element");
  check_tree(*doc.FirstChildElement("robot"), source);

  CaptureErrors capture;
  console_bridge::useOutputHandler(&capture);
  urdf::ModelInterfaceSharedPtr model = urdf::parseURDF(xml);
  console_bridge::restorePreviousOutputHandler();
  if (!model) {
    fail(source,
         "invalid URDF: " + (capture.first_error.empty() ? std::string("rejected by urdfdom")
                                                         : capture.first_error));
  }
  if (model->links_.size() > kMaxLinks)
    fail(source, "more than " + std::to_string(kMaxLinks) + " links");
  const auto accel = read_acceleration_limits(doc);

  RobotModel m;
  // Links in parent-before-child order: breadth-first from the root.
  std::vector<urdf::LinkConstSharedPtr> order{model->getRoot()};
  for (std::size_t i = 0; i < order.size(); ++i) {
    for (const auto& child : order[i]->child_links) order.push_back(child);
  }
  std::map<std::string, int> index;
  std::array<bool, kNumJoints> seen{};
  for (const auto& l : order) {
    Link link;
    link.name = l->name;
    Link& cj = link;
    if (const auto& j = l->parent_joint) {
      link.parent_link = index.at(j->parent_link_name);
      cj.origin = to_isometry(j->parent_to_joint_origin_transform);
      cj.axis = Eigen::Vector3d(j->axis.x, j->axis.y, j->axis.z);
      switch (j->type) {
        case urdf::Joint::FIXED:
          cj.joint_type = JointType::kFixed;
          break;
        case urdf::Joint::REVOLUTE:
          cj.joint_type = JointType::kRevolute;
          break;
        case urdf::Joint::PRISMATIC:
          cj.joint_type = JointType::kPrismatic;
          break;
        default:
          fail(source,
               "joint '" + j->name + "': only fixed, revolute and prismatic joints are supported");
      }
      const auto it = std::find(kJointNames.begin(), kJointNames.end(), j->name);
      if (it != kJointNames.end()) {
        const int qi = static_cast<int>(it - kJointNames.begin());
        if (cj.joint_type == JointType::kFixed)
          fail(source, "joint '" + j->name + "' must not be fixed");
        if (!j->limits) fail(source, "joint '" + j->name + "' has no <limit>");
        if (j->limits->lower >= j->limits->upper)
          fail(source, "joint '" + j->name + "' has lower >= upper");
        if (j->limits->velocity <= 0)
          fail(source, "joint '" + j->name + "' has no positive velocity limit");
        const auto a = accel.find(j->name);
        if (a == accel.end() || a->second <= 0) {
          fail(source, "joint '" + j->name + "' has no positive <acceleration_limit value=..>");
        }
        m.limits_[qi] = {j->limits->lower, j->limits->upper, j->limits->velocity, a->second};
        link.joint = qi;
        seen[qi] = true;
      } else if (cj.joint_type != JointType::kFixed) {
        const auto followed =
            j->mimic ? std::find(kJointNames.begin(), kJointNames.end(), j->mimic->joint_name)
                     : kJointNames.end();
        if (followed == kJointNames.end()) {
          fail(source, "joint '" + j->name +
                           "' is movable but neither one of the 8 planned joints nor a "
                           "<mimic> of one");
        }
        link.joint = static_cast<int>(followed - kJointNames.begin());
        link.mimic_multiplier = j->mimic->multiplier;
        link.mimic_offset = j->mimic->offset;
      }
    }
    for (const auto& c : l->collision_array) {
      if (!c || !c->geometry) continue;
      CollisionShape s;
      s.origin = to_isometry(c->origin);
      switch (c->geometry->type) {
        case urdf::Geometry::BOX: {
          const auto& b = static_cast<const urdf::Box&>(*c->geometry);
          s.type = CollisionShape::Type::kBox;
          s.size = Eigen::Vector3d(b.dim.x, b.dim.y, b.dim.z);
          break;
        }
        case urdf::Geometry::CYLINDER: {
          const auto& cy = static_cast<const urdf::Cylinder&>(*c->geometry);
          s.type = CollisionShape::Type::kCylinder;
          s.size = Eigen::Vector3d(cy.radius, cy.length, 0.0);
          break;
        }
        case urdf::Geometry::SPHERE: {
          const auto& sp = static_cast<const urdf::Sphere&>(*c->geometry);
          s.type = CollisionShape::Type::kSphere;
          s.size = Eigen::Vector3d(sp.radius, 0.0, 0.0);
          break;
        }
        default:
          fail(source, "link '" + l->name +
                           "': only box, cylinder and sphere collision geometry is supported");
      }
      link.shapes.push_back(s);
    }
    index[link.name] = static_cast<int>(m.links_.size());
    m.links_.push_back(std::move(link));
  }
  for (int i = 0; i < kNumJoints; ++i) {
    if (!seen[i]) fail(source, std::string("missing joint '") + kJointNames[i] + "'");
  }
  for (const TiXmlElement* a = doc.FirstChildElement("robot")->FirstChildElement("allow_collision");
       a != nullptr; a = a->NextSiblingElement("allow_collision")) {
    const char* l1 = a->Attribute("link1");
    const char* l2 = a->Attribute("link2");
    const auto i1 = l1 ? index.find(l1) : index.end();
    const auto i2 = l2 ? index.find(l2) : index.end();
    if (i1 == index.end() || i2 == index.end()) {
      fail(source, "<allow_collision> at line " + std::to_string(a->Row()) +
                       " needs existing link1 and link2");
    }
    m.allowed_.emplace_back(i1->second, i2->second);
  }

  // The closed-form IK assumes yaw about z, then two pitch joints about y
  // offset along the link's x, then a level flange turning about z (arm_4),
  // then the plate offset along x.
  auto joint_link = [&](int qi) {
    for (std::size_t i = 0; i < m.links_.size(); ++i) {
      if (m.links_[i].joint == qi && m.links_[i].mimic_multiplier == 1.0 &&
          m.links_[i].mimic_offset == 0.0)
        return static_cast<int>(i);
    }
    return -1;
  };
  const int l1 = joint_link(kArm1), l2 = joint_link(kArm2), l3 = joint_link(kArm3),
            l4 = joint_link(kArm4);
  const auto plate = index.find("plate");
  if (plate == index.end()) fail(source, "missing link 'plate'");
  m.plate_link_ = plate->second;
  const Eigen::Vector3d ex = Eigen::Vector3d::UnitX(), ey = Eigen::Vector3d::UnitY(),
                        ez = Eigen::Vector3d::UnitZ();
  if (m.links_[l1].parent_link != joint_link(kBaseX) || !m.links_[l1].axis.isApprox(ez) ||
      !m.links_[l1].origin.linear().isIdentity(1e-9)) {
    fail(source, "arm_1 must turn about z on base_link (closed-form IK)");
  }
  if (m.links_[l2].parent_link != l1 || !m.links_[l2].axis.isApprox(ey) ||
      !is_pure_offset(m.links_[l2].origin, ez)) {
    fail(source, "arm_2 must pitch about y straight above arm_1 (closed-form IK)");
  }
  if (m.links_[l3].parent_link != l2 || !m.links_[l3].axis.isApprox(ey) ||
      !is_pure_offset(m.links_[l3].origin, ex)) {
    fail(source, "arm_3 must pitch about y, offset along x from arm_2 (closed-form IK)");
  }
  if (!m.links_[l4].axis.isApprox(ez)) fail(source, "arm_4 must turn about z (closed-form IK)");
  if (m.links_[m.plate_link_].parent_link != l4 ||
      m.links_[m.plate_link_].joint_type != JointType::kFixed ||
      !is_pure_offset(m.links_[m.plate_link_].origin, ex)) {
    fail(source, "link 'plate' must be fixed to the arm_4 link, offset along x (closed-form IK)");
  }
  // Whatever the shoulder and elbow do, arm_4's frame must stay level and
  // keep its offset along the forearm: the parallelogram.
  std::vector<Eigen::Isometry3d> poses;
  for (const auto& [a2, a3] : {std::pair{0.0, 0.0}, std::pair{0.7, -1.3}, std::pair{-1.1, 2.0}}) {
    JointVector q = JointVector::Zero();
    q[kArm1] = 0.3;
    q[kArm2] = a2;
    q[kArm3] = a3;
    m.forward_kinematics(q, poses);
    const Eigen::Isometry3d fore_to_wrist = poses[l3].inverse() * poses[l4];
    const Eigen::Matrix3d level = Eigen::AngleAxisd(0.3, ez).toRotationMatrix();
    const Eigen::Vector3d offset = fore_to_wrist.translation();
    if (!poses[l4].linear().isApprox(level, 1e-9) || (offset - offset.x() * ex).norm() > 1e-9) {
      fail(source,
           "arm_4 must sit on a level flange at the end of arm_3's link (mimic joints "
           "following arm_2 and arm_3 backwards; closed-form IK)");
    }
    m.arm_.fore = offset.x();
  }
  m.arm_.yaw_origin = m.links_[l1].origin.translation();
  m.arm_.shoulder_height = m.links_[l2].origin.translation().z();
  m.arm_.upper = m.links_[l3].origin.translation().x();
  m.arm_.plate = m.links_[m.plate_link_].origin.translation().x();
  return m;
}

int RobotModel::link_index(const std::string& name) const {
  for (std::size_t i = 0; i < links_.size(); ++i) {
    if (links_[i].name == name) return static_cast<int>(i);
  }
  return -1;
}

bool RobotModel::within_limits(const JointVector& q, double tol) const {
  for (int i = 0; i < kNumJoints; ++i) {
    if (!(q[i] >= limits_[i].lower - tol && q[i] <= limits_[i].upper + tol)) return false;
  }
  return true;
}

void RobotModel::forward_kinematics(const JointVector& q,
                                    std::vector<Eigen::Isometry3d>& poses) const {
  poses.resize(links_.size());
  for (std::size_t i = 0; i < links_.size(); ++i) {
    const Link& cj = links_[i];
    Eigen::Isometry3d local = cj.origin;
    if (links_[i].joint >= 0) {
      const double v = cj.mimic_multiplier * q[links_[i].joint] + cj.mimic_offset;
      if (cj.joint_type == JointType::kRevolute) {
        local.linear() = local.linear() * Eigen::AngleAxisd(v, cj.axis).toRotationMatrix();
      } else {
        local.translation() += local.linear() * (cj.axis * v);
      }
    }
    poses[i] = links_[i].parent_link < 0 ? local : poses[links_[i].parent_link] * local;
  }
}

Eigen::Vector3d half_extents(const CollisionShape& shape, const Eigen::Isometry3d& pose) {
  const Eigen::Matrix3d& r = pose.linear();
  switch (shape.type) {
    case CollisionShape::Type::kBox:
      return r.cwiseAbs() * (shape.size / 2);
    case CollisionShape::Type::kCylinder: {
      // Along a world axis: half the axis' projection plus the rim's.
      const Eigen::Vector3d axis = r.col(2);
      const double radius = shape.size.x(), half_length = shape.size.y() / 2;
      Eigen::Vector3d e;
      for (int i = 0; i < 3; ++i)
        e[i] = half_length * std::abs(axis[i]) +
               radius * std::sqrt(std::max(0.0, 1.0 - axis[i] * axis[i]));
      return e;
    }
    case CollisionShape::Type::kSphere:
      return Eigen::Vector3d::Constant(shape.size.x());
  }
  return Eigen::Vector3d::Zero();
}

Eigen::Isometry3d RobotModel::plate_pose(const JointVector& q) const {
  std::vector<Eigen::Isometry3d> poses;
  forward_kinematics(q, poses);
  return poses[plate_link_];
}

PlateTarget RobotModel::plate_target(const JointVector& q) const {
  const Eigen::Isometry3d p = plate_pose(q);
  const Eigen::Vector3d n = p.linear().col(0);
  return {p.translation(), std::atan2(n.y(), n.x())};
}

std::vector<JointVector> RobotModel::arm_ik(const PlateTarget& target,
                                            const JointVector& seed) const {
  std::vector<JointVector> out;
  const Eigen::Vector3d yaw_origin = arm_.yaw_origin + Eigen::Vector3d(seed[kBaseX], 0.0, 0.0);
  // The wrist axis stands behind the plate, along its normal.
  const Eigen::Vector3d wrist =
      target.position - arm_.plate * Eigen::Vector3d(std::cos(target.yaw), std::sin(target.yaw), 0);
  const Eigen::Vector3d d = wrist - yaw_origin;
  const double r = std::hypot(d.x(), d.y());
  const double psi = r > 1e-9 ? std::atan2(d.y(), d.x()) : seed[kArm1];
  const double l1 = arm_.upper, l2 = arm_.fore;
  // Planar coordinates (u forward, v down) of the wrist in the arm's plane.
  // Two yaw branches: facing the wrist (u = r) and turned away (u = -r, the
  // arm reaching back over itself); each has elbow up and elbow down.
  const double v = -(d.z() - arm_.shoulder_height);
  for (int branch = 0; branch < 2; ++branch) {
    const double yaw = branch == 0 ? psi : psi + M_PI;
    const double u = branch == 0 ? r : -r;
    const double c3 = (u * u + v * v - l1 * l1 - l2 * l2) / (2.0 * l1 * l2);
    if (c3 < -1.0 - 1e-12 || c3 > 1.0 + 1e-12) continue;
    const double base3 = std::acos(std::clamp(c3, -1.0, 1.0));
    for (double q3 : {base3, -base3}) {
      const double q2 = std::atan2(v, u) - std::atan2(l2 * std::sin(q3), l1 + l2 * std::cos(q3));
      JointVector q = seed;
      q[kArm1] = wrap_near(yaw, limits_[kArm1].lower, limits_[kArm1].upper);
      q[kArm2] = wrap_near(q2, limits_[kArm2].lower, limits_[kArm2].upper);
      q[kArm3] = wrap_near(q3, limits_[kArm3].lower, limits_[kArm3].upper);
      q[kArm4] = wrap_near(target.yaw - q[kArm1], limits_[kArm4].lower, limits_[kArm4].upper);
      if (!within_limits(q)) continue;
      const bool duplicate = std::any_of(
          out.begin(), out.end(), [&](const JointVector& o) { return (o - q).norm() < 1e-9; });
      if (!duplicate) out.push_back(q);
      if (base3 == 0.0) break;
    }
  }
  std::sort(out.begin(), out.end(), [&](const JointVector& x, const JointVector& y) {
    return (x - seed).squaredNorm() < (y - seed).squaredNorm();
  });
  return out;
}

}  // namespace plr::sim
