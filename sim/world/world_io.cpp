#include "plr/sim/world_io.hpp"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>
#include <plr/atomic_file.hpp>
#include <plr/yaml_reader.hpp>

#include <cstdint>
#include <limits>
#include <map>
#include <optional>
#include <string_view>

namespace plr::sim {
namespace {

constexpr const char* kFormat = "plr-world";
constexpr int kVersion = 1;

// A trailer holds a few hundred boxes; this many is a mistake, not a world.
constexpr std::size_t kMaxBoxes = 100'000;
// Trailers and containers are at most 2.5 m wide, 2.7 m high and 16 m deep:
// the bounds leave room, and refuse a size whose octree would not fit in memory.
constexpr double kMaxTrailerWidth = 4, kMaxTrailerHeight = 4, kMaxTrailerDepth = 20;
constexpr double kMinBoxSize = 0.01, kMaxBoxSize = 4;  // m
constexpr double kMaxCoordinate = 100;                 // m from the trailer's origin
constexpr double kMaxMass = 1000;                      // kg

template <int N>
std::optional<Eigen::Matrix<double, N, 1>> vector(const yaml::Node& node, std::string_view what) {
  const yaml::List items = node.list(what, N, N);
  if (!items) return std::nullopt;
  Eigen::Matrix<double, N, 1> v;
  bool ok = true;
  for (int i = 0; i < N; ++i) {
    const auto x = items[static_cast<std::size_t>(i)].number(-kMaxCoordinate, kMaxCoordinate);
    ok = ok && x.has_value();
    v[i] = x.value_or(0.0);
  }
  if (!ok) return std::nullopt;
  return v;
}

std::optional<Box> read_box(const yaml::Map& fields) {
  Box box;
  const auto id = fields.required("id").integer(0, std::numeric_limits<std::uint32_t>::max());
  if (id) box.id = static_cast<std::uint32_t>(*id);
  const yaml::List size = fields.required("size").list("3 sizes", 3, 3);
  for (std::size_t i = 0; i < size.size(); ++i)
    box.size[static_cast<int>(i)] = size[i].number(kMinBoxSize, kMaxBoxSize).value_or(1.0);
  const auto position = vector<3>(fields.required("position"), "a position x, y, z");
  Eigen::Quaterniond q = Eigen::Quaterniond::Identity();
  const yaml::Node orientation = fields.find("orientation");
  if (const auto wxyz = vector<4>(orientation, "a quaternion w, x, y, z")) {
    if (wxyz->norm() < 1e-9)
      orientation.error("must be a rotation, got a zero quaternion");
    else
      q = Eigen::Quaterniond((*wxyz)[0], (*wxyz)[1], (*wxyz)[2], (*wxyz)[3]).normalized();
  }
  box.pose = Eigen::Isometry3d::Identity();
  box.pose.linear() = q.toRotationMatrix();
  box.pose.translation() = position.value_or(Eigen::Vector3d::Zero());
  // 0 or absent: not known (a perceived world); the simulator needs it.
  box.mass = fields.find("mass").number(0.0, kMaxMass).value_or(0.0);
  if (!id || !size || !position) return std::nullopt;
  return box;
}

Expected<World> read_world(Expected<yaml::Document> doc) {
  if (!doc) return doc.error();
  const yaml::Map top = doc->root().map("a world", {"format", "version", "trailer", "boxes"});
  if (!top) return doc->error();
  const yaml::Node format = top.required("format");
  if (const auto f = format.string(); f && *f != kFormat)
    format.error(fmt::format("expected '{}', got '{}'", kFormat, *f));
  const yaml::Node version = top.required("version");
  if (const auto v = version.integer(); v && *v != kVersion)
    version.error(fmt::format("unsupported version {} (this reader knows {})", *v, kVersion));
  // Not a world of this version: what else is wrong with it does not matter.
  if (!doc->ok()) return doc->error();
  World world;
  const yaml::Map trailer = top.required("trailer").map("a trailer", {"width", "height", "depth"});
  world.trailer.width = trailer.required("width").number(0.5, kMaxTrailerWidth).value_or(1.0);
  world.trailer.height = trailer.required("height").number(0.5, kMaxTrailerHeight).value_or(1.0);
  world.trailer.depth = trailer.required("depth").number(0.5, kMaxTrailerDepth).value_or(1.0);

  std::map<std::uint32_t, std::string> ids;  // id -> the path of the box that has it
  for (const yaml::Node& item : top.required("boxes").list("a list of boxes", 0, kMaxBoxes)) {
    const yaml::Map fields = item.map("a box", {"id", "size", "position", "orientation", "mass"});
    auto box = fields ? read_box(fields) : std::nullopt;
    if (!box) continue;
    const yaml::Node id = fields.find("id");
    if (const auto [first, inserted] = ids.emplace(box->id, id.path()); !inserted) {
      id.error(fmt::format("duplicate id {} (also {})", box->id, first->second));
      continue;
    }
    world.boxes.push_back(std::move(*box));
  }
  return doc->result(std::move(world));
}

}  // namespace

Expected<World> parse_world(const std::string& text, const std::string& origin) {
  return read_world(yaml::Document::parse(text, origin));
}

Expected<World> load_world(const std::filesystem::path& file) {
  return read_world(yaml::Document::open(file.string(), "the world"));
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

Status save_world(const World& world, const std::filesystem::path& file) {
  return write_file_atomically(file.string(), format_world(world));
}

}  // namespace plr::sim
