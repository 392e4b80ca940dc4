#include <plr/svg_chart.hpp>

#include <expat.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <map>
#include <string>
#include <vector>

namespace {

// Parses `svg` with expat; counts elements by name and keeps the text.
struct Parsed {
  bool ok = false;
  std::map<std::string, int> elements;
  std::string text;
  std::vector<std::string> polyline_points;
};

Parsed parse(const std::string& svg) {
  Parsed r;
  XML_Parser p = XML_ParserCreate(nullptr);
  XML_SetUserData(p, &r);
  XML_SetElementHandler(
      p,
      [](void* data, const XML_Char* name, const XML_Char** attributes) {
        auto& r = *static_cast<Parsed*>(data);
        ++r.elements[name];
        for (int i = 0; attributes[i]; i += 2)
          if (std::string(name) == "polyline" && std::string(attributes[i]) == "points")
            r.polyline_points.push_back(attributes[i + 1]);
      },
      [](void*, const XML_Char*) {});
  XML_SetCharacterDataHandler(p, [](void* data, const XML_Char* s, int n) {
    static_cast<Parsed*>(data)->text.append(s, static_cast<std::size_t>(n));
  });
  r.ok = XML_Parse(p, svg.data(), static_cast<int>(svg.size()), 1) == XML_STATUS_OK;
  XML_ParserFree(p);
  return r;
}

TEST(ChartTicks, AreRoundStepsInsideTheRange) {
  EXPECT_EQ(plr::chart_ticks(0, 100), (std::vector<double>{0, 20, 40, 60, 80, 100}));
  EXPECT_EQ(plr::chart_ticks(0, 1, 4), (std::vector<double>{0, 0.5, 1}));
  EXPECT_EQ(plr::chart_ticks(-7, 13), (std::vector<double>{-5, 0, 5, 10}));
  EXPECT_EQ(plr::chart_ticks(0, 3, 5, true), (std::vector<double>{0, 1, 2, 3}));
  const auto tenths = plr::chart_ticks(0, 0.6, 6);
  ASSERT_EQ(tenths.size(), 7u);
  EXPECT_DOUBLE_EQ(tenths[3], 0.3);
  EXPECT_TRUE(plr::chart_ticks(1, 1).empty());
}

TEST(SvgChart, DrawsEverySeriesWithItsLegendAsWellFormedXml) {
  plr::Chart c;
  c.title = "A1 <seed 1> & co";
  c.x.label = "robot time [s]";
  c.y.label = "boxes unloaded";
  c.y.min = 0;
  plr::ChartSeries band;
  band.label = "H & NN";
  band.points = {{0, 0}, {10, 3}, {25, 8}};
  band.band_low = {0, 2, 6};
  band.band_high = {0, 4, 9};
  plr::ChartSeries dashed;
  dashed.color = "#999";
  dashed.points = {{0, 10}, {25, 10}};
  dashed.dashed = true;
  plr::ChartSeries steps;
  steps.label = "steps";
  steps.color = "#c00";
  steps.points = {{0, 0}, {5, 1}};
  steps.steps = true;
  steps.marker_radius = 3;
  c.series = {band, dashed, steps};
  const std::string svg = plr::render_svg(c);
  const Parsed p = parse(svg);
  ASSERT_TRUE(p.ok) << svg;
  EXPECT_EQ(svg.rfind("<svg ", 0), 0u);
  EXPECT_EQ(p.elements.at("polyline"), 3);
  EXPECT_EQ(p.elements.at("polygon"), 1);  // the band
  EXPECT_EQ(p.elements.at("circle"), 2);   // the markers of "steps"
  EXPECT_NE(p.text.find("A1 <seed 1> & co"), std::string::npos);
  EXPECT_NE(p.text.find("H & NN"), std::string::npos);
  EXPECT_NE(p.text.find("steps"), std::string::npos);
  EXPECT_NE(p.text.find("robot time [s]"), std::string::npos);
  EXPECT_NE(p.text.find("boxes unloaded"), std::string::npos);
  // The y axis reaches the dashed line at 10 and is labelled in round steps.
  EXPECT_NE(p.text.find("10"), std::string::npos);
  // A step series holds each value until the next point: 2 points, 3 vertices.
  ASSERT_EQ(p.polyline_points.size(), 3u);
  EXPECT_EQ(std::count(p.polyline_points[2].begin(), p.polyline_points[2].end(), ','), 3);
  EXPECT_EQ(std::count(p.polyline_points[0].begin(), p.polyline_points[0].end(), ','), 3);
}

TEST(SvgChart, WithoutDataIsStillAChart) {
  plr::Chart c;
  c.title = "empty";
  const Parsed p = parse(plr::render_svg(c));
  EXPECT_TRUE(p.ok);
  EXPECT_EQ(p.elements.count("polyline"), 0u);
  EXPECT_GT(p.elements.at("line"), 0);  // the grid
}

}  // namespace
