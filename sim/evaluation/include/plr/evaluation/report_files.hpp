// What an evaluation writes from its summary (plr/evaluation/summary.hpp):
// per environment the comparison plot — boxes unloaded against robot time,
// each method's mean with a standard-error band, as the paper's figure — as
// SVG and PNG (rsvg-convert, Debian's librsvg2-bin), and report.html with
// the plots, Tables I and II, the findings and every run.
#pragma once

#include <plr/expected.hpp>

#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

namespace plr::evaluation {

// The plot of environment `name` of `summary`.
std::string plot_svg(const nlohmann::json& summary, const std::string& name);

// report.html's text.
std::string report_html(const nlohmann::json& summary);

// SVG file -> PNG file (written atomically) by rsvg-convert.
plr::Status svg_to_png(const std::filesystem::path& svg, const std::filesystem::path& png);

// Writes the plots (SVG, PNG), report.json and report.html into `dir`,
// each atomically.
plr::Status write_report(const nlohmann::json& summary, const std::filesystem::path& dir);

}  // namespace plr::evaluation
