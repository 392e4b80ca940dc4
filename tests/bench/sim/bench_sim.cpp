// Real-time factor (simulated s / wall s) of the box simulation:
//   pick      settled A1 wall (>= 150 boxes): the arm reaches the wall face,
//             grips the top box of a column, pulls it out, drops it on the
//             nose belt, which carries it out;
//   sweep     settled B1 pile: a nose-like slab with a running belt drives
//             forward under the pile and back;
//   sequence  10 pick actions in a row on one A1 wall.
// Then the full state as bytes (Snapshot::to_bytes / from_bytes, and
// Simulation::from_snapshot): size and time, for the settled wall and for
// the pile in the middle of the sweep (boxes moving).
// Robot shapes move kinematically at industrial speeds (0.5 m/s, 1 m/s^2).
// Each scenario starts from the same snapshot; figures are medians over the
// repetitions. --environments N also generates N seeds per family and checks
// them (no interpenetration, at rest within 2 s). --generators N only checks
// the first N seeds of every family as generated (A walls stacked, B piles
// before their drop): clean and at rest within 2 s; exit status 1 if not.
// --families B1,B2 limits that check to the families listed.
//
//   bench_sim [--quick] [--json] [--repeat R] [--environments N] [--generators N]
//             [--families LIST]
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <string>
#include <vector>

#include "bench_cli.hpp"
#include "bench_families.hpp"
#include "plr/sim/generators.hpp"
#include "plr/sim/physics.hpp"

namespace {

using plr::sim::Box;
using plr::sim::EnvFamily;
using plr::sim::LinkGeometry;
using plr::sim::Simulation;
using plr::sim::SuctionPlate;
using plr::sim::World;
using Clock = std::chrono::steady_clock;

constexpr double kControl = 0.01;  // s between robot pose updates

double seconds_since(Clock::time_point t) {
  return std::chrono::duration<double>(Clock::now() - t).count();
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 == 1 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// A simple unloader: base, arm (one long link ending in the suction plate),
// nose with a belt. Poses in the trailer frame.
struct Robot {
  double base_x = 0.0;
  Eigen::Vector3d plate{0.0, 0.0, 1.0};  // plate centre; the plate faces +x
  bool nose_down = true;

  static constexpr double kNoseLength = 1.2;
  static constexpr double kNoseTop = 0.30;

  // Where a dropped box's bottom centre should be: over the middle of the belt.
  Eigen::Vector3d nose_drop() const {
    return {base_x + 0.5 + 0.5 * kNoseLength, 0.0, kNoseTop + 0.1};
  }

  std::vector<LinkGeometry> links() const {
    std::vector<LinkGeometry> l(3);
    // Base body, kept below the nose: its own conveyor takes over the boxes.
    l[0].size = {1.0, 1.2, 0.2};
    l[0].pose.translation() = Eigen::Vector3d(base_x, 0.0, 0.1);
    l[1].size = {kNoseLength, 1.4, 0.08};  // nose with its belt
    l[1].pose.translation() =
        Eigen::Vector3d(base_x + 0.5 + 0.5 * kNoseLength, 0.0, kNoseTop - 0.04);
    l[1].belt_speed = 0.6;
    // Arm: a beam from the base top to just behind the plate.
    const Eigen::Vector3d shoulder(base_x + 0.3, 0.0, 1.1);
    const Eigen::Vector3d wrist = plate - Eigen::Vector3d(0.12, 0.0, 0.0);
    const Eigen::Vector3d d = wrist - shoulder;
    l[2].size = {std::max(0.1, d.norm()), 0.12, 0.12};
    l[2].pose.linear() =
        Eigen::Quaterniond::FromTwoVectors(Eigen::Vector3d::UnitX(), d).toRotationMatrix();
    l[2].pose.translation() = shoulder + 0.5 * d;
    return l;
  }

  SuctionPlate suction() const {
    SuctionPlate p;
    // Cup face normal (+z) along +x; the long side (local x) horizontal, so
    // the cups cover one box of a column, not the one below as well.
    p.pose = Eigen::Translation3d(plate) * Eigen::AngleAxisd(0.5 * M_PI, Eigen::Vector3d::UnitY()) *
             Eigen::AngleAxisd(0.5 * M_PI, Eigen::Vector3d::UnitZ());
    return p;
  }
};

struct Run {
  double sim_time = 0.0, wall = 0.0, physics = 0.0;
  double dynamic_share = 0.0;  // steps that integrated some box
  double mean_awake = 0.0;     // awake boxes per dynamic step
  int unloaded = 0, picked = 0, dropped = 0;
};

class Driver {
 public:
  Driver(Simulation& sim, Robot& robot) : sim_(sim), robot_(robot) { apply(); }

  void apply() {
    sim_.set_robot_links(robot_.links());
    sim_.set_suction_plate(robot_.suction());
  }

  // Moves the plate (and base) along a straight line with a trapezoidal
  // speed profile.
  void move(const Eigen::Vector3d& plate_to, double base_to, double vmax = 0.5, double amax = 1.0) {
    const Eigen::Vector3d p0 = robot_.plate;
    const double b0 = robot_.base_x;
    const double dist = std::max((plate_to - p0).norm(), std::abs(base_to - b0));
    if (dist < 1e-9) return;
    const double ta = std::min(vmax / amax, std::sqrt(dist / amax));
    const double v = amax * ta;
    const double total = 2.0 * ta + (dist - v * ta) / v;
    for (double t = kControl; t < total + kControl; t += kControl) {
      const double tc = std::min(t, total);
      double s;
      if (tc < ta) {
        s = 0.5 * amax * tc * tc;
      } else if (tc > total - ta) {
        s = dist - 0.5 * amax * (total - tc) * (total - tc);
      } else {
        s = 0.5 * v * ta + v * (tc - ta);
      }
      const double f = std::clamp(s / dist, 0.0, 1.0);
      robot_.plate = p0 + f * (plate_to - p0);
      robot_.base_x = b0 + f * (base_to - b0);
      apply();
      sim_.step(kControl);
    }
  }

  void wait(double t) { sim_.step(t); }

 private:
  Simulation& sim_;
  Robot& robot_;
};

// The box to pick next: highest box of the wall face nearest the robot.
const Box* next_target(const World& w) {
  double face = 1e9;
  for (const Box& b : w.boxes) face = std::min(face, b.pose.translation().x() - 0.5 * b.size.x());
  const Box* best = nullptr;
  for (const Box& b : w.boxes) {
    if (b.pose.translation().x() - 0.5 * b.size.x() > face + 0.1) continue;
    if (best == nullptr || b.pose.translation().z() > best->pose.translation().z() + 0.01) {
      best = &b;
    }
  }
  return best;
}

// One Pick: base up to the wall, pre-grasp, approach, grip, pull out, drop on
// the nose, arm home.
bool pick(Simulation& sim, Robot& robot, Driver& drive) {
  const World w = sim.world();
  const Box* target = next_target(w);
  if (target == nullptr) return false;
  const Eigen::Vector3d c = target->pose.translation();
  const double face = c.x() - 0.5 * target->size.x();
  const Eigen::Vector3d grasp(face, c.y(), c.z());
  const double base_x = std::max(robot.base_x, face - 2.6);
  drive.move(Eigen::Vector3d(base_x + 0.9, 0.0, 1.2), base_x);        // base
  drive.move(grasp - Eigen::Vector3d(0.15, 0.0, 0.0), base_x);        // pre-grasp
  drive.move(grasp - Eigen::Vector3d(0.002, 0.0, 0.0), base_x, 0.1);  // approach
  const bool gripped = !sim.suction_on().empty();
  drive.move(grasp - Eigen::Vector3d(0.6, 0.0, 0.0), base_x, 0.3);  // retract
  drive.move(
      robot.nose_drop() + Eigen::Vector3d(-0.5 * target->size.x(), 0.0, 0.5 * target->size.z()),
      base_x);  // drop-off
  sim.suction_off();
  drive.wait(0.5);
  drive.move(Eigen::Vector3d(base_x + 0.9, 0.0, 1.2), base_x);  // home
  drive.wait(1.0);                                              // belt carries the box out
  return gripped;
}

Run measure(Simulation& sim, const std::function<void()>& act, int picks_before,
            std::size_t events_before) {
  const auto start = Clock::now();
  const double t0 = sim.time();
  const plr::sim::PhysicsStats s0 = sim.stats();
  act();
  Run r;
  r.wall = seconds_since(start);
  r.sim_time = sim.time() - t0;
  const plr::sim::PhysicsStats s1 = sim.stats();
  r.physics = s1.wall_seconds - s0.wall_seconds;
  const double steps = static_cast<double>(s1.steps - s0.steps);
  const double dyn = static_cast<double>(s1.dynamic_steps - s0.dynamic_steps);
  r.dynamic_share = steps > 0 ? dyn / steps : 0.0;
  r.mean_awake = dyn > 0 ? static_cast<double>(s1.body_steps - s0.body_steps) / dyn : 0.0;
  r.unloaded = static_cast<int>(sim.unloaded().size()) - picks_before;
  for (std::size_t i = events_before; i < sim.suction_events().size(); ++i) {
    const auto k = sim.suction_events()[i].kind;
    r.picked += k == plr::sim::SuctionEvent::Kind::kGripped;
    r.dropped += k == plr::sim::SuctionEvent::Kind::kDropped;
  }
  return r;
}

struct Row {
  std::string name;
  std::vector<Run> runs;
  int boxes = 0;
};

struct BytesRow {
  std::string name;
  int boxes = 0, awake = 0;
  std::size_t size = 0;
  double write_us = 0.0, read_us = 0.0, build_us = 0.0;  // medians
};

BytesRow measure_bytes(const std::string& name, const Simulation& sim, int reps) {
  BytesRow row{name, static_cast<int>(sim.world().boxes.size()), sim.stats().awake, 0, 0, 0, 0};
  const plr::sim::Snapshot snapshot = sim.snapshot();
  std::vector<double> write, read, build;
  for (int r = 0; r < reps; ++r) {
    auto t = Clock::now();
    const std::vector<std::uint8_t> bytes = snapshot.to_bytes();
    write.push_back(1e6 * seconds_since(t));
    t = Clock::now();
    const auto back = plr::sim::Snapshot::from_bytes(bytes.data(), bytes.size());
    read.push_back(1e6 * seconds_since(t));
    if (!back) {
      std::fprintf(stderr, "bench_sim: %s\n", back.error().message.c_str());
      std::exit(1);
    }
    t = Clock::now();
    const auto restored = Simulation::from_snapshot(back.value());
    build.push_back(1e6 * seconds_since(t));
    row.size = bytes.size();
  }
  row.write_us = median(write);
  row.read_us = median(read);
  row.build_us = median(build);
  return row;
}

void print_bytes(const std::vector<BytesRow>& rows) {
  std::printf("\n%-12s %6s %6s %10s %12s %12s %12s\n", "state", "boxes", "awake", "bytes",
              "write [us]", "read [us]", "build [us]");
  for (const BytesRow& r : rows) {
    std::printf("%-12s %6d %6d %10zu %12.0f %12.0f %12.0f\n", r.name.c_str(), r.boxes, r.awake,
                r.size, r.write_us, r.read_us, r.build_us);
  }
}

std::string bytes_json(const std::vector<BytesRow>& rows) {
  std::string json = ",\"state_bytes\":{";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    char buf[256];
    std::snprintf(buf, sizeof buf,
                  "%s\"%s\":{\"boxes\":%d,\"awake\":%d,\"bytes\":%zu,\"write_us\":%.1f,"
                  "\"read_us\":%.1f,\"build_us\":%.1f}",
                  i ? "," : "", rows[i].name.c_str(), rows[i].boxes, rows[i].awake, rows[i].size,
                  rows[i].write_us, rows[i].read_us, rows[i].build_us);
    json += buf;
  }
  return json + "}";
}

void print_table(const std::vector<Row>& rows) {
  std::printf("%-9s %6s %9s %9s %10s %8s %8s %7s %7s %8s %6s\n", "scenario", "boxes", "sim [s]",
              "wall [s]", "physics[s]", "RTF [x]", "dyn [%]", "awake", "gripped", "unloaded",
              "runs");
  for (const Row& row : rows) {
    std::vector<double> sim, wall, phys, rtf, dyn, awake, unl, grip;
    for (const Run& r : row.runs) {
      grip.push_back(r.picked);
      sim.push_back(r.sim_time);
      wall.push_back(r.wall);
      phys.push_back(r.physics);
      rtf.push_back(r.sim_time / r.wall);
      dyn.push_back(100.0 * r.dynamic_share);
      awake.push_back(r.mean_awake);
      unl.push_back(r.unloaded);
    }
    std::printf("%-9s %6d %9.1f %9.2f %10.2f %8.1f %8.1f %7.1f %7.0f %8.0f %6zu\n",
                row.name.c_str(), row.boxes, median(sim), median(wall), median(phys), median(rtf),
                median(dyn), median(awake), median(grip), median(unl), row.runs.size());
  }
}

void print_json(const std::vector<Row>& rows, const std::string& extra_json) {
  std::printf("{\"scenarios\":{");
  for (std::size_t i = 0; i < rows.size(); ++i) {
    std::vector<double> sim, wall, phys, rtf, unl;
    for (const Run& r : rows[i].runs) {
      sim.push_back(r.sim_time);
      wall.push_back(r.wall);
      phys.push_back(r.physics);
      rtf.push_back(r.sim_time / r.wall);
      unl.push_back(r.unloaded);
    }
    std::printf(
        "%s\"%s\":{\"boxes\":%d,\"sim_s\":%.3f,\"wall_s\":%.3f,\"physics_s\":%.3f,"
        "\"real_time_factor\":%.2f,\"unloaded\":%.0f,\"runs\":%zu}",
        i ? "," : "", rows[i].name.c_str(), rows[i].boxes, median(sim), median(wall), median(phys),
        median(rtf), median(unl), rows[i].runs.size());
  }
  std::printf("}%s}\n", extra_json.c_str());
}

// Generates `seeds` worlds per family and checks each (piles are dropped and
// settled first).
std::string check_environments(int seeds, bool table) {
  std::string json = ",\"environments\":{";
  if (table) {
    std::printf("\n%-6s %6s %8s %10s %12s %12s\n", "family", "seeds", "boxes", "clean", "settle<2s",
                "wall [s]");
  }
  bool first = true;
  for (EnvFamily f : {EnvFamily::kA1, EnvFamily::kA2, EnvFamily::kB1, EnvFamily::kB2}) {
    int clean = 0, settled = 0;
    double boxes = 0.0;
    const auto start = Clock::now();
    for (int seed = 0; seed < seeds; ++seed) {
      const World generated = plr::sim::generate_world(f, static_cast<std::uint64_t>(seed));
      const bool wall = f == EnvFamily::kA1 || f == EnvFamily::kA2;
      const World w =
          wall ? generated : plr::sim::make_environment(f, static_cast<std::uint64_t>(seed));
      boxes += static_cast<double>(w.boxes.size());
      Simulation sim(w);
      const bool rest = sim.settle(2.0) >= 0.0;
      const bool ok = plr::sim::find_interpenetrations(generated, 1e-6).empty() &&
                      plr::sim::find_interpenetrations(sim.world(), 0.005).empty();
      clean += ok;
      settled += rest;
    }
    const double wall_s = seconds_since(start);
    if (table) {
      std::printf("%-6s %6d %8.1f %10d %12d %12.1f\n", std::string(to_string(f)).c_str(), seeds,
                  boxes / seeds, clean, settled, wall_s);
    }
    json += std::string(first ? "" : ",") + "\"" + std::string(to_string(f)) +
            "\":{\"seeds\":" + std::to_string(seeds) + ",\"clean\":" + std::to_string(clean) +
            ",\"settled\":" + std::to_string(settled) + "}";
    first = false;
  }
  return json + "}";
}

// The generators as generated (piles not yet dropped): every world free of
// interpenetration, then simulated until at rest, at most 2 s; a world at
// rest must also stay clean (nothing sank).
int check_generators(int seeds, const std::vector<EnvFamily>& families) {
  std::printf("%-6s %6s %8s %8s %10s %12s %12s %10s\n", "family", "seeds", "boxes", "clean",
              "settled", "rest med [s]", "rest max [s]", "wall [s]");
  int failures = 0;
  for (const EnvFamily f : families) {
    int clean = 0, settled = 0;
    double boxes = 0.0;
    std::vector<double> rest;
    std::string failed;
    const auto start = Clock::now();
    for (int seed = 0; seed < seeds; ++seed) {
      const World w = plr::sim::generate_world(f, static_cast<std::uint64_t>(seed));
      boxes += static_cast<double>(w.boxes.size());
      Simulation sim(w);
      const double t = sim.settle(2.0);
      const bool ok = plr::sim::find_interpenetrations(w, 1e-6).empty() &&
                      plr::sim::find_interpenetrations(sim.world(), 0.005).empty();
      clean += ok;
      settled += t >= 0.0;
      if (t >= 0.0) rest.push_back(t);
      if (!ok || t < 0.0) failed += " " + std::to_string(seed);
    }
    failures += seeds - std::min(clean, settled);
    std::printf("%-6s %6d %8.1f %8d %10d %12.2f %12.2f %10.1f%s%s\n",
                std::string(to_string(f)).c_str(), seeds, boxes / seeds, clean, settled,
                rest.empty() ? -1.0 : median(rest),
                rest.empty() ? -1.0 : *std::max_element(rest.begin(), rest.end()),
                seconds_since(start), failed.empty() ? "" : "  failed seeds:", failed.c_str());
    std::fflush(stdout);
  }
  return failures == 0 ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  bool quick = false, json = false;
  int repeat = 3, environments = 0, generators = 0;
  std::vector<EnvFamily> families{EnvFamily::kA1, EnvFamily::kA2, EnvFamily::kB1, EnvFamily::kB2};
  CLI::App app{
      "Real-time factor of the box simulation (pick, sweep, a sequence of picks) and "
      "the size and time of its state as bytes"};
  plr::bench::add_quick_flag(app, quick, "1 repetition, 3 picks in the sequence");
  plr::bench::add_json_flag(app, json);
  app.add_option("--repeat", repeat, "Repetitions of each scenario (figures are medians)")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  app.add_option("--environments", environments,
                 "Also generate N seeds per family and check them (no interpenetration, at rest "
                 "within 2 s)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  app.add_option("--generators", generators,
                 "Only check the first N seeds of every family as generated; exit 1 if one fails")
      ->check(CLI::PositiveNumber);
  plr::bench::add_families_option(app, families, "Families the checks run (default A1,A2,B1,B2)");
  plr::bench::parse_or_exit(app, argc, argv);
  if (generators > 0) return check_generators(generators, families);
  if (quick) repeat = 1;
  const int sequence_actions = quick ? 3 : 10;

  std::vector<Row> rows;
  std::vector<BytesRow> bytes_rows;
  const int bytes_reps = quick ? 5 : 20;
  {
    // Settled A1 wall, then pick / sequence from the same snapshot each run.
    Simulation sim(plr::sim::make_environment(EnvFamily::kA1, 1));
    Robot robot;
    robot.base_x = 9.0;
    robot.plate = {9.9, 0.0, 1.2};
    Driver drive(sim, robot);
    drive.wait(0.1);
    const plr::sim::Snapshot start = sim.snapshot();
    const Robot robot0 = robot;
    bytes_rows.push_back(measure_bytes("A1 wall", sim, bytes_reps));
    Row pick_row{"pick", {}, static_cast<int>(sim.world().boxes.size())};
    Row seq_row{"sequence", {}, pick_row.boxes};
    for (int r = 0; r < repeat; ++r) {
      sim.restore(start);
      robot = robot0;
      const int before = static_cast<int>(sim.unloaded().size());
      const std::size_t events = sim.suction_events().size();
      pick_row.runs.push_back(measure(
          sim, [&] { pick(sim, robot, drive); }, before, events));
    }
    for (int r = 0; r < repeat; ++r) {
      sim.restore(start);
      robot = robot0;
      const int before = static_cast<int>(sim.unloaded().size());
      const std::size_t events = sim.suction_events().size();
      seq_row.runs.push_back(measure(
          sim,
          [&] {
            for (int a = 0; a < sequence_actions; ++a) pick(sim, robot, drive);
          },
          before, events));
    }
    rows.push_back(pick_row);
    rows.push_back(seq_row);
  }
  {
    Simulation sim(plr::sim::make_environment(EnvFamily::kB1, 1));
    double front = 1e9;
    for (const Box& b : sim.world().boxes) front = std::min(front, b.pose.translation().x());
    Robot robot;
    robot.base_x = front - 2.6;
    robot.plate = {robot.base_x + 0.6, 0.0, 1.4};
    robot.nose_down = true;
    Driver drive(sim, robot);
    drive.wait(0.1);
    const plr::sim::Snapshot start = sim.snapshot();
    const Robot robot0 = robot;
    Row row{"sweep", {}, static_cast<int>(sim.world().boxes.size())};
    for (int r = 0; r < repeat; ++r) {
      sim.restore(start);
      robot = robot0;
      const int before = static_cast<int>(sim.unloaded().size());
      row.runs.push_back(measure(
          sim,
          [&] {
            drive.move(robot.plate + Eigen::Vector3d(1.4, 0, 0), robot.base_x + 1.4, 0.3);
            drive.wait(1.0);
            drive.move(robot.plate - Eigen::Vector3d(1.4, 0, 0), robot.base_x - 1.4, 0.3);
            drive.wait(1.0);
          },
          before, sim.suction_events().size()));
    }
    rows.push_back(row);
    sim.restore(start);
    robot = robot0;
    drive.move(robot.plate + Eigen::Vector3d(0.7, 0, 0), robot.base_x + 0.7, 0.3);
    bytes_rows.push_back(measure_bytes("B1 sweeping", sim, bytes_reps));
  }
  std::string extra_json = bytes_json(bytes_rows);
  if (!json) {
    print_table(rows);
    print_bytes(bytes_rows);
  }
  if (environments > 0) extra_json += check_environments(environments, !json);
  if (json) print_json(rows, extra_json);
  return 0;
}
