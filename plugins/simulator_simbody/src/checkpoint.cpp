#include "checkpoint.hpp"

#include <plr/atomic_file.hpp>
#include <plr/sim/world_io.hpp>

#include <nlohmann/json.hpp>

#include <fstream>
#include <system_error>

namespace plr::simulator {

namespace fs = std::filesystem;

namespace {

// Every file under the folder: a temp file left behind would count too.
std::uint64_t folder_bytes(const fs::path& dir) {
  std::uint64_t bytes = 0;
  std::error_code ec;
  for (auto it = fs::recursive_directory_iterator(dir, ec); !ec && it != fs::end(it);
       it.increment(ec)) {
    std::error_code size_ec;
    if (it->is_regular_file(size_ec)) bytes += it->file_size(size_ec);
  }
  return bytes;
}

}  // namespace

Expected<std::uint64_t> save_checkpoint(const fs::path& dir, const Checkpoint& c) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec) return make_error(PLR_ERR_INTERNAL, dir.string() + ": " + ec.message());
  if (Status saved = sim::save_world(c.world, dir / "world.yaml"); !saved) return saved.error();
  nlohmann::json j;
  j["q"] = std::vector<double>(c.robot.q.data(), c.robot.q.data() + c.robot.q.size());
  j["held"] = c.robot.held;
  j["sim_time"] = c.sim_time;
  j["boxes_total"] = c.boxes_total;
  j["boxes_unloaded"] = c.boxes_unloaded;
  // Written last: its presence marks a complete checkpoint.
  if (Status saved = write_file_atomically((dir / "state.json").string(), j.dump()); !saved)
    return saved.error();
  return folder_bytes(dir);
}

Expected<std::optional<Checkpoint>> load_checkpoint(const fs::path& dir) {
  const fs::path state = dir / "state.json";
  std::error_code ec;
  const bool there = fs::exists(state, ec);
  if (ec) return make_error(PLR_ERR_INTERNAL, state.string() + ": " + ec.message());
  if (!there) return std::nullopt;
  auto world = sim::load_world(dir / "world.yaml");
  if (!world) return world.error();
  Checkpoint c;
  c.world = std::move(*world);
  std::ifstream in(state);
  const auto j = nlohmann::json::parse(in, nullptr, false);
  const Error damaged = make_error(PLR_ERR_INVALID, state.string() + ": damaged checkpoint");
  if (j.is_discarded() || !j.contains("q") || j["q"].size() != sim::kNumJoints) return damaged;
  // nlohmann::json throws on a value of the wrong type: that file is damaged too.
  try {
    for (int i = 0; i < sim::kNumJoints; ++i) c.robot.q[i] = j["q"][i].get<double>();
    c.robot.held = j.value("held", std::vector<std::uint32_t>{});
    c.sim_time = j.value("sim_time", 0.0);
    c.boxes_total = j.value("boxes_total", 0u);
    c.boxes_unloaded = j.value("boxes_unloaded", 0u);
  } catch (const nlohmann::json::exception&) {
    return damaged;
  }
  return std::optional<Checkpoint>(std::move(c));
}

}  // namespace plr::simulator
