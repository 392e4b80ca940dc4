// The evaluation's report files (sim/evaluation/report_files.cpp) from the
// summary of a few synthetic runs (runs.hpp): which files, and what the
// report's tables say.
#include "plr/evaluation/report_files.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <iterator>

#include "plr/evaluation/summary.hpp"
#include "runs.hpp"

namespace plr::evaluation {
namespace {

namespace fs = std::filesystem;

nlohmann::json summary() {
  auto runs = testing::runs();
  // Names and reasons are written into HTML and SVG: escaped.
  runs[3]["error"] = "killed <by> signal & timeout";
  return summarize(testing::settings(), runs, true);
}

std::string read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

struct TempDir {
  TempDir() : path(fs::temp_directory_path() / ("plr_report_files_" + std::to_string(::getpid()))) {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
  fs::path path;
};

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST(ReportHtml, HoldsTheClaimsTablesAndEveryRun) {
  const std::string h = report_html(summary());
  EXPECT_TRUE(
      contains(h, "<p>3 seeds from seed 1 (quick mode), each run cut at 120 robot-seconds"));
  for (const char* id : {"claims", "table1", "table2", "methods", "trailers", "runs"})
    EXPECT_TRUE(contains(h, std::string("<table id=\"") + id + "\">")) << id;
  EXPECT_TRUE(contains(
      h, "<tr data-row=\"PLR &gt;= H on A1\"><td>PLR &gt;= H on A1</td><td>no</td><td>-1.6</td>"));
  EXPECT_TRUE(contains(h,
                       "<tr data-row=\"PLR &gt; H on A1 at 600 s\"><td>PLR &gt; H on A1 at 600 "
                       "s</td><td>yes</td><td>2.5</td>"));
  // H on A1 over whole trailers: emptied at 60 and 40 s, the third counted
  // at the 120 s horizon.
  EXPECT_TRUE(contains(h,
                       "<tr data-row=\"A1/H\"><td>A1</td><td>H</td><td>53 ± 7 (3)</td><td>73 ± "
                       "24 (2)</td><td>73 ± 24 (2)</td><td>8.7 ± 1.3</td>"));
  // Table I, M2 over PLR's three runs: 10 ± 10 queries, failures 10 ± 14.1 %.
  EXPECT_TRUE(contains(h, "<tr data-row=\"M2\"><td>M2</td><td>"));
  EXPECT_TRUE(contains(h, "<td>10.0 ± 10.0</td><td>2.9 ± 1.5</td><td>10.0 ± 14.1</td></tr>"));
  // Table II's pick row: 4/3 executions per run, 1 s planning, 9 s executing.
  EXPECT_TRUE(contains(h,
                       "<tr data-row=\"pick\"><td>pick</td><td>1.3 ± 2.3</td><td>1.00 ± "
                       "0.00</td><td>9.00 ± 0.00</td><td>0.100 ± 0.000</td></tr>"));
  // H on A1: 8.7 ± 1.3 boxes of 10, 90 % after a median 50 s in 2 of 3 runs.
  EXPECT_TRUE(contains(h,
                       "<tr data-row=\"A1/H\"><td>A1</td><td>H</td><td>3</td><td>8.7 ± "
                       "1.3</td><td>10.0</td><td>50 (2 of 3)</td>"));
  EXPECT_TRUE(contains(h, "1 × killed &lt;by&gt; signal &amp; timeout; 3 × trailer empty"));
  EXPECT_TRUE(contains(h,
                       "<td>B1</td><td>PLR</td><td>1</td><td>3.0 ± 0.0</td><td>10.0</td><td>"
                       "not reached</td>"));
  // One row per run.
  std::size_t rows = 0;
  for (auto at = h.find("<table id=\"runs\">"); (at = h.find("<tr><td>", at)) != std::string::npos;
       ++at)
    ++rows;
  EXPECT_EQ(rows, testing::runs().size());
  EXPECT_TRUE(contains(h, "<img src=\"A1.svg\" alt=\"A1\"/>"));
}

TEST(PlotSvg, IsAnSvgNamingTheEnvironmentAndItsMethods) {
  const std::string svg = plot_svg(summary(), "A1");
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_TRUE(contains(svg, "</svg>"));
  EXPECT_TRUE(contains(svg, "A1 (training)"));
  EXPECT_TRUE(contains(svg, "H (3 runs)"));
  EXPECT_TRUE(contains(svg, "PLR (2 runs)"));
  EXPECT_TRUE(contains(plot_svg(summary(), "B1"), "B1 (held out)"));
}

TEST(SvgToPng, WritesAPngOrSaysWhyNot) {
  const TempDir dir;
  const fs::path svg = dir.path / "a.svg", png = dir.path / "a.png";
  std::ofstream(svg) << plot_svg(summary(), "A1");
  ASSERT_TRUE(svg_to_png(svg, png)) << "rsvg-convert (librsvg2-bin) is needed";
  EXPECT_EQ(read(png).substr(1, 3), "PNG");
  std::ofstream(dir.path / "bad.svg") << "not an svg";
  const auto bad = svg_to_png(dir.path / "bad.svg", dir.path / "bad.png");
  ASSERT_FALSE(bad);
  EXPECT_TRUE(contains(bad.error().message, "rsvg-convert failed on"));
  EXPECT_FALSE(fs::exists(dir.path / "bad.png"));
  EXPECT_FALSE(fs::exists(dir.path / "bad.png.tmp"));
}

TEST(WriteReport, WritesThePlotsTheJsonAndTheHtml) {
  const TempDir dir;
  const nlohmann::json s = summary();
  ASSERT_TRUE(write_report(s, dir.path));
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(dir.path)) files.push_back(e.path().filename());
  std::sort(files.begin(), files.end());
  EXPECT_EQ(files, (std::vector<std::string>{"A1.png", "A1.svg", "B1.png", "B1.svg", "report.html",
                                             "report.json"}));
  EXPECT_EQ(nlohmann::json::parse(read(dir.path / "report.json")), s);
  EXPECT_EQ(read(dir.path / "report.html"), report_html(s));
  EXPECT_EQ(read(dir.path / "A1.svg"), plot_svg(s, "A1"));
}

}  // namespace
}  // namespace plr::evaluation
