#include "checkpoint.hpp"

#include <plr/atomic_file.hpp>
#include <plr/sim/world_io.hpp>

#include <nlohmann/json.hpp>

#include <fstream>
#include <stdexcept>

namespace plr::simulator {

namespace fs = std::filesystem;

void save_checkpoint(const fs::path& dir, const Checkpoint& c) {
  fs::create_directories(dir);
  sim::save_world(c.world, dir / "world.yaml");
  nlohmann::json j;
  j["q"] = std::vector<double>(c.robot.q.data(), c.robot.q.data() + c.robot.q.size());
  j["held"] = c.robot.held;
  j["sim_time"] = c.sim_time;
  j["boxes_total"] = c.boxes_total;
  j["boxes_unloaded"] = c.boxes_unloaded;
  // Written last: its presence marks a complete checkpoint.
  if (const Status written = write_file_atomically((dir / "state.json").string(), j.dump());
      !written)
    throw std::runtime_error(written.error().message);
}

std::optional<Checkpoint> load_checkpoint(const fs::path& dir) {
  if (!fs::exists(dir / "state.json")) return std::nullopt;
  Checkpoint c;
  c.world = sim::load_world(dir / "world.yaml");
  std::ifstream in(dir / "state.json");
  const auto j = nlohmann::json::parse(in, nullptr, false);
  if (j.is_discarded() || !j.contains("q") || j["q"].size() != sim::kNumJoints)
    throw std::runtime_error((dir / "state.json").string() + ": damaged checkpoint");
  for (int i = 0; i < sim::kNumJoints; ++i) c.robot.q[i] = j["q"][i].get<double>();
  c.robot.held = j.value("held", std::vector<std::uint32_t>{});
  c.sim_time = j.value("sim_time", 0.0);
  c.boxes_total = j.value("boxes_total", 0u);
  c.boxes_unloaded = j.value("boxes_unloaded", 0u);
  return c;
}

}  // namespace plr::simulator
