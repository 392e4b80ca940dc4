#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

#include "plr/sim/generators.hpp"
#include "plr/sim/render.hpp"

namespace plr::sim {
namespace {

std::size_t count(const std::string& s, const std::string& what) {
  std::size_t n = 0;
  for (std::size_t p = s.find(what); p != std::string::npos; p = s.find(what, p + 1)) ++n;
  return n;
}

TEST(Render, OnePolygonPerBoxAndRobotShape) {
  const World w = generate_world(EnvFamily::kA1, 4);
  RenderOptions o;
  o.robot.push_back({{1.0, 0.8, 0.5}, Eigen::Isometry3d(Eigen::Translation3d(1.0, 0.0, 0.5))});
  o.title = "A1 seed 4";
  for (View v : {View::kSide, View::kTop}) {
    const std::string svg = render_svg(w, v, o);
    EXPECT_EQ(svg.rfind("<svg", 0), 0u);
    EXPECT_EQ(count(svg, "<polygon"), w.boxes.size() + 1);
    EXPECT_NE(svg.find("A1 seed 4"), std::string::npos);
    EXPECT_NE(svg.find("</svg>"), std::string::npos);
  }
}

TEST(Render, HeavierBoxesAreDarker) {
  World w;
  for (int i = 0; i < 2; ++i) {
    Box b;
    b.id = static_cast<std::uint32_t>(i + 1);
    b.pose.translation() = Eigen::Vector3d(10.0 + i, 0.0, 0.2);
    b.mass = i == 0 ? 1.0 : 30.0;
    w.boxes.push_back(b);
  }
  const std::string svg = render_svg(w, View::kSide);
  EXPECT_NE(svg.find("#fce49b"), std::string::npos);  // light
  EXPECT_NE(svg.find("#a01414"), std::string::npos);  // heaviest
}

TEST(Render, WritesAFile) {
  const auto p = std::filesystem::temp_directory_path() / "plr_render_test.svg";
  ASSERT_TRUE(write_svg(p, generate_world(EnvFamily::kB1, 1), View::kTop));
  std::ifstream in(p);
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str().rfind("<svg", 0), 0u);
  std::filesystem::remove(p);
}

TEST(Render, AFileThatCannotBeWrittenIsNamed) {
  const auto p = std::filesystem::temp_directory_path() / "plr_no_such_folder" / "scene.svg";
  const Status written = write_svg(p, World{}, View::kSide);
  ASSERT_FALSE(written);
  EXPECT_EQ(written.error().message,
            p.string() + ": cannot create a temporary file: No such file or directory");
}

}  // namespace
}  // namespace plr::sim
