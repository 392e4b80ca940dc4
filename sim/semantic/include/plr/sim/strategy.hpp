// Strategies: decision trees over the 12 abstract actions, branching on the
// 18 semantic observations (the enums of sdk/schemas/strategy.fbs).
//
// A strategy starts at nodes[root]; after a node's action the executor
// observes the world and follows the edge labelled with that observation. A
// node without a matching edge ends the strategy.
//
// Files: the FlatBuffers binary of plr.msg.Strategy with file identifier
// "PLRS" (extension .plrs), or the same tree in YAML (.yaml / .yml):
//
//   format: plr-strategy
//   version: 1
//   name: example
//   root: 0
//   nodes:
//     - {action: Pick(high, left), children: {wall/high/left: 1}}
//     - {action: Sweep(low)}
#pragma once

#include <plr/msg/strategy_generated.h>
#include <plr/expected.hpp>

#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace plr::sim {

using Action = plr::msg::Action;
using Observation = plr::msg::Observation;

enum class Height { kLow, kMid, kHigh };
enum class Side { kLeft, kCenter, kRight };
enum class ActionKind { kPick, kSweep };
enum class Structure { kPile, kWall };

inline constexpr int kNumActions = 12;
inline constexpr int kNumObservations = 18;

const char* to_string(Height h);
const char* to_string(Side s);
const char* to_string(Structure s);

Action make_pick(Height height, Side side);
Action make_sweep(Height height);
ActionKind kind(Action a);
Height height(Action a);
// Sweeps have no side; kCenter for them.
Side side(Action a);
// "Pick(high, left)", "Sweep(low)".
std::string to_string(Action a);
std::optional<Action> parse_action(std::string_view text);

Observation make_observation(Structure structure, Height height, Side side);
Structure structure(Observation o);
Height height(Observation o);
Side side(Observation o);
// "wall/high/left".
std::string to_string(Observation o);
std::optional<Observation> parse_observation(std::string_view text);

struct StrategyNode {
  Action action = Action::PickLowLeft;
  std::vector<std::pair<Observation, std::uint32_t>> children;  // observation -> node index
};

struct Strategy {
  std::string name;
  std::uint32_t root = 0;
  std::vector<StrategyNode> nodes;

  // The node reached from `node` on `observation`, if the tree plans for it.
  std::optional<std::uint32_t> next(std::uint32_t node, Observation observation) const;
  std::size_t depth() const;
};

// A strategy of one action (what the hardcoded strategy hands out).
Strategy single_action(Action action, std::string name);

// Whether the strategy is a well-formed tree: nodes exist, the root and
// every child index are in range, enums are valid, no node has two edges for
// one observation, and every node is reached from the root exactly once. The
// error is one line saying what is wrong.
plr::Status validate(const Strategy& strategy);

// FlatBuffers conversion (plr.msg.Strategy).
flatbuffers::Offset<plr::msg::Strategy> build(flatbuffers::FlatBufferBuilder& fbb,
                                              const Strategy& strategy);
// The error is "<origin>: <cause>" if the tree is not valid.
plr::Expected<Strategy> from_message(const plr::msg::Strategy& message, const std::string& origin);

// The binary file image (identifier "PLRS").
std::vector<std::uint8_t> serialize(const Strategy& strategy);
// Verifies untrusted bytes before reading them.
plr::Expected<Strategy> deserialize(const std::uint8_t* data, std::size_t size,
                                    const std::string& origin);

std::string format_yaml(const Strategy& strategy);
// Read with plr/yaml_reader.hpp: unknown keys are errors, child and root
// indices must name a node. The error is the first problem as one line,
// "<origin>:line:col: key: cause"; what only the whole tree shows
// (validate()) is located at the list of nodes.
plr::Expected<Strategy> parse_yaml(const std::string& text, const std::string& origin);

// By extension: .yaml/.yml as YAML, anything else as the binary form. Writes
// are atomic (plr::write_file_atomically); an error is one line
// "<file>[:line:col]: <cause>".
plr::Status save_strategy(const Strategy& strategy, const std::filesystem::path& file);
plr::Expected<Strategy> load_strategy(const std::filesystem::path& file);

}  // namespace plr::sim
