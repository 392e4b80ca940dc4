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
#include "plr/sim/render.hpp"

extern char** environ;

namespace plr::evaluation {

namespace {

using sim::xml_escape;

const char* color(const std::string& method) {
  if (method == "H") return "#1f77b4";
  if (method == "NN") return "#ff7f0e";
  if (method == "open-loop") return "#2ca02c";
  if (method == "expected-offline") return "#9467bd";
  if (method == "PLR") return "#d62728";
  return "#555555";
}

// A round step for about `target` ticks over [0, max].
double tick_step(double max, int target) {
  const double raw = max / target;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * p >= raw) return m * p;
  return 10 * p;
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
  constexpr double kW = 680, kH = 420, kL = 60, kR = 210, kT = 40, kB = 50;
  const auto& env = summary["environments"][name];
  const auto& grid = summary["grid_s"];
  const double t_max = std::max(1.0, grid.back().get<double>());
  double n_max = 1;
  for (const auto& [m, d] : env["methods"].items())
    for (std::size_t i = 0; i < d["mean"].size(); ++i)
      n_max = std::max(n_max, d["mean"][i].get<double>() + d["se"][i].get<double>());
  const double y_step = tick_step(n_max, 6);
  n_max = std::ceil(n_max / y_step) * y_step;
  auto px = [&](double t) { return kL + (kW - kL - kR) * t / t_max; };
  auto py = [&](double n) { return kH - kB - (kH - kT - kB) * n / n_max; };
  std::string s = fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{0}\" height=\"{1}\" viewBox=\"0 0 {0} "
      "{1}\" font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"{0}\" height=\"{1}\" "
      "fill=\"white\"/>\n",
      kW, kH);
  s += fmt::format(
      "<text x=\"{}\" y=\"22\" font-size=\"14\">{} ({}): boxes unloaded, mean ± standard "
      "error</text>\n",
      kL, xml_escape(name), env["training"].get<bool>() ? "training" : "held out");
  const double x_step = tick_step(t_max, 6);
  for (double t = 0; t <= t_max + 1e-9; t += x_step)
    s += fmt::format(
        "<line x1=\"{0:.1f}\" y1=\"{1}\" x2=\"{0:.1f}\" y2=\"{2}\" stroke=\"#ddd\"/><text "
        "x=\"{0:.1f}\" y=\"{3}\" text-anchor=\"middle\">{4:g}</text>\n",
        px(t), kT, kH - kB, kH - kB + 16, t);
  for (double n = 0; n <= n_max + 1e-9; n += y_step)
    s += fmt::format(
        "<line x1=\"{0}\" y1=\"{1:.1f}\" x2=\"{2}\" y2=\"{1:.1f}\" stroke=\"#ddd\"/><text "
        "x=\"{3}\" y=\"{4:.1f}\" text-anchor=\"end\">{5:g}</text>\n",
        kL, py(n), kW - kR, kL - 6, py(n) + 4, n);
  s += fmt::format(
      "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"black\"/>\n", kL,
      kT, kW - kL - kR, kH - kT - kB);
  s += fmt::format(
      "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\">robot time [s]</text>\n<text x=\"14\" "
      "y=\"{}\" transform=\"rotate(-90 14 {})\" text-anchor=\"middle\">boxes unloaded</text>\n",
      (kL + kW - kR) / 2, kH - 12, (kT + kH - kB) / 2, (kT + kH - kB) / 2);
  int row = 0;
  for (const auto& method : summary["settings"]["methods"]) {
    const std::string m = method.get<std::string>();
    if (!env["methods"].contains(m)) continue;
    const auto& d = env["methods"][m];
    if (d["runs"].get<std::size_t>() == 0) continue;
    std::string upper, lower, line;
    for (std::size_t i = 0; i < grid.size(); ++i) {
      const double t = grid[i].get<double>(), mean = d["mean"][i].get<double>(),
                   se = d["se"][i].get<double>();
      upper += fmt::format("{:.1f},{:.1f} ", px(t), py(mean + se));
      line += fmt::format("{:.1f},{:.1f} ", px(t), py(mean));
    }
    for (std::size_t i = grid.size(); i-- > 0;) {
      const double t = grid[i].get<double>(),
                   low = std::max(0.0, d["mean"][i].get<double>() - d["se"][i].get<double>());
      lower += fmt::format("{:.1f},{:.1f} ", px(t), py(low));
    }
    s +=
        fmt::format("<polygon points=\"{}{}\" fill=\"{}\" fill-opacity=\"0.2\" stroke=\"none\"/>\n",
                    upper, lower, color(m));
    s += fmt::format("<polyline points=\"{}\" fill=\"none\" stroke=\"{}\" stroke-width=\"2\"/>\n",
                     line, color(m));
    const double ly = kT + 10 + 20 * row++;
    s += fmt::format(
        "<line x1=\"{0}\" y1=\"{1}\" x2=\"{2}\" y2=\"{1}\" stroke=\"{3}\" "
        "stroke-width=\"3\"/><text "
        "x=\"{4}\" y=\"{5}\">{6} ({7} runs)</text>\n",
        kW - kR + 10, ly, kW - kR + 30, color(m), kW - kR + 36, ly + 4, xml_escape(m),
        d["runs"].get<std::size_t>());
  }
  s += "</svg>\n";
  return s;
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
  h += "</table>\n<h2>Runs</h2>\n<table id=\"runs\">\n<tr><th>environment</th><th>method</th>"
       "<th>seed</th><th>world</th><th>boxes</th><th>robot time [s]</th><th>actions</th>"
       "<th>wall [s]</th><th>end</th></tr>\n";
  for (const auto& x : r["runs"])
    h += fmt::format(
        "<tr><td>{}</td><td>{}</td><td>{}</td><td>{}</td><td>{}/{}</td><td>{:.0f}</td><td>{}</td>"
        "<td>{:.0f}</td><td style=\"text-align:left\">{}</td></tr>\n",
        xml_escape(x["environment"].get<std::string>()), xml_escape(x["method"].get<std::string>()),
        x["seed"].get<std::uint64_t>(), xml_escape(x["world"].get<std::string>()),
        x["boxes_unloaded"].get<std::uint64_t>(), x["boxes_total"].get<std::uint64_t>(),
        x["robot_time_s"].get<double>(), x["actions"].get<std::uint64_t>(),
        x["wall_s"].get<double>(), xml_escape(x["stop_reason"].get<std::string>()));
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
