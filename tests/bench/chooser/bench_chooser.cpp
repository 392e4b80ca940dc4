// The strategy chooser's figures: the time of one decision (features of W,
// the nearest library world, the SVM's verdict) on worlds of A1, A2, B1 and
// B2, p50 and p99 (issue 21's target: p99 <= 1 ms); and, from a training's
// data set, the wall time of each DAgger iteration and the accuracy curve.
//
//   bench_chooser [--quick] [--json] [--library FILE] [--model FILE] [--data FILE]
//                 [--seeds N] [--repeats R]
// Defaults: lib/library.plrl, chooser/model.plrm, chooser/data.plrd (what
// configs/train_chooser.yaml makes), seeds 1-10 of each family, 200 decisions
// per world. --quick: seeds 1-3, 50 decisions. Worlds are the generators'
// layouts (not settled: latency does not depend on it).
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <string>
#include <vector>

#include "bench_cli.hpp"
#include "bench_util.hpp"
#include "plr/chooser/model.hpp"
#include "plr/chooser/nearest.hpp"
#include "plr/chooser/training/data_set.hpp"
#include "plr/sim/generators.hpp"
#include "plr/sim/library.hpp"

namespace {

using Clock = std::chrono::steady_clock;
using plr::sim::EnvFamily;

[[noreturn]] void die(const std::string& what) {
  std::fprintf(stderr, "bench_chooser: %s\n", what.c_str());
  std::exit(1);
}

double percentile(std::vector<double> v, double p) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const auto i = static_cast<std::size_t>(p * static_cast<double>(v.size() - 1) + 0.5);
  return v[std::min(i, v.size() - 1)];
}

}  // namespace

int main(int argc, char** argv) {
  std::string library_file = "lib/library.plrl", model_file = "chooser/model.plrm",
              data_file = "chooser/data.plrd";
  int seeds = 10, repeats = 200;
  bool quick = false, json = false;
  CLI::App app{
      "The strategy chooser's decision time on A1, A2, B1 and B2 worlds, and the "
      "DAgger iterations of a training's data set"};
  plr::bench::add_quick_flag(app, quick, "seeds 1-3, 50 decisions per world");
  plr::bench::add_json_flag(app, json);
  app.add_option("--library", library_file, "Strategy library (.plrl)")->capture_default_str();
  app.add_option("--model", model_file, "Trained chooser model (.plrm)")->capture_default_str();
  app.add_option("--data", data_file, "The training's data set (.plrd)")->capture_default_str();
  auto* seeds_option = app.add_option("--seeds", seeds, "Seeds 1-N of each family")
                           ->check(CLI::PositiveNumber)
                           ->capture_default_str();
  auto* repeats_option = app.add_option("--repeats", repeats, "Decisions timed per world")
                             ->check(CLI::PositiveNumber)
                             ->capture_default_str();
  plr::bench::parse_or_exit(app, argc, argv);
  if (quick && seeds_option->count() == 0) seeds = 3;
  if (quick && repeats_option->count() == 0) repeats = 50;
  const auto library = plr::sim::load_library(library_file);
  if (!library) die(library.error().message);
  const auto model = plr::chooser::Model::load(model_file);
  if (!model)
    die(model.error().message + " (train one: plr chooser train configs/train_chooser.yaml)");
  const plr::chooser::LibraryIndex index(*library, model->scaling());

  // Per family: every decision's time, and each part's.
  struct Times {
    std::vector<double> total, features, nearest, svm;
    std::size_t chose_nearest = 0;
  };
  std::map<std::string, Times> by_family;
  const std::vector<EnvFamily> families{EnvFamily::kA1, EnvFamily::kA2, EnvFamily::kB1,
                                        EnvFamily::kB2};
  plr::bench::Progress progress("bench_chooser", families.size() * static_cast<std::size_t>(seeds));
  for (const EnvFamily family : families) {
    Times& t = by_family[std::string(to_string(family))];
    for (int seed = 1; seed <= seeds; ++seed) {
      const plr::sim::World world =
          plr::sim::generate_world(family, static_cast<std::uint64_t>(seed));
      for (int r = 0; r < repeats; ++r) {
        const auto t0 = Clock::now();
        const plr::chooser::Features f = plr::chooser::features(world);
        const auto t1 = Clock::now();
        const plr::chooser::Nearest nn = index.nearest(model->scaling().apply(f));
        const auto t2 = Clock::now();
        const plr::chooser::Verdict v = model->decide(f);
        const auto t3 = Clock::now();
        const auto ms = [](auto a, auto b) {
          return std::chrono::duration<double, std::milli>(b - a).count();
        };
        t.features.push_back(ms(t0, t1));
        t.nearest.push_back(ms(t1, t2));
        t.svm.push_back(ms(t2, t3));
        t.total.push_back(ms(t0, t3));
        if (r == 0) t.chose_nearest += v.nearest && nn.entry < library->entries.size();
      }
      progress.step(fmt::format("{} seed {}", to_string(family), seed));
    }
  }
  progress.finish();

  nlohmann::json out;
  out["library_entries"] = library->entries.size();
  out["support_vectors"] = model->support_vectors();
  out["seeds"] = seeds;
  out["repeats"] = repeats;
  Times all_a, all_b;
  for (const auto& [family, t] : by_family) {
    Times& group = family[0] == 'A' ? all_a : all_b;
    for (auto [from, to] : {std::pair{&t.total, &group.total},
                            {&t.features, &group.features},
                            {&t.nearest, &group.nearest},
                            {&t.svm, &group.svm}})
      to->insert(to->end(), from->begin(), from->end());
    group.chose_nearest += t.chose_nearest;
  }
  for (const auto& [name, t] : {std::pair{"A", &all_a}, {"B", &all_b}}) {
    out["latency_ms"][name] = {{"p50", percentile(t->total, 0.5)},
                               {"p99", percentile(t->total, 0.99)},
                               {"features_p50", percentile(t->features, 0.5)},
                               {"nearest_p50", percentile(t->nearest, 0.5)},
                               {"svm_p50", percentile(t->svm, 0.5)},
                               {"worlds", t->total.size() / static_cast<std::size_t>(repeats)},
                               {"chose_nearest", t->chose_nearest}};
  }
  // Training figures, if a training's data set is there.
  if (auto data = plr::chooser::load_data_set(data_file)) {
    std::vector<double> wall;
    nlohmann::json curve = nlohmann::json::array();
    for (const auto& r : data->iterations) {
      wall.push_back(r.wall_s);
      curve.push_back({{"iteration", r.iteration},
                       {"samples", r.samples},
                       {"validation_accuracy", r.validation_accuracy},
                       {"majority_accuracy", r.majority_accuracy},
                       {"cv_accuracy", r.cv_accuracy},
                       {"wall_s", r.wall_s}});
    }
    out["training"] = {
        {"iterations", data->iterations.size()},
        {"training_states", data->training.size()},
        {"validation_states", data->validation.size()},
        {"wall_s_total", data->wall_s},
        {"iteration_wall_s_median", plr::bench::median(wall)},
        {"iteration_wall_s_max", wall.empty() ? 0.0 : *std::max_element(wall.begin(), wall.end())},
        {"curve", curve}};
  } else {
    out["training"] = {{"missing", data.error().message}};
  }
  if (json) {
    std::printf("%s\n", out.dump().c_str());
    return 0;
  }
  std::printf("decision latency (features + NN + SVM), %d seeds x %d decisions per family\n", seeds,
              repeats);
  std::printf("%-8s %10s %10s %12s %10s %10s\n", "worlds", "p50 [ms]", "p99 [ms]", "features p50",
              "NN p50", "SVM p50");
  for (const char* g : {"A", "B"}) {
    const auto& l = out["latency_ms"][g];
    std::printf("%-8s %10.4f %10.4f %12.4f %10.4f %10.4f%s\n",
                g == std::string("A") ? "A1+A2" : "B1+B2", l["p50"].get<double>(),
                l["p99"].get<double>(), l["features_p50"].get<double>(),
                l["nearest_p50"].get<double>(), l["svm_p50"].get<double>(),
                l["p99"].get<double>() <= 1.0 ? "" : "  (over the 1 ms target)");
  }
  std::printf("library entries %zu, support vectors %zu\n", library->entries.size(),
              model->support_vectors());
  const auto& tr = out["training"];
  if (tr.contains("missing")) {
    std::printf("training: %s\n", tr["missing"].get<std::string>().c_str());
    return 0;
  }
  std::printf(
      "\ntraining: %zu iterations, %zu training + %zu validation states, %.0f s wall; "
      "per iteration median %.0f s, max %.0f s\n",
      tr["iterations"].get<std::size_t>(), tr["training_states"].get<std::size_t>(),
      tr["validation_states"].get<std::size_t>(), tr["wall_s_total"].get<double>(),
      tr["iteration_wall_s_median"].get<double>(), tr["iteration_wall_s_max"].get<double>());
  std::printf("%9s %8s %11s %9s %9s %8s\n", "iteration", "samples", "validation", "majority", "cv",
              "wall [s]");
  for (const auto& r : tr["curve"])
    std::printf("%9u %8u %11.3f %9.3f %9.3f %8.0f\n", r["iteration"].get<unsigned>(),
                r["samples"].get<unsigned>(), r["validation_accuracy"].get<double>(),
                r["majority_accuracy"].get<double>(), r["cv_accuracy"].get<double>(),
                r["wall_s"].get<double>());
  return 0;
}
