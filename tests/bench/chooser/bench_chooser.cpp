// The strategy chooser's figures: the time of one decision (features of W,
// the nearest library world, the SVM's verdict) on worlds of A1, A2, B1 and
// B2, p50 and p99 (issue 21's target: p99 <= 1 ms); and, from a training's
// data set, the wall time of each DAgger iteration and the accuracy curve.
//
//   bench_chooser [--quick] [--json] [--library FILE] [--model FILE] [--data FILE]
//                 [--seeds N] [--repeats R]
//                 [--fidelity full|adaptive|fast] [--compare-fidelity]
//                 [--label-worlds A1:3,B1:3] [--label-states N] [--particles N]
//                 [--rollout-actions N]
// Defaults: lib/library.plrl, chooser/model.plrm, chooser/data.plrd (what
// configs/train_chooser.yaml makes), seeds 1-10 of each family, 200 decisions
// per world. --quick: seeds 1-3, 50 decisions. Worlds are the generators'
// layouts (not settled: latency does not depend on it).
//
// With --fidelity or --compare-fidelity, the cost of a chooser label as the
// training makes one (sim/chooser/training/dagger.cpp): from a state, the
// nearest library strategy and strategy H rolled out for rollout-actions
// actions on each of `particles` mass particles (the state's own masses,
// then draws from the prior), one after the other in this process. The
// states are each label world's start and the states H's rollout reaches
// from it (label-states per world), made at full fidelity; each is labelled
// at --fidelity's level, and with --compare-fidelity at full fidelity too:
// per label the wall time at each level, the ratio (medians over the
// labels), and whether the label (NN, H or a tie) is the same.
// Defaults: A1:3 and B1:3, 3 states each, 2 particles, 3 actions (the
// shipped chooser's training settings); --quick: 1 state each.
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <map>
#include <string>
#include <vector>

#include "bench_cli.hpp"
#include "bench_util.hpp"
#include "plr/actions/rig.hpp"
#include "plr/chooser/model.hpp"
#include "plr/chooser/nearest.hpp"
#include "plr/chooser/training/data_set.hpp"
#include "plr/episode/open_loop.hpp"
#include "plr/sim/generators.hpp"
#include "plr/sim/library.hpp"

#include <plr/message.hpp>

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

using Masses = std::vector<std::pair<std::uint32_t, double>>;

double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// One state's label at the rig's fidelity: the rollouts of NN's strategy and
// of H on each particle, pooled; their wall time; and where H's rollout on
// the first particle ended (the next state of the trajectory).
struct Label {
  double wall_s = 0.0;
  double cpu_s = 0.0;  // this process's CPU time: what the machine's load does not change
  std::uint32_t nn_boxes = 0, h_boxes = 0;
  double nn_s = 0.0, h_s = 0.0;
  std::vector<std::uint8_t> h_end;
  std::uint64_t h_actions = 0;

  // As the training labels (its default tie settings): "NN", "H" or "tie".
  std::string verdict(std::size_t particles) const {
    const double nn = nn_s > 0 ? nn_boxes / nn_s : 0.0, h = h_s > 0 ? h_boxes / h_s : 0.0;
    const auto difference = nn_boxes > h_boxes ? nn_boxes - h_boxes : h_boxes - nn_boxes;
    if (std::abs(nn - h) <= 0.05 * std::max(nn, h) || difference < 2 * particles) return "tie";
    return nn > h ? "NN" : "H";
  }
};

plr::Expected<Label> label(plr::actions::Rig& rig, const std::vector<std::uint8_t>& state,
                           const plr::sim::Strategy& nearest, const std::vector<Masses>& particles,
                           std::uint64_t actions) {
  Label out;
  for (std::size_t p = 0; p < particles.size(); ++p) {
    for (const bool by_nn : {true, false}) {
      const auto t0 = Clock::now();
      const double c0 = cpu_seconds();
      auto memory = rig.restore(state);
      if (!memory) return memory.error();
      if (!particles[p].empty())
        if (auto ok = rig.simulation().set_masses(particles[p]); !ok) return ok.error();
      auto run =
          plr::episode::run_open_loop(rig.model(), rig.backend(), *memory,
                                      by_nn ? std::optional(nearest) : std::nullopt, {}, actions);
      if (!run) return run.error();
      out.wall_s += std::chrono::duration<double>(Clock::now() - t0).count();
      out.cpu_s += cpu_seconds() - c0;
      (by_nn ? out.nn_boxes : out.h_boxes) += run->boxes;
      (by_nn ? out.nn_s : out.h_s) += run->robot_time_s;
      if (!by_nn && p == 0) {
        out.h_end = rig.snapshot(*memory);
        out.h_actions = run->actions;
      }
    }
  }
  return out;
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
  std::string fidelity = "full";
  bool compare = false;
  std::vector<std::string> label_worlds{"A1:3", "B1:3"};
  int label_states = 3, particles = 2, rollout_actions = 3;
  auto* fidelity_option =
      app.add_option("--fidelity", fidelity, "Time chooser labels at this simulation fidelity")
          ->check(CLI::IsMember({"full", "adaptive", "fast"}))
          ->capture_default_str();
  app.add_flag("--compare-fidelity", compare,
               "Time each label at full fidelity and at --fidelity's level, side by side");
  app.add_option("--label-worlds", label_worlds, "Worlds (FAMILY:SEED) whose states are labelled")
      ->delimiter(',')
      ->capture_default_str();
  auto* states_option = app.add_option("--label-states", label_states, "States labelled per world")
                            ->check(CLI::PositiveNumber)
                            ->capture_default_str();
  app.add_option("--particles", particles, "Mass particles of a label")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--rollout-actions", rollout_actions, "Actions of a rollout")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  plr::bench::parse_or_exit(app, argc, argv);
  const plr::sim::Fidelity level = plr::sim::parse_fidelity(fidelity).value();
  if (compare && level == plr::sim::Fidelity::kFull)
    die("--compare-fidelity needs --fidelity adaptive or fast");
  const bool labels = compare || fidelity_option->count() > 0;
  if (quick && states_option->count() == 0) label_states = 1;
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
  if (labels) {
    auto rig = plr::actions::Rig::create([] {
      plr::actions::ActionOptions o;
      o.plan_timeout_s = plr::actions::kOfflinePlanTimeoutS;
      return o;
    }());
    if (!rig) die(rig.error().message);
    std::vector<plr::sim::Fidelity> levels{level};
    if (compare) levels = {plr::sim::Fidelity::kFull, level};
    nlohmann::json rows = nlohmann::json::array();
    std::vector<double> wall_full, wall_level, ratios, cpu_full, cpu_level, cpu_ratios;
    std::size_t same = 0;
    for (const std::string& name : label_worlds) {
      const auto colon = name.find(':');
      const auto family = plr::sim::parse_env_family(name.substr(0, colon));
      if (!family || colon == std::string::npos) die("--label-worlds: not FAMILY:SEED: " + name);
      const std::uint64_t seed = std::strtoull(name.c_str() + colon + 1, nullptr, 10);
      // The trajectory is made at full fidelity: every level labels the same states.
      (*rig)->set_fidelity(plr::sim::Fidelity::kFull);
      (*rig)->reset(plr::sim::make_environment(*family, seed));
      std::vector<std::uint8_t> state = (*rig)->snapshot({});
      for (int step = 0; step < label_states; ++step) {
        if (!(*rig)->restore(state)) die(name + ": the state does not restore");
        const auto seen = (*rig)->backend().observe();
        if (!seen) die(seen.error().message);
        if (seen->world.boxes.empty()) break;
        const auto nn = index.nearest(model->scaling().apply(plr::chooser::features(seen->world)));
        std::vector<Masses> masses(static_cast<std::size_t>(particles));
        for (int p = 1; p < particles; ++p) {
          const plr::sim::World drawn = plr::sim::sample_masses(
              seen->world, *family,
              plr::sim::particle_seed(plr::fnv1a(name + "#" + std::to_string(step)), p));
          for (const plr::sim::Box& b : drawn.boxes)
            masses[static_cast<std::size_t>(p)].emplace_back(b.id, b.mass);
        }
        std::vector<Label> made;
        for (const plr::sim::Fidelity at : levels) {
          (*rig)->set_fidelity(at);
          auto l = label(**rig, state, library->entries.at(nn.entry).strategy, masses,
                         static_cast<std::uint64_t>(rollout_actions));
          if (!l) die(name + " state " + std::to_string(step) + ": " + l.error().message);
          made.push_back(std::move(*l));
          std::fprintf(stderr, "%s state %d at %s: %.1f s\n", name.c_str(), step,
                       plr::sim::to_string(at).c_str(), made.back().wall_s);
        }
        nlohmann::json row = {{"world", name}, {"state", step}};
        for (std::size_t i = 0; i < levels.size(); ++i)
          row[plr::sim::to_string(levels[i])] = {{"wall_s", made[i].wall_s},
                                                 {"cpu_s", made[i].cpu_s},
                                                 {"nn_boxes", made[i].nn_boxes},
                                                 {"nn_robot_s", made[i].nn_s},
                                                 {"h_boxes", made[i].h_boxes},
                                                 {"h_robot_s", made[i].h_s},
                                                 {"label", made[i].verdict(masses.size())}};
        (compare ? wall_level : wall_full).push_back(made.back().wall_s);
        (compare ? cpu_level : cpu_full).push_back(made.back().cpu_s);
        if (compare) {
          wall_full.push_back(made.front().wall_s);
          cpu_full.push_back(made.front().cpu_s);
          cpu_ratios.push_back(made.front().cpu_s / std::max(1e-9, made.back().cpu_s));
          ratios.push_back(made.front().wall_s / std::max(1e-9, made.back().wall_s));
          row["full_over_level"] = ratios.back();
          row["same_label"] =
              made.front().verdict(masses.size()) == made.back().verdict(masses.size());
          same += row["same_label"].get<bool>();
        }
        rows.push_back(row);
        // The next state: where H's rollout on the state's own masses ended
        // (at full fidelity), as the training goes on when H is followed.
        if (made.front().h_actions == 0) break;
        state = made.front().h_end;
      }
    }
    out["labels"] = {{"fidelity", fidelity},
                     {"compare", compare},
                     {"particles", particles},
                     {"rollout_actions", rollout_actions},
                     {"rows", rows},
                     {"wall_s_median", plr::bench::median(compare ? wall_level : wall_full)},
                     {"cpu_s_median", plr::bench::median(compare ? cpu_level : cpu_full)}};
    if (compare) {
      out["labels"]["full_wall_s_median"] = plr::bench::median(wall_full);
      out["labels"]["full_over_level_median"] = plr::bench::median(ratios);
      out["labels"]["full_cpu_s_median"] = plr::bench::median(cpu_full);
      out["labels"]["full_over_level_cpu_median"] = plr::bench::median(cpu_ratios);
      out["labels"]["same_label"] = same;
    }
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
  if (out.contains("labels")) {
    const auto& l = out["labels"];
    std::printf("\nchooser labels (NN and H, %d particles x %d actions each)\n", particles,
                rollout_actions);
    std::printf("%-8s %5s %10s %10s %8s %10s %8s\n", "world", "state", compare ? "full [s]" : "",
                (fidelity + " [s]").c_str(), compare ? "ratio" : "", compare ? "CPU ratio" : "",
                "labels");
    for (const auto& r : l["rows"]) {
      const auto& at = r[fidelity];
      std::string labels_text = at["label"].get<std::string>();
      if (compare) labels_text = r["full"]["label"].get<std::string>() + "/" + labels_text;
      const std::string cpu =
          compare ? fmt::format("{:.2f}x", r["full"]["cpu_s"].get<double>() /
                                               std::max(1e-9, at["cpu_s"].get<double>()))
                  : "";
      std::printf("%-8s %5d %10s %10.1f %8s %10s %8s\n", r["world"].get<std::string>().c_str(),
                  r["state"].get<int>(),
                  compare ? fmt::format("{:.1f}", r["full"]["wall_s"].get<double>()).c_str() : "",
                  at["wall_s"].get<double>(),
                  compare ? fmt::format("{:.2f}x", r["full_over_level"].get<double>()).c_str() : "",
                  cpu.c_str(), labels_text.c_str());
    }
    if (compare) {
      std::printf("median: full %.1f s, %s %.1f s a label; full/%s %.2fx; same label %zu of %zu\n",
                  l["full_wall_s_median"].get<double>(), fidelity.c_str(),
                  l["wall_s_median"].get<double>(), fidelity.c_str(),
                  l["full_over_level_median"].get<double>(), l["same_label"].get<std::size_t>(),
                  l["rows"].size());
      std::printf("CPU time: full %.1f s, %s %.1f s a label; full/%s %.2fx\n",
                  l["full_cpu_s_median"].get<double>(), fidelity.c_str(),
                  l["cpu_s_median"].get<double>(), fidelity.c_str(),
                  l["full_over_level_cpu_median"].get<double>());
    } else
      std::printf("median: %.1f s a label at %s\n", l["wall_s_median"].get<double>(),
                  fidelity.c_str());
  }
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
