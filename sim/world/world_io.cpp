#include "plr/sim/world_io.hpp"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>
#include <plr/atomic_file.hpp>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <fstream>
#include <set>
#include <sstream>

namespace plr::sim {
namespace {

constexpr const char* kFormat = "plr-world";
constexpr int kVersion = 1;

class Reader {
 public:
  explicit Reader(std::string origin) : origin_(std::move(origin)) {}

  [[noreturn]] void fail(const YAML::Node& at, const std::string& key,
                         const std::string& cause) const {
    const int line = at.Mark().is_null() ? 0 : at.Mark().line + 1;
    throw WorldFileError(fmt::format("{}:{}: {}: {}", origin_, line, key, cause));
  }

  YAML::Node require(const YAML::Node& map, const char* name, const std::string& key) const {
    const YAML::Node node = map[name];
    if (!node) fail(map, key, "missing");
    return node;
  }

  double number(const YAML::Node& node, const std::string& key) const {
    if (!node.IsScalar()) fail(node, key, "expected a number");
    double value = 0.0;
    if (!YAML::convert<double>::decode(node, value) || !std::isfinite(value)) {
      fail(node, key, fmt::format("expected a number, got '{}'", node.Scalar()));
    }
    return value;
  }

  double positive(const YAML::Node& node, const std::string& key) const {
    const double value = number(node, key);
    if (value <= 0.0) fail(node, key, fmt::format("must be > 0, got {}", value));
    return value;
  }

  template <int N>
  Eigen::Matrix<double, N, 1> vector(const YAML::Node& node, const std::string& key) const {
    if (!node.IsSequence() || node.size() != N) {
      fail(node, key, fmt::format("expected a list of {} numbers", N));
    }
    Eigen::Matrix<double, N, 1> v;
    for (int i = 0; i < N; ++i) v[i] = number(node[i], fmt::format("{}[{}]", key, i));
    return v;
  }

  const std::string& origin() const { return origin_; }

 private:
  std::string origin_;
};

Box read_box(const Reader& r, const YAML::Node& node, const std::string& key) {
  if (!node.IsMap()) r.fail(node, key, "expected a map");
  Box box;
  const YAML::Node id = r.require(node, "id", key + ".id");
  const double id_value = r.number(id, key + ".id");
  if (id_value < 0 || id_value > 4294967295.0 || std::floor(id_value) != id_value) {
    r.fail(id, key + ".id", "expected an unsigned integer");
  }
  box.id = static_cast<std::uint32_t>(id_value);
  const YAML::Node size = r.require(node, "size", key + ".size");
  box.size = r.vector<3>(size, key + ".size");
  for (int i = 0; i < 3; ++i) {
    if (box.size[i] <= 0.0) r.fail(size[i], fmt::format("{}.size[{}]", key, i), "must be > 0");
  }
  const Eigen::Vector3d position =
      r.vector<3>(r.require(node, "position", key + ".position"), key + ".position");
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  if (const YAML::Node o = node["orientation"]) {
    const Eigen::Vector4d wxyz = r.vector<4>(o, key + ".orientation");
    if (wxyz.norm() < 1e-9) r.fail(o, key + ".orientation", "zero quaternion");
    q = Eigen::Quaterniond(wxyz[0], wxyz[1], wxyz[2], wxyz[3]).normalized();
  }
  box.pose = Eigen::Isometry3d::Identity();
  box.pose.linear() = q.toRotationMatrix();
  box.pose.translation() = position;
  if (const YAML::Node m = node["mass"]) {
    box.mass = r.number(m, key + ".mass");
    if (box.mass < 0.0) r.fail(m, key + ".mass", "must be >= 0");
  }
  return box;
}

}  // namespace

World parse_world(const std::string& text, const std::string& origin) {
  const Reader r(origin);
  YAML::Node root;
  try {
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw WorldFileError(fmt::format("{}:{}: (syntax): {}", origin, e.mark.line + 1, e.msg));
  }
  if (!root.IsMap()) r.fail(root, "(document)", "expected a map");
  const YAML::Node format = r.require(root, "format", "format");
  if (!format.IsScalar() || format.Scalar() != kFormat) {
    r.fail(format, "format", fmt::format("expected '{}'", kFormat));
  }
  const YAML::Node version = r.require(root, "version", "version");
  if (r.number(version, "version") != kVersion) {
    r.fail(version, "version", fmt::format("unsupported, this reader knows {}", kVersion));
  }
  World world;
  const YAML::Node trailer = r.require(root, "trailer", "trailer");
  if (!trailer.IsMap()) r.fail(trailer, "trailer", "expected a map");
  world.trailer.width = r.positive(r.require(trailer, "width", "trailer.width"), "trailer.width");
  world.trailer.height =
      r.positive(r.require(trailer, "height", "trailer.height"), "trailer.height");
  world.trailer.depth = r.positive(r.require(trailer, "depth", "trailer.depth"), "trailer.depth");

  const YAML::Node boxes = r.require(root, "boxes", "boxes");
  if (!boxes.IsSequence()) r.fail(boxes, "boxes", "expected a list");
  std::set<std::uint32_t> ids;
  for (std::size_t i = 0; i < boxes.size(); ++i) {
    const std::string key = fmt::format("boxes[{}]", i);
    Box box = read_box(r, boxes[i], key);
    if (!ids.insert(box.id).second) {
      r.fail(boxes[i]["id"], key + ".id", fmt::format("duplicate id {}", box.id));
    }
    world.boxes.push_back(std::move(box));
  }
  return world;
}

World load_world(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) {
    throw WorldFileError(
        fmt::format("{}:0: (file): cannot open: {}", file.string(), std::strerror(errno)));
  }
  std::ostringstream text;
  text << in.rdbuf();
  return parse_world(text.str(), file.string());
}

std::string format_world(const World& world) {
  YAML::Emitter out;
  out.SetDoublePrecision(17);
  out << YAML::BeginMap;
  out << YAML::Key << "format" << YAML::Value << kFormat;
  out << YAML::Key << "version" << YAML::Value << kVersion;
  out << YAML::Key << "trailer" << YAML::Value << YAML::Flow << YAML::BeginMap;
  out << YAML::Key << "width" << YAML::Value << world.trailer.width;
  out << YAML::Key << "height" << YAML::Value << world.trailer.height;
  out << YAML::Key << "depth" << YAML::Value << world.trailer.depth;
  out << YAML::EndMap;
  out << YAML::Key << "boxes" << YAML::Value << YAML::BeginSeq;
  for (const Box& box : world.boxes) {
    const Eigen::Quaterniond q(box.pose.rotation());
    const Eigen::Vector3d p = box.pose.translation();
    out << YAML::Flow << YAML::BeginMap;
    out << YAML::Key << "id" << YAML::Value << box.id;
    out << YAML::Key << "size" << YAML::Value << YAML::Flow << YAML::BeginSeq << box.size.x()
        << box.size.y() << box.size.z() << YAML::EndSeq;
    out << YAML::Key << "position" << YAML::Value << YAML::Flow << YAML::BeginSeq << p.x() << p.y()
        << p.z() << YAML::EndSeq;
    out << YAML::Key << "orientation" << YAML::Value << YAML::Flow << YAML::BeginSeq << q.w()
        << q.x() << q.y() << q.z() << YAML::EndSeq;
    out << YAML::Key << "mass" << YAML::Value << box.mass;
    out << YAML::EndMap;
  }
  out << YAML::EndSeq << YAML::EndMap;
  return std::string(out.c_str()) + "\n";
}

void save_world(const World& world, const std::filesystem::path& file) {
  if (const Status written = write_file_atomically(file.string(), format_world(world)); !written)
    throw WorldFileError(written.error().message);
}

}  // namespace plr::sim
