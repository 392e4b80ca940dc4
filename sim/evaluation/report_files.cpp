#include "plr/evaluation/report_files.hpp"

#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>

#include "plr/atomic_file.hpp"
#include "plr/svg_chart.hpp"
#include "plr/xml_escape.hpp"

extern char** environ;

namespace plr::evaluation {

namespace {

const char* color(const std::string& method) {
  if (method == "H") return "#1f77b4";
  if (method == "NN") return "#ff7f0e";
  if (method == "open-loop") return "#2ca02c";
  if (method == "expected-offline") return "#9467bd";
  if (method == "PLR") return "#d62728";
  return "#555555";
}

std::string pm(const nlohmann::json& j, const char* mean, const char* sd, int digits) {
  return fmt::format("{:.{}f} ± {:.{}f}", j[mean].get<double>(), digits, j[sd].get<double>(),
                     digits);
}

// "412 (3 of 4)": the median robot time to 90 % over the runs that got there.
std::string to_90(const nlohmann::json& method) {
  const auto& t = method["robot_s_to_90_percent"];
  const auto n = t["n"].get<std::size_t>();
  if (n == 0) return "not reached";
  return fmt::format("{:.0f} ({} of {})", t["median"].get<double>(), n,
                     method["runs"].get<std::size_t>());
}

}  // namespace

std::string plot_svg(const nlohmann::json& summary, const std::string& name) {
  const auto& env = summary["environments"][name];
  const auto& grid = summary["grid_s"];
  Chart chart;
  chart.title = fmt::format("{} ({}): boxes unloaded, mean ± standard error", name,
                            env["training"].get<bool>() ? "training" : "held out");
  chart.width = 680;
  chart.height = 420;
  chart.x.label = "robot time [s]";
  chart.x.min = 0;
  chart.x.max = std::max(1.0, grid.back().get<double>());
  chart.y.label = "boxes unloaded";
  chart.y.min = 0;
  for (const auto& method : summary["settings"]["methods"]) {
    const std::string m = method.get<std::string>();
    if (!env["methods"].contains(m)) continue;
    const auto& d = env["methods"][m];
    if (d["runs"].get<std::size_t>() == 0) continue;
    ChartSeries s;
    s.label = fmt::format("{} ({} runs)", m, d["runs"].get<std::size_t>());
    s.color = color(m);
    for (std::size_t i = 0; i < grid.size(); ++i) {
      const double mean = d["mean"][i].get<double>(), se = d["se"][i].get<double>();
      s.points.push_back({grid[i].get<double>(), mean});
      s.band_low.push_back(std::max(0.0, mean - se));
      s.band_high.push_back(mean + se);
    }
    chart.series.push_back(std::move(s));
  }
  return render_svg(chart);
}

std::string report_html(const nlohmann::json& r) {
  const auto& set = r["settings"];
  std::string h =
      "<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"/><title>PLR evaluation</title>\n"
      "<style>body{font-family:sans-serif;max-width:1000px;margin:auto}table{border-collapse:"
      "collapse}td,th{border:1px solid #999;padding:2px 8px;text-align:right}th{background:#ddd}"
      "td:first-child{text-align:left}</style></head><body>\n<h1>PLR evaluation</h1>\n";
  h += fmt::format(
      "<p>{} seeds from seed {}{}, each run cut at {:g} robot-seconds; library {}, chooser model "
      "{}. Figures from <a href=\"report.json\">report.json</a>.</p>\n",
      set["seeds"].get<std::uint64_t>(), set["first_seed"].get<std::uint64_t>(),
      set["quick"].get<bool>() ? " (quick mode)" : "", set["max_robot_time_s"].get<double>(),
      xml_escape(set["library"].get<std::string>()), xml_escape(set["model"].get<std::string>()));
  h += "<h2>Boxes unloaded against robot time</h2>\n";
  for (const auto& [name, env] : r["environments"].items())
    h += fmt::format("<img src=\"{}\" alt=\"{}\"/>\n",
                     xml_escape(env["plot_svg"].get<std::string>()), xml_escape(name));
  h += "<h2>Findings</h2>\n<ul>\n";
  for (const auto& f : r["findings"])
    h += "<li>" + xml_escape(f["text"].get<std::string>()) + "</li>\n";
  h += "</ul>\n<h3>The paper's claims</h3>\n<table id=\"claims\">\n<tr><th>claim</th><th>holds</th>"
       "<th>standard errors</th><th>the data behind it</th></tr>\n";
  for (const auto& c : r["claims"])
    h += fmt::format(
        "<tr data-row=\"{0}\"><td>{0}</td><td>{1}</td><td>{2:.1f}</td><td>{3}</td></tr>\n",
        xml_escape(c["claim"].get<std::string>()), c["holds"].get<bool>() ? "yes" : "no",
        c["z"].get<double>(),
        c.contains("why") ? xml_escape(c["why"]["text"].get<std::string>()) : "");
  h += "</table>\n";

  const auto& t1 = r["table1"];
  h += fmt::format(
      "<h2>Table I: planner queries per mode</h2>\n<p>{} runs of {}, all environments; planning "
      "time over the answered queries, queries and failures per run (mean ± sd).</p>\n<table "
      "id=\"table1\">\n<tr><th>mode</th><th>DOF</th><th>queries per run</th><th>planning time "
      "[ms]</th><th>failures [%]</th></tr>\n",
      t1["runs"].get<std::size_t>(), xml_escape(t1["method"].get<std::string>()));
  for (const auto& [key, m] : t1["modes"].items())
    h += fmt::format(
        "<tr data-row=\"{}\"><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}</td></tr>\n", key,
        xml_escape(m["name"].get<std::string>()), m["dof"].get<int>(),
        pm(m, "queries_per_run", "queries_per_run_sd", 1),
        pm(m, "planning_ms", "planning_ms_sd", 1), pm(m, "failures_pct", "failures_pct_sd", 1));
  h += "</table>\n";
  const auto& t2 = r["table2"];
  h += fmt::format(
      "<h2>Table II: picks and sweeps</h2>\n<p>{} runs of {}, all environments; times per "
      "execution, executions and boxes per second per run (mean ± sd).</p>\n<table "
      "id=\"table2\">\n<tr><th>action</th><th>executions per run</th><th>planning time "
      "[s]</th><th>execution time [s]</th><th>boxes per second</th></tr>\n",
      t2["runs"].get<std::size_t>(), xml_escape(t2["method"].get<std::string>()));
  for (const auto& [key, a] : t2["actions"].items())
    h += fmt::format(
        "<tr data-row=\"{0}\"><td>{0}</td><td>{1}</td><td>{2}</td><td>{3}</td><td>{4}</td></tr>\n",
        key, pm(a, "executions_per_run", "executions_per_run_sd", 1),
        pm(a, "plan_s", "plan_s_sd", 2), pm(a, "exec_s", "exec_s_sd", 2),
        pm(a, "boxes_per_s", "boxes_per_s_sd", 3));
  h += "</table>\n";

  h += "<h2>Boxes by the horizon</h2>\n<table id=\"methods\">\n<tr><th>environment</th><th>method"
       "</th><th>runs</th><th>boxes (mean ± se)</th><th>of boxes</th><th>robot s to 90 % (median; "
       "runs there)</th><th>why runs ended</th></tr>\n";
  for (const auto& [name, env] : r["environments"].items())
    for (const auto& [m, d] : env["methods"].items()) {
      std::string stops;
      for (const auto& [why, n] : d["stop_reasons"].items())
        stops += fmt::format("{}{} × {}", stops.empty() ? "" : "; ", n.get<int>(), why);
      h += fmt::format(
          "<tr data-row=\"{0}/{1}\"><td>{0}</td><td>{1}</td><td>{2}</td><td>{3}</td><td>{4:.1f}"
          "</td><td>{5}</td><td style=\"text-align:left\">{6}</td></tr>\n",
          xml_escape(name), xml_escape(m), d["runs"].get<std::size_t>(),
          pm(d["boxes_at_horizon"], "mean", "se", 1), d["boxes_total"]["mean"].get<double>(),
          to_90(d), xml_escape(stops));
    }
  h += "</table>\n<h2>Whole trailers</h2>\n<p>Robot seconds to half, 90 % and all of a trailer's "
       "boxes (a run that did not get there counts as the horizon; runs there in brackets), and "
       "boxes out at 300, 600 and 1200 robot-seconds (mean ± se).</p>\n<table id=\"trailers\">\n"
       "<tr><th>environment</th><th>method</th><th>to 50 %</th><th>to 90 %</th><th>to empty</th>"
       "<th>at 300 s</th><th>at 600 s</th><th>at 1200 s</th></tr>\n";
  for (const auto& [name, env] : r["environments"].items())
    for (const auto& [m, d] : env["methods"].items()) {
      auto to = [&](const char* share) {
        const auto& t = d["time_to_share_s"][share];
        return fmt::format("{} ({})", pm(t, "mean", "se", 0), t["reached"].get<std::size_t>());
      };
      h += fmt::format(
          "<tr data-row=\"{0}/{1}\"><td>{0}</td><td>{1}</td><td>{2}</td><td>{3}</td><td>{4}</td>"
          "<td>{5}</td><td>{6}</td><td>{7}</td></tr>\n",
          xml_escape(name), xml_escape(m), to("50"), to("90"), to("100"),
          pm(d["boxes_at"]["300"], "mean", "se", 1), pm(d["boxes_at"]["600"], "mean", "se", 1),
          pm(d["boxes_at"]["1200"], "mean", "se", 1));
    }
  h += "</table>\n";
  if (r.contains("fidelity_check") && !r["fidelity_check"]["pairs"].empty()) {
    const auto& check = r["fidelity_check"];
    h += fmt::format(
        "<h2>Fidelity check</h2>\n<p>The runs are simulated at the {} level; these seeds ran "
        "again at full fidelity. Boxes by the horizon differ by {:.1f} at the median, {:.0f} at "
        "most; {} of {} runs ended the same way.</p>\n<table id=\"fidelity\">\n<tr><th>"
        "environment</th><th>method</th><th>seed</th><th>boxes ({})</th><th>boxes (full)</th>"
        "<th>difference</th><th>robot time [s] ({})</th><th>robot time [s] (full)</th><th>end "
        "({})</th><th>end (full)</th><th>wall [s] ({})</th><th>wall [s] (full)</th></tr>\n",
        xml_escape(check["level"].get<std::string>()),
        check["median_abs_boxes_difference"].get<double>(),
        check["max_abs_boxes_difference"].get<double>(), check["same_ending"].get<std::size_t>(),
        check["pairs"].size(), xml_escape(check["level"].get<std::string>()),
        xml_escape(check["level"].get<std::string>()),
        xml_escape(check["level"].get<std::string>()),
        xml_escape(check["level"].get<std::string>()));
    for (const auto& p : check["pairs"])
      h += fmt::format(
          "<tr data-row=\"{0}/{1}/{2}\"><td>{0}</td><td>{1}</td><td>{2}</td><td>{3:.0f}</td>"
          "<td>{4:.0f}</td><td>{5:+.0f}</td><td>{6:.0f}</td><td>{7:.0f}</td><td>{8}</td>"
          "<td>{9}</td><td>{10:.0f}</td><td>{11:.0f}</td></tr>\n",
          xml_escape(p["environment"].get<std::string>()),
          xml_escape(p["method"].get<std::string>()), p["seed"].get<std::uint64_t>(),
          p["boxes_at_horizon"].get<double>(), p["boxes_at_horizon_full"].get<double>(),
          p["boxes_difference"].get<double>(), p["robot_time_s"].get<double>(),
          p["robot_time_s_full"].get<double>(), xml_escape(p["ended"].get<std::string>()),
          xml_escape(p["ended_full"].get<std::string>()), p["wall_s"].get<double>(),
          p["wall_s_full"].get<double>());
    h += "</table>\n";
  }
  h += "<h2>Runs</h2>\n<table id=\"runs\">\n<tr><th>environment</th><th>method</th>"
       "<th>seed</th><th>world</th><th>boxes</th><th>robot time [s]</th><th>actions</th>"
       "<th>wall [s]</th><th>fidelity</th><th>end</th></tr>\n";
  for (const auto& x : r["runs"])
    h += fmt::format(
        "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}/{}</td><td>{:.0f}</td><td>{}</td>"
        "<td>{:.0f}</td><td>{}</td><td style=\"text-align:left\">{}</td></tr>\n",
        xml_escape(x["environment"].get<std::string>()), xml_escape(x["method"].get<std::string>()),
        x["seed"].get<std::uint64_t>(), xml_escape(x["world"].get<std::string>()),
        x["boxes_unloaded"].get<std::uint64_t>(), x["boxes_total"].get<std::uint64_t>(),
        x["robot_time_s"].get<double>(), x["actions"].get<std::uint64_t>(),
        x["wall_s"].get<double>(), xml_escape(x.value("fidelity", std::string("full"))),
        xml_escape(x["stop_reason"].get<std::string>()));
  h += "</table>\n</body></html>\n";
  return h;
}

plr::Status svg_to_png(const std::filesystem::path& svg, const std::filesystem::path& png) {
  const std::string tmp = png.string() + ".tmp";
  const std::string in = svg.string();
  std::vector<std::string> args = {"rsvg-convert", "--format", "png", "--output", tmp, in};
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  pid_t pid = 0;
  const int err = ::posix_spawnp(&pid, "rsvg-convert", nullptr, nullptr, argv.data(), environ);
  if (err != 0)
    return plr::make_error(PLR_ERR_UNAVAILABLE,
                           fmt::format("rsvg-convert: {} (install the Debian package librsvg2-bin)",
                                       std::strerror(err)));
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::filesystem::remove(tmp);
    return plr::make_error(PLR_ERR_INTERNAL, "rsvg-convert failed on " + in);
  }
  std::error_code ec;
  std::filesystem::rename(tmp, png, ec);
  if (ec) return plr::make_error(PLR_ERR_INTERNAL, png.string() + ": " + ec.message());
  return {};
}

plr::Status write_report(const nlohmann::json& summary, const std::filesystem::path& dir) {
  for (const auto& [name, env] : summary["environments"].items()) {
    const auto svg = dir / env["plot_svg"].get<std::string>();
    if (auto ok = plr::write_file_atomically(svg.string(), plot_svg(summary, name)); !ok) return ok;
    if (auto ok = svg_to_png(svg, dir / env["plot_png"].get<std::string>()); !ok) return ok;
  }
  if (auto ok = plr::write_file_atomically((dir / "report.json").string(), summary.dump(1) + "\n");
      !ok)
    return ok;
  return plr::write_file_atomically((dir / "report.html").string(), report_html(summary));
}

}  // namespace plr::evaluation
