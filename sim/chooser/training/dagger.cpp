#include "plr/chooser/training/dagger.hpp"

#include <plr/atomic_file.hpp>
#include <plr/frame.hpp>
#include <plr/message.hpp>

#include <fmt/format.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <optional>

#include "plr/chooser/model.hpp"
#include "plr/chooser/nearest.hpp"
#include "plr/chooser/training/data_set.hpp"
#include "plr/jobs/process_runner.hpp"
#include "plr/jobs/signals.hpp"
#include "plr/jobs/slurm_runner.hpp"
#include "plr/sim/generators.hpp"
#include "plr/sim/library.hpp"

#include "curve_svg.hpp"
#include "rollout.hpp"

namespace plr::chooser {

namespace {

using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

std::vector<int> labels_of(const std::vector<Sample>& samples) {
  std::vector<int> y;
  for (const Sample& s : samples) y.push_back(s.label);
  return y;
}
std::vector<Features> features_of(const std::vector<Sample>& samples) {
  std::vector<Features> x;
  for (const Sample& s : samples) x.push_back(s.features);
  return x;
}

double majority_share(const std::vector<Sample>& samples) {
  if (samples.empty()) return 0.0;
  std::size_t nearest = 0;
  for (const Sample& s : samples) nearest += s.label == kNearestLabel;
  const auto n = static_cast<double>(samples.size());
  return std::max(static_cast<double>(nearest), n - static_cast<double>(nearest)) / n;
}

// The particles' seed at a state: the same at the same state of a resumed
// training.
std::uint64_t state_seed(const std::string& world, std::uint32_t step) {
  return plr::fnv1a(world + "#" + std::to_string(step));
}

plr::Error error(const std::string& what) {
  return plr::make_error(PLR_ERR_INVALID, what);
}

// A few actions take seconds to minutes; a rollout past this is stuck.
constexpr double kRolloutTimeoutS = 3600;

// A state's rollouts' keys: the world, the step and the state itself, so a
// stored result is never taken for another state's.
std::string state_key(const std::string& world, std::uint32_t step,
                      const std::vector<std::uint8_t>& state) {
  std::string name = world;
  for (char& c : name)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '-' && c != '_') c = '_';
  return fmt::format("{}-s{}-{:08x}", name, step, plr::crc32(state.data(), state.size()));
}

// The rig the settings describe.
plr::Expected<std::unique_ptr<actions::Rig>> make_rig(const TrainingSettings& settings) {
  actions::ActionOptions options;
  options.observation = settings.observation;
  options.plan_timeout_s = actions::kOfflinePlanTimeoutS;
  auto rig = actions::Rig::create(std::move(options));
  // Every simulation the rollouts make: the forked children inherit it, a
  // Slurm task makes its rig here.
  if (rig) (*rig)->set_fidelity(settings.fidelity);
  return rig;
}

// DAgger's end: enough data, and no new best held-out accuracy for the
// last `patience` iterations.
bool stopped_rising(const DataSet& d, const TrainingSettings& settings) {
  if (settings.patience == 0 || d.training.size() < settings.min_samples) return false;
  if (d.iterations.size() < settings.patience) return false;
  const auto best = std::max_element(
      d.iterations.begin(), d.iterations.end(),
      [](const auto& a, const auto& b) { return a.validation_accuracy < b.validation_accuracy; });
  return static_cast<std::size_t>(d.iterations.end() - best) > settings.patience;
}

}  // namespace

plr::Expected<TrainingSummary> train_chooser(const TrainingSettings& settings,
                                             const std::function<void(const std::string&)>& log,
                                             const std::vector<std::string>& slurm_task) {
  auto library = sim::load_library(settings.library);
  if (!library) return library.error();
  if (library->entries.empty()) return error(settings.library.string() + ": the library is empty");
  const std::uint32_t library_crc = fingerprint(*library);
  const std::uint64_t hash = settings.hash(library_crc);
  std::error_code ec;
  fs::create_directories(settings.out, ec);
  if (ec) return error(settings.out.string() + ": " + ec.message());
  const fs::path data_file = settings.out / "data.plrd", model_file = settings.out / "model.plrm",
                 curve_file = settings.out / "validation.svg";

  DataSet d;
  if (fs::exists(data_file)) {
    auto loaded = load_data_set(data_file);
    if (!loaded) return loaded.error();
    d = std::move(*loaded);
    if (d.settings_hash != hash)
      return error(data_file.string() +
                   ": made with other settings or another library; train into another folder "
                   "(out) or remove this one");
    log(fmt::format("resuming: {} validation and {} training states labelled, {} iterations",
                    d.validation.size(), d.training.size(), d.iterations.size()));
  } else {
    // The scaling is fixed before any label: the training worlds' layouts
    // and the library's worlds, the spaces NN and M work in.
    std::vector<Features> seen;
    for (const WorldSource& w : settings.train) {
      auto world = w.layout();
      if (!world) return world.error();
      seen.push_back(features(*world, settings.observation));
    }
    for (const sim::LibraryEntry& e : library->entries)
      seen.push_back(features(e.world, settings.observation));
    d.settings_hash = hash;
    d.scaling = Scaling::fit(seen);
    if (auto ok = save_data_set(d, data_file); !ok) return ok.error();
  }
  const LibraryIndex index(*library, d.scaling, settings.observation);
  // Not the command line: where the data goes and where rollouts run do
  // not change the model.
  const std::string made_by = "plr chooser train: " + settings.describe(library_crc);
  auto rig = make_rig(settings);
  if (!rig) return rig.error();
  // The rollouts: children forked for each job (they inherit the rig and
  // the library), or Slurm array tasks that load them, their results in a
  // store beside the data set until the state's label is saved.
  const RolloutContext context{**rig, *library, settings.h, settings.rollout_actions};
  jobs::Kinds kinds;
  add_rollout_kind(kinds, context);
  std::optional<jobs::Store> store;
  std::unique_ptr<jobs::Runner> runner;
  if (settings.runner.kind == jobs::RunnerSettings::Kind::kSlurm) {
    if (slurm_task.empty()) return error("rollouts on Slurm need the command of a task");
    auto opened = jobs::Store::open(settings.out / "rollouts");
    if (!opened) return opened.error();
    store.emplace(std::move(*opened));
    runner = std::make_unique<jobs::SlurmRunner>(*store, slurm_task, settings.runner.slurm);
  } else {
    auto local = jobs::ProcessRunner::create({{},
                                              &kinds,
                                              static_cast<unsigned>(std::max(settings.workers, 1)),
                                              kRolloutTimeoutS,
                                              1,
                                              true,
                                              {}});
    if (!local) return local.error();
    runner = std::move(*local);
  }

  const auto below_minimum = [&]() -> std::string {
    if (d.training.size() >= settings.min_samples) return {};
    return fmt::format("{} labelled states, {} {} (min_samples)", d.training.size(), kBelowMinimum,
                       settings.min_samples);
  };
  std::optional<Model> model;
  const auto retrain = [&]() -> plr::Status {
    auto m = Model::train(features_of(d.training), labels_of(d.training), d.scaling, library_crc,
                          settings.svm);
    if (!m) return m.error();
    model = std::move(*m);
    model->set_made_by(made_by + (below_minimum().empty() ? "" : " | data: " + below_minimum()));
    return {};
  };
  if (!d.training.empty())
    if (auto ok = retrain(); !ok) return ok.error();

  auto world_start = Clock::now();
  for (;;) {
    const auto& worlds = d.validating ? settings.validation : settings.train;
    if (d.world >= worlds.size()) {
      if (!d.validating) break;
      d.validating = false;
      d.world = d.step = 0;
      d.state.clear();
      if (auto ok = save_data_set(d, data_file); !ok) return ok.error();
      continue;
    }
    if (!d.validating && d.state.empty() && stopped_rising(d, settings)) {
      log(
          fmt::format("the held-out accuracy has not risen for {} iterations, with {} labelled "
                      "states: the training ends",
                      settings.patience, d.training.size()));
      break;
    }
    const WorldSource& source = worlds[d.world];
    const auto t0 = Clock::now();
    if (d.state.empty()) {
      auto truth = source.load();
      if (!truth) return truth.error();
      (*rig)->reset(*truth);
      d.state = (*rig)->snapshot({});
      world_start = t0;
    }
    if (auto restored = (*rig)->restore(d.state); !restored) return restored.error();
    auto seen = (*rig)->backend().observe();
    if (!seen) return seen.error();

    bool world_done = seen->world.boxes.empty() || d.step >= settings.states_per_world;
    // The stored rollouts of the state labelled now: once the data set is
    // saved they are not needed again (a resumed training goes on from the
    // next state).
    std::vector<std::string> labelled;
    const auto forget = [&] {
      if (store)
        for (const std::string& key : labelled) fs::remove(store->result_file(key));
    };
    if (!world_done) {
      const Features f = features(seen->world, settings.observation);
      const Nearest nn = index.nearest(d.scaling.apply(f));
      // Pairs of rollouts (NN, H): particle 0 is the state as it is, the
      // others draw the masses W does not show.
      std::vector<RolloutJob> todo;
      const auto family = source.family() ? source.family() : settings.mass_prior;
      for (std::uint32_t p = 0; p < settings.particles; ++p) {
        std::vector<std::pair<std::uint32_t, double>> masses;
        if (p > 0) {
          // Settings refuse particles without a family to draw from.
          const sim::World particle = sim::sample_masses(
              seen->world, *family,
              sim::particle_seed(state_seed(source.name, d.step), static_cast<int>(p)));
          for (const sim::Box& b : particle.boxes) masses.emplace_back(b.id, b.mass);
        }
        todo.push_back({static_cast<std::uint32_t>(nn.entry), masses});
        todo.push_back({std::nullopt, std::move(masses)});
      }
      const auto batch = rollout_jobs(state_key(source.name, d.step, d.state), d.state, todo);
      // Ctrl-C or SIGTERM while rollouts run stops them (a Slurm array is
      // cancelled); the data set holds every state labelled so far.
      const jobs::StopOnSignals stop;
      jobs::RunOptions run_options;
      run_options.stop = [&] { return stop(); };
      auto outcome = jobs::run(batch, *runner, store ? &*store : nullptr, run_options);
      if (!outcome) return outcome.error();
      if (outcome->stopped)
        return plr::make_error(PLR_ERR_CANCELLED,
                               "stopped; run it again on the same out folder to go on");
      const auto runs = rollout_results(*outcome);
      for (const jobs::Job& j : batch) labelled.push_back(j.key);
      bool failed = false;
      for (const auto& r : runs) {
        if (!r) {
          // A rollout that cannot go on (a process that died, an action the
          // model refused) ends this world's trajectory, not the training.
          log(fmt::format("{} state {}: {}; going on with the next world", source.name, d.step,
                          r.error().message));
          failed = true;
        }
      }
      if (failed) {
        ++d.world;
        d.step = 0;
        d.state.clear();
        if (auto ok = save_data_set(d, data_file); !ok) return ok.error();
        forget();
        continue;
      }
      Rollout by_nn, by_h;  // pooled over the particles
      for (std::size_t i = 0; i < runs.size(); ++i) {
        Rollout& to = i % 2 == 0 ? by_nn : by_h;
        to.boxes += runs[i]->boxes;
        to.robot_time_s += runs[i]->robot_time_s;
      }
      const double best = std::max(by_nn.rate(), by_h.rate());
      const auto box_difference = static_cast<std::uint32_t>(
          std::abs(static_cast<long>(by_nn.boxes) - static_cast<long>(by_h.boxes)));
      const bool tie = std::abs(by_nn.rate() - by_h.rate()) <= settings.tie_margin * best ||
                       box_difference < settings.tie_boxes * settings.particles;
      const int label = by_nn.rate() > by_h.rate() ? kNearestLabel : kHardcodedLabel;
      Sample s{source.name,
               d.step,
               f,
               label,
               static_cast<std::uint32_t>(nn.entry),
               nn.distance,
               by_nn.boxes,
               by_nn.robot_time_s,
               by_h.boxes,
               by_h.robot_time_s};
      bool follow_nearest = label == kNearestLabel;
      if (tie) {
        // Not a sample; the trajectory goes on as M (or, before there is
        // one, H) would go.
        follow_nearest = !d.validating && model && model->decide(f).nearest;
      } else if (d.validating) {
        d.validation.push_back(s);
      } else {
        d.training.push_back(s);
        if (auto ok = retrain(); !ok) return ok.error();
        follow_nearest = model->decide(f).nearest;
      }
      log(fmt::format(
          "{} {} state {}: NN {} ({:.2f}) {} boxes in {:.1f} s, H {} boxes in {:.1f} s "
          "(over {} particles) -> {}; going on with {} ({:.1f} s)",
          d.validating ? "validation" : "training", source.name, d.step,
          library->entries[nn.entry].name, nn.distance, by_nn.boxes, by_nn.robot_time_s, by_h.boxes,
          by_h.robot_time_s, settings.particles,
          tie                      ? "tie, not a sample"
          : label == kNearestLabel ? "NN"
                                   : "H",
          follow_nearest ? "NN" : "H", std::chrono::duration<double>(Clock::now() - t0).count()));
      const Rollout& next = *runs[follow_nearest ? 0 : 1];  // particle 0: the state's masses
      ++d.step;
      if (next.actions == 0) {
        world_done = true;  // nothing moves from here: the trailer is done with
      } else {
        d.state = next.end;
      }
    }
    if (world_done) {
      if (!d.validating && model) {
        IterationRecord r;
        r.iteration = static_cast<std::uint32_t>(d.iterations.size() + 1);
        r.samples = static_cast<std::uint32_t>(d.training.size());
        r.cv_accuracy = model->cv_accuracy();
        r.validation_accuracy = model->accuracy(features_of(d.validation), labels_of(d.validation));
        r.majority_accuracy = majority_share(d.validation);
        r.c = model->c();
        r.gamma = model->gamma();
        r.wall_s = std::chrono::duration<double>(Clock::now() - world_start).count();
        d.iterations.push_back(r);
        if (auto ok = model->save(model_file); !ok) return ok.error();
        if (auto ok = plr::write_file_atomically(curve_file.string(), curve_svg(d.iterations)); !ok)
          return ok.error();
        log(
            fmt::format("iteration {} ({}): {} samples, validation accuracy {:.3f} (majority "
                        "{:.3f}), cross-validation {:.3f}, C {:g}, gamma {:g}, {:.0f} s",
                        r.iteration, source.name, r.samples, r.validation_accuracy,
                        r.majority_accuracy, r.cv_accuracy, r.c, r.gamma, r.wall_s));
      }
      ++d.world;
      d.step = 0;
      d.state.clear();
    }
    d.wall_s += std::chrono::duration<double>(Clock::now() - t0).count();
    if (auto ok = save_data_set(d, data_file); !ok) return ok.error();
    forget();
  }
  if (!model) return error("no training state was labelled: nothing to train on");
  if (auto ok = model->save(model_file); !ok) return ok.error();
  TrainingSummary summary;
  summary.validation_samples = d.validation.size();
  summary.training_samples = d.training.size();
  summary.iterations = d.iterations.size();
  summary.validation_accuracy = model->accuracy(features_of(d.validation), labels_of(d.validation));
  summary.majority_accuracy = majority_share(d.validation);
  summary.below_minimum = below_minimum();
  return summary;
}

int run_rollout_task(const TrainingSettings& settings, const fs::path& batch_file) {
  std::optional<sim::Library> library;
  std::unique_ptr<actions::Rig> rig;
  std::optional<RolloutContext> context;
  jobs::Kinds kinds;
  // Registered before anything is loaded (a task whose result is stored
  // exits at once); it runs on what prepare loads.
  kinds.add(kRolloutKind,
            [&](const jobs::Bytes& input) { return run_rollout_job(*context, input); });
  const auto prepare = [&] {
    auto l = sim::load_library(settings.library);
    auto made = l ? make_rig(settings) : plr::Expected<std::unique_ptr<actions::Rig>>(l.error());
    if (!made) {
      std::fprintf(stderr, "plr chooser: %s\n", made.error().message.c_str());
      std::exit(2);
    }
    library = std::move(*l);
    rig = std::move(*made);
    context.emplace(RolloutContext{*rig, *library, settings.h, settings.rollout_actions});
  };
  return jobs::run_array_task(kinds, batch_file, prepare);
}

}  // namespace plr::chooser
